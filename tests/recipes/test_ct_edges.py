"""Edges of the CT bone surface against object-space truth (issue item 3: "black speckle along
the slice terraces of enhanced CT bone surfaces").

The shared Philips phantom has 5 mm slices of 0.45 mm pixels; cut as it is, its skull is a
terrace at every slice, full of short creases that neither the truth nor the drawing should
show. :func:`ct_surface` refines the slices and smooths the surface first; its profile + crease
ink must then match tests/helpers/edge_truth.py at 1.5 px from three views, without specks.
"""

from __future__ import annotations

import pytest

from sciviz_gbuf.recipes.medical import ct_surface
from tests.filters.test_edges_organic import VIEWS, assert_edges_match_truth


@pytest.fixture(scope="module")
def phantom(shared_data):
    return ct_surface(shared_data / "ct" / "dcm_qa_ct_Philips_phantom_5mm", iso="bone")


@pytest.mark.parametrize("azel", VIEWS, ids=[f"az{a:g}_el{e:g}" for a, e in VIEWS])
def test_phantom_bone_edges_match_truth_without_specks(phantom, azel):
    assert_edges_match_truth(phantom, phantom, azel, min_truth=1000)
