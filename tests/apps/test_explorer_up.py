"""The explorer's up axis: a y-up model stands upright in the first view and the orbit camera
turns around its up axis (``--up`` / ``Explorer(up=...)``, default by the file's convention)."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv

from sciviz_gbuf.apps.explorer import Explorer
from sciviz_gbuf.cli import build_parser
from sciviz_gbuf.errors import InputError

SIZE = (160, 120)


def cone_y(tmp_path, suffix: str = ".ply"):
    """A cone pointing +y (a y-up model), standing on y = 0, written as ``suffix``."""
    cone = pv.Cone(center=(0, 1, 0), direction=(0, 1, 0), height=2.0, radius=0.5, resolution=40)
    path = tmp_path / f"cone{suffix}"
    cone.triangulate().save(path)
    return path


def box(mask: np.ndarray) -> tuple[int, int]:
    """Width and height in pixels of the mask's bounding box."""
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    return int(cols[-1] - cols[0] + 1), int(rows[-1] - rows[0] + 1)


def iou(a: np.ndarray, b: np.ndarray) -> float:
    return float((a & b).sum() / (a | b).sum())


@pytest.mark.parametrize("suffix", [".ply", ".obj"])
def test_a_y_up_file_stands_upright_and_orbits_around_y(tmp_path, suffix):
    e = Explorer.from_file(cone_y(tmp_path, suffix), window_size=SIZE)
    assert e.up == "y"
    first = e.gbuffer.mask.copy()
    bw, bh = box(first)
    assert bh > 1.6 * bw  # the cone's axis vertical: tall and narrow
    top = np.flatnonzero(first.any(axis=1))[0]
    bottom = np.flatnonzero(first.any(axis=1))[-1]
    assert first[top].sum() < 0.3 * first[bottom - 2].sum()  # apex up, base down
    # The orbit turns around the cone's own axis: every azimuth shows the same silhouette.
    for azimuth in (100.0, 170.0, -80.0):
        e.set_camera(azimuth=azimuth)
        assert iou(e.gbuffer.mask, first) > 0.9, azimuth
    # heights (contours, colour bands) run along y: the cone spans y in [0, 2]
    lo, hi = e.height_range
    assert lo < 0.3 and hi > 1.8
    img = e.render_image({"contour_interval": 0.25, "bands": 4})
    assert img.shape == (SIZE[1], SIZE[0], 3)


def test_up_overrides_the_file_convention(tmp_path):
    path = cone_y(tmp_path)
    lying = Explorer.from_file(path, window_size=SIZE, up="z")
    assert lying.up == "z"
    bw, bh = box(lying.gbuffer.mask)
    assert bh < 1.2 * bw
    # orbiting around z, which is across the cone's axis, turns its silhouette
    first = lying.gbuffer.mask.copy()
    lying.set_camera(azimuth=lying.camera.azimuth + 90.0)
    assert iou(lying.gbuffer.mask, first) < 0.8
    # a z-up file keeps z, and so does a dataset not read from a file
    stl = tmp_path / "cone.stl"
    pv.Cone(direction=(0, 0, 1)).triangulate().save(stl)
    assert Explorer.from_file(stl, window_size=SIZE).up == "z"
    assert Explorer(pv.Cone(), window_size=SIZE).up == "z"
    assert Explorer(pv.Cone(), window_size=SIZE, up="X").up == "x"
    with pytest.raises(InputError, match="up: expected"):
        Explorer.from_file(path, window_size=SIZE, up="w")


def test_explore_command_takes_up():
    parser = build_parser()
    assert parser.parse_args(["explore", "cone.ply"]).up is None  # the file's convention
    assert parser.parse_args(["explore", "cone.ply", "--up", "z"]).up == "z"
    assert parser.parse_args(["explore", "cone.ply", "-x"]).up == "x"
    with pytest.raises(SystemExit):
        parser.parse_args(["explore", "cone.ply", "--up", "w"])
