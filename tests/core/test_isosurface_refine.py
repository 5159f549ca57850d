"""Thick slices refined by cubic convolution before the isosurface is cut (core/isosurface.py).

Marching cubes interpolates linearly between slices, so a surface cut across thick slices kinks
at every slice plane (terraces). The refinement is checked on fields whose surfaces are known:
a quadratic in z (cubic convolution reproduces it exactly, linear interpolation does not), a
sharp-walled ball on 4 mm slices of 0.5 mm pixels (its slice creases), and a sheared grid.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import pyvista as pv

from sciviz_gbuf.core.isosurface import REFINE_POINTS, isosurface, refine_factors
from sciviz_gbuf.errors import InputError

CENTRE = np.array([0.3, -0.2, 0.5])
RADIUS = 12.0


def _factors(surf: pv.PolyData) -> list[int]:
    return json.loads(surf.field_data["isosurface"][0])["refine"]


def _image(dz: float, dx: float = 0.5) -> pv.ImageData:
    n, m = round(32 / dx) + 1, round(32 / dz) + 1
    return pv.ImageData(dimensions=(n, n, m), spacing=(dx, dx, dz), origin=(-16, -16, -16))


def _ball(grid: pv.DataSet) -> pv.DataSet:
    """Bone (300 HU) inside RADIUS of CENTRE, the wall 1 mm thick: a step at 4 mm slices."""
    r = np.linalg.norm(np.asarray(grid.points) - CENTRE, axis=1)
    grid.point_data["HU"] = (300.0 + 700.0 * np.tanh((RADIUS - r) / 1.0)).astype(np.float32)
    return grid


def test_refine_factors_follow_the_thick_axis_and_the_budget():
    # The shared Philips phantom: 0.451 mm pixels, 5 mm slices -> 6 samples per slice step.
    assert refine_factors((0.451, 0.451, 5.0), (512, 512, 28)) == (1, 1, 6)
    # Up to twice the finest spacing nothing is refined (the frog's 1 x 1 x 1.5 mm voxels).
    assert refine_factors((1.0, 1.0, 1.5), (500, 470, 136)) == (1, 1, 1)
    assert refine_factors((1.0, 1.0, 2.0), (10, 10, 10)) == (1, 1, 1)
    assert refine_factors((3.0, 1.0, 1.0), (10, 10, 10)) == (2, 1, 1)
    # The budget lowers the factor, and an axis that cannot be doubled is left alone.
    full = 512 * 512 * (27 * 6 + 1) * 4
    assert full <= REFINE_POINTS
    assert refine_factors((0.451, 0.451, 5.0), (512, 512, 28), budget=full * 3 // 5) == (1, 1, 3)
    assert refine_factors((0.451, 0.451, 5.0), (512, 512, 28), budget=full // 8) == (1, 1, 1)


def test_cubic_refinement_reproduces_a_quadratic_between_slices():
    # HU = 1000 - 20 z^2 cut at 300: planes z = +-sqrt(35). Linear interpolation between the
    # 4 mm slices puts them 0.33 mm too close; Keys' cubic convolution is exact on quadratics.
    im = _image(4.0, dx=1.0)
    z = np.asarray(im.points)[:, 2]
    im.point_data["HU"] = (1000.0 - 20.0 * z**2).astype(np.float32)
    exact = np.sqrt(35.0)
    plain = isosurface(im, smooth=0, refine=False)
    fine = isosurface(im, smooth=0)
    assert _factors(plain) == [1, 1, 1] and _factors(fine) == [1, 1, 2]
    err_plain = np.abs(np.abs(plain.points[:, 2]) - exact).max()
    err_fine = np.abs(np.abs(fine.points[:, 2]) - exact).max()
    assert err_plain > 0.2
    assert err_fine < 0.1 * err_plain


def test_thick_slices_lose_their_terraces():
    vol = _ball(_image(4.0))

    def creases(surf: pv.PolyData) -> int:
        edges = surf.extract_feature_edges(
            20.0, boundary_edges=False, non_manifold_edges=False, manifold_edges=False
        )
        return edges.n_cells

    plain, fine = isosurface(vol, smooth=0, refine=False), isosurface(vol, smooth=0)
    assert _factors(fine) == [1, 1, 4]
    # The slice kinks are the creases of the raw surface; refined, few are left.
    assert creases(plain) > 100
    assert creases(fine) < 0.25 * creases(plain)
    for surf in (plain, fine):
        r = np.linalg.norm(surf.points - CENTRE, axis=1)
        assert np.abs(r - RADIUS).max() < 1.0  # the thickness of the wall
    # Smoothed (the default), the refined surface still has fewer creases.
    assert creases(isosurface(vol)) < creases(isosurface(vol, refine=False))


def test_a_sheared_grid_is_refined_with_its_points():
    # A gantry-tilt-like series: each slice shifted in y in proportion to its z.
    grid = _image(4.0, dx=1.0).cast_to_structured_grid()
    pts = np.asarray(grid.points).copy()
    pts[:, 1] += 0.3 * pts[:, 2]
    grid.points = pts
    grid = _ball(grid)
    surf = isosurface(grid, smooth=0)
    assert _factors(surf) == [1, 1, 3]  # the slice step is 4.2 mm along the shear
    r = np.linalg.norm(surf.points - CENTRE, axis=1)
    assert np.abs(r - RADIUS).max() < 1.0
    assert json.loads(surf.field_data["isosurface"][0])["method"] == "contour"


def test_refine_is_checked():
    vol = _ball(_image(4.0, dx=2.0))
    for bad in ("yes", 1, None):
        with pytest.raises(InputError, match="refine"):
            isosurface(vol, refine=bad)
