"""Image-space edges against an object-space ground truth (issue 3 acceptance).

The truth (tests/helpers/edge_truth.py) takes silhouette, border and crease edges from the mesh
itself and keeps the visible parts by ray casting against the triangles: it shares nothing with
the image-space filters. Profile + crease ink must match it with precision and recall >= 0.9 at a
tolerance of 1.5 px, on the machine nut, the CAD part of ../shared/data and PyVista's airplane
(open surfaces: border edges), at 512^2 and 1024^2 from several views.
"""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv
from pyvista import examples

import sciviz_gbuf as sg
from sciviz_gbuf.datasets import load_nut
from sciviz_gbuf.filters import crease_edges, profile_edges
from tests.helpers.edge_truth import precision_recall, visible_edge_truth

VIEWS = [(35.0, 30.0), (-120.0, 55.0), (200.0, -25.0)]  # (azimuth, elevation) in degrees


def view(mesh, azimuth: float, elevation: float, view_angle: float = 30.0):
    """(position, focal point, view up) looking at the mesh's bounding sphere, filling ~80 %."""
    b = np.asarray(mesh.bounds, dtype=np.float64).reshape(3, 2)
    centre = b.mean(axis=1)
    radius = 0.5 * np.linalg.norm(b[:, 1] - b[:, 0])
    a, e = np.radians(azimuth), np.radians(elevation)
    direction = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    dist = radius / np.sin(np.radians(view_angle / 2)) * 1.05
    up = (0.0, 0.0, 1.0) if abs(elevation) < 80 else (0.0, 1.0, 0.0)
    return tuple(centre + dist * direction), tuple(centre), up


def _stl(shared):
    return pv.read(shared / "meshes" / "vtkdata_42400-IDGH.stl")


MESHES = {
    "nut": lambda shared: load_nut(),
    "cad_stl": _stl,
    "airplane": lambda shared: examples.load_airplane(),
}


def detect(gb, **kw) -> np.ndarray:
    return (profile_edges(gb, **kw.get("profile", {})) >= 0.5) | (
        crease_edges(gb, **kw.get("crease", {})) >= 0.5
    )


def _score(mesh, gb, **kw):
    truth = visible_edge_truth(mesh, gb, feature_angle=30.0)["all"]
    assert truth.sum() > 200  # the view shows a fair amount of lines
    return precision_recall(detect(gb, **kw), truth, tol_px=1.5)


@pytest.fixture(scope="module")
def meshes(shared_data):
    return {name: load(shared_data) for name, load in MESHES.items()}


@pytest.mark.parametrize("size", [512, 1024])
@pytest.mark.parametrize("azel", VIEWS, ids=[f"az{a:g}_el{e:g}" for a, e in VIEWS])
@pytest.mark.parametrize("name", list(MESHES))
def test_profile_and_crease_edges_match_object_space_truth(meshes, name, azel, size):
    mesh = meshes[name]
    gb = sg.capture(mesh, window_size=(size, size), camera=view(mesh, *azel))
    precision, recall = _score(mesh, gb)
    assert precision >= 0.9 and recall >= 0.9, (precision, recall)


def test_parallel_projection_matches_truth_too(meshes):
    mesh = meshes["cad_stl"]
    gb = sg.capture(
        mesh, window_size=(512, 512), camera=view(mesh, 60, 35), parallel_projection=True
    )
    precision, recall = _score(mesh, gb)
    assert precision >= 0.9 and recall >= 0.9, (precision, recall)


@pytest.mark.parametrize(
    ("kw", "which"),
    [
        ({"crease": {"crease_angle": 3.0}}, "precision"),  # facets of curved parts flood in
        ({"crease": {"crease_angle": 100.0}}, "recall"),  # real creases are lost
    ],
)
def test_a_wrong_threshold_fails_the_same_check(meshes, kw, which):
    mesh = meshes["cad_stl"]
    gb = sg.capture(mesh, window_size=(512, 512), camera=view(mesh, *VIEWS[0]))
    precision, recall = _score(mesh, gb, **kw)
    value = precision if which == "precision" else recall
    assert value < 0.9, (precision, recall)
