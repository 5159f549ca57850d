"""Clean edges on organic and scanned surfaces (issue: "Clean edges", item 3).

Profile + crease ink against the object-space truth of tests/helpers/edge_truth.py, at
320x240 from three views each. Scanned surfaces are made by adding Gaussian noise (well below
a pixel) to a smooth tessellation, decimated ones by quadric decimation of a dense one: their
truth is the lines of the smooth shape they stand for (the facets' own folds and the noise's
creases are what the picture must not show). CAD meshes are their own truth.
"""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv
from scipy import ndimage

import sciviz_gbuf as sg
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters import crease_edges, profile_edges
from tests.filters.test_edges_acceptance import view
from tests.helpers.edge_truth import precision_recall, visible_edge_truth

SIZE = (320, 240)
VIEWS = [(35.0, 30.0), (-120.0, 55.0), (200.0, -25.0)]


def _noisy(mesh: pv.PolyData, sigma: float, seed: int) -> pv.PolyData:
    out = mesh.copy()
    out.points = out.points + np.random.default_rng(seed).normal(0.0, sigma, out.points.shape)
    out.point_data.clear()  # a scan's normals come from its own triangles
    return out


def _organic():
    sphere = pv.Sphere(radius=1.0, theta_resolution=80, phi_resolution=80)
    torus = pv.ParametricTorus()
    decimated = torus.triangulate().decimate(0.9)
    decimated.point_data.clear()
    return {
        "noisy_sphere": (_noisy(sphere, 0.004, 0), sphere),
        "noisy_torus": (_noisy(torus, 0.004, 1), torus),
        "decimated_torus": (decimated, torus),
    }


def _cad(shared):
    stl = pv.read(shared / "meshes" / "vtkdata_42400-IDGH.stl")
    cube = pv.Cube().triangulate()
    cylinder = pv.Cylinder(resolution=60).triangulate()
    return {"cube": (cube, cube), "cylinder": (cylinder, cylinder), "cad_stl": (stl, stl)}


def specks_per_1000(ink: np.ndarray, most: int = 4) -> float:
    labels, n = ndimage.label(ink, structure=np.ones((3, 3), dtype=bool))
    sizes = np.bincount(labels.ravel(), minlength=n + 1)[1:]
    return 1000.0 * int((sizes <= most).sum()) / max(1, int(ink.sum()))


def _lines(gb, **kw) -> np.ndarray:
    return (profile_edges(gb, **kw) >= 0.5) | (crease_edges(gb, **kw) >= 0.5)


def assert_edges_match_truth(mesh, shape, azel, min_truth: int) -> None:
    """Profile + crease ink of ``mesh`` seen from ``azel`` (framed on ``shape``) against the
    object-space truth of ``shape``: precision and recall >= 0.95 at 1.5 px, <= 2 specks per
    1000 ink px (the issue's acceptance); the truth has more than ``min_truth`` pixels."""
    gb = sg.capture(mesh, window_size=SIZE, camera=view(shape, *azel))
    truth = visible_edge_truth(shape, gb, feature_angle=30.0)["all"]
    assert truth.sum() > min_truth
    ink = _lines(gb)
    precision, recall = precision_recall(ink, truth, tol_px=1.5)
    assert precision >= 0.95 and recall >= 0.95, (precision, recall)
    assert specks_per_1000(ink) <= 2.0


@pytest.fixture(scope="module")
def scenes(shared_data):
    return _organic() | _cad(shared_data)


CASES = ["noisy_sphere", "noisy_torus", "decimated_torus", "cube", "cylinder", "cad_stl"]


@pytest.mark.parametrize("azel", VIEWS, ids=[f"az{a:g}_el{e:g}" for a, e in VIEWS])
@pytest.mark.parametrize("name", CASES)
def test_edges_match_truth_without_specks(scenes, name, azel):
    mesh, shape = scenes[name]
    assert_edges_match_truth(mesh, shape, azel, min_truth=200)


def test_without_the_cleaning_a_scan_is_speckled(scenes):
    # The same check fails on the raw lines: the cleaning is what passes it.
    mesh, shape = scenes["noisy_sphere"]
    gb = sg.capture(mesh, window_size=SIZE, camera=view(shape, *VIEWS[0]))
    raw = _lines(gb, min_length=0.0)
    clean = _lines(gb)
    assert specks_per_1000(raw) > 2.0 >= specks_per_1000(clean)
    assert clean.sum() < raw.sum()


def test_cube_corner_and_a_small_far_object_survive():
    # A cube seen corner-on (its three short edges meet there) and a cube a few pixels
    # across: joined edges and whole small outlines are never specks.
    big = pv.Cube(center=(0, 0, 0)).triangulate()
    small = pv.Cube(center=(0.0, 0.0, 1.2), x_length=0.03, y_length=0.03, z_length=0.03)
    scene = [big, small.triangulate()]
    gb = sg.capture(scene, window_size=SIZE, camera=((3.0, 2.5, 2.2), (0, 0, 0.3), (0, 0, 1)))
    truth = visible_edge_truth(scene, gb, feature_angle=30.0)["all"]
    ink = _lines(gb)
    precision, recall = precision_recall(ink, truth, tol_px=1.5)
    assert precision >= 0.97 and recall >= 0.97, (precision, recall)
    tiny = visible_edge_truth(scene[1], gb, feature_angle=30.0)["all"]
    assert 0 < tiny.sum() <= 40  # the far cube is a few pixels across
    near_tiny = ndimage.binary_dilation(tiny, iterations=2)
    assert ink[near_tiny].sum() >= 0.5 * tiny.sum()


def test_min_length_is_checked(scenes):
    mesh, shape = scenes["cube"]
    gb = sg.capture(mesh, window_size=(64, 48), camera=view(shape, *VIEWS[0]))
    for bad in (-1.0, float("nan"), 65.0, "5"):
        with pytest.raises(InputError, match="min_length"):
            profile_edges(gb, min_length=bad)
        with pytest.raises(InputError, match="min_length"):
            crease_edges(gb, min_length=bad)
