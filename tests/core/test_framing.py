"""The one framing rule and the up axis, measured on real offscreen VTK renders.

Framing: the covered pixels' bounding box is centred and fills FILL (85 %) of the limiting
image dimension, so the empty-frame fraction (1 - fill) is at most 25 % for every default
view. Up axis: y-up files (PLY/OBJ) stand upright by default; ``up=`` / ``--up`` override.
"""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv
from PIL import Image

import sciviz_gbuf as sg
from sciviz_gbuf.core.framing import (
    FILL,
    default_up,
    framed_camera,
    framing,
    named_view_camera,
    terrain_birdseye_camera,
)
from sciviz_gbuf.readers import FORMATS, read_mesh, up_axis
from sciviz_gbuf.recipes.birdseye import birdseye_gbuffer
from sciviz_gbuf.recipes.surface import surface_gbuffer
from tests.helpers.cli import run_cli
from tests.helpers.paths import SHARED_DATA

SIZE = (160, 120)


def box(mask: np.ndarray) -> tuple[float, float, float, float, float]:
    """``(fill, dx, dy, width, height)`` of the covered pixels' bounding box: fill of the
    limiting dimension, centre offset in fractions of the image (right and down positive)."""
    h, w = mask.shape
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    bh, bw = rows[-1] - rows[0] + 1, cols[-1] - cols[0] + 1
    dx = ((cols[0] + cols[-1] + 1) / 2 - w / 2) / w
    dy = ((rows[0] + rows[-1] + 1) / 2 - h / 2) / h
    return max(bw / w, bh / h), dx, dy, bw, bh


def assert_framed(mask: np.ndarray, tol: float = 0.03) -> None:
    fill, dx, dy, _, _ = box(mask)
    # one pixel of rasterisation either way on each side
    px = 2.0 / min(mask.shape)
    assert 0.75 <= fill <= 0.92, fill
    assert abs(fill - FILL) <= tol + px, fill
    assert abs(dx) <= 0.01 + px and abs(dy) <= 0.01 + px, (dx, dy)


def cone_y(tmp_path, suffix: str):
    """A cone pointing +y (a y-up model), standing on y = 0, written as ``suffix``."""
    cone = pv.Cone(center=(0, 1, 0), direction=(0, 1, 0), height=2.0, radius=0.5, resolution=40)
    path = tmp_path / f"cone{suffix}"
    cone.triangulate().save(path)
    return path


@pytest.mark.parametrize("parallel", [False, True])
@pytest.mark.parametrize("direction", [(1.0, -2.0, 1.5), (0.2, -1.0, 3.0)])
def test_framed_camera_centres_and_fills_a_real_render(direction, parallel):
    # A long thin oblique shape: corner framing would leave it small and off-centre.
    mesh = pv.Cylinder(direction=(1, 0.3, 0.2), height=4.0, radius=0.3).triangulate()
    cam = framed_camera(
        (), direction, (0, 0, 1), aspect=SIZE[0] / SIZE[1], points=mesh.points, parallel=parallel
    )
    g = sg.capture(mesh, window_size=SIZE, camera=cam, parallel_projection=parallel or None)
    assert_framed(g.mask)
    scale = g.camera.parallel_scale if parallel else None
    fill, dx, dy = framing(mesh.points, *cam, aspect=SIZE[0] / SIZE[1], parallel_scale=scale)
    assert abs(fill - FILL) < 2e-3 and abs(dx) < 2e-3 and abs(dy) < 2e-3


@pytest.mark.parametrize("view", ["iso", "xy", "xz", "yz"])
def test_capture_named_views_follow_the_rule(view):
    g = sg.capture(pv.Cube(x_length=2.0).triangulate(), window_size=SIZE, camera=view)
    assert_framed(g.mask)
    g = sg.capture(pv.Sphere(), window_size=SIZE, camera=view, parallel_projection=True)
    assert_framed(g.mask)


def test_terrain_birdseye_frames_the_ground_not_its_box():
    x, y = np.meshgrid(np.linspace(0, 100, 60), np.linspace(0, 60, 40))
    z = 8 * np.sin(x / 15) * np.cos(y / 11)
    ground = pv.StructuredGrid(x, y, z)
    pts = np.asarray(ground.points)
    loose = terrain_birdseye_camera(ground.bounds, aspect=SIZE[0] / SIZE[1])
    tight = terrain_birdseye_camera(ground.bounds, aspect=SIZE[0] / SIZE[1], points=pts)
    assert_framed(sg.capture(ground, window_size=SIZE, camera=tight).mask)
    assert box(sg.capture(ground, window_size=SIZE, camera=loose).mask)[0] < FILL


def test_up_axis_is_a_field_of_the_one_suffix_table():
    for suffix in (".ply", ".obj", ".off", ".gltf", ".glb"):
        assert FORMATS[suffix].up == "y" and up_axis(f"m{suffix.upper()}") == "y"
    for suffix in (".stl", ".vtk", ".vtp", ".asc", ".tif", ".hgt", ".bpt"):
        assert FORMATS[suffix].up == "z" and up_axis(f"m{suffix}") == "z"
    assert up_axis("scan.xyz") == "z" and up_axis(None) == "z"
    assert {f.up for f in FORMATS.values()} <= {"x", "y", "z"}


def test_a_y_up_ply_stands_upright_by_default_and_up_overrides(tmp_path):
    mesh = read_mesh(cone_y(tmp_path, ".ply"))
    assert default_up(mesh) == "y" and default_up(pv.Cone()) == "z"
    upright = sg.capture(mesh, window_size=SIZE, camera="iso")
    assert_framed(upright.mask)
    _, _, _, bw, bh = box(upright.mask)
    assert bh > 1.6 * bw  # the cone's axis vertical: tall and narrow
    # the apex is the top of the picture, above the base's centre
    top = np.flatnonzero(upright.mask.any(axis=1))[0]
    cols = np.flatnonzero(upright.mask[top])
    assert abs(cols.mean() - SIZE[0] / 2) < 0.05 * SIZE[0]
    lying = sg.capture(mesh, window_size=SIZE, camera="iso", up="z")
    _, _, _, bw, bh = box(lying.mask)
    assert bh < 1.2 * bw
    with pytest.raises(sg.InputError, match="up: expected"):
        sg.capture(mesh, window_size=SIZE, camera="iso", up="w")


@pytest.mark.parametrize(
    ("suffix", "cmd", "extra", "tall"),
    [
        (".obj", "mesh", [], True),
        (".ply", "mesh", ["--parallel"], True),
        (".ply", "edges", [], True),
        (".ply", "edges", ["--up", "z"], False),
        (".obj", "mesh", ["-z"], False),
    ],
)
def test_mesh_and_edges_commands_draw_y_up_files_upright(tmp_path, suffix, cmd, extra, tall):
    path = cone_y(tmp_path, suffix)
    out = tmp_path / "out.png"
    r = run_cli([cmd, str(path), "-o", str(out), "--size", "160x120", *extra])
    assert r.returncode == 0, r.stderr
    rgb = np.asarray(Image.open(out).convert("RGB")).astype(int)
    ink = np.abs(rgb - 255).sum(axis=2) > 12
    fill, dx, dy, bw, bh = box(ink)
    assert 0.75 <= fill <= 0.92 and abs(dx) < 0.04 and abs(dy) < 0.04, (fill, dx, dy)
    assert (bh > 1.6 * bw) == tall, (bw, bh)


def test_up_option_is_checked(tmp_path):
    r = run_cli(["mesh", str(cone_y(tmp_path, ".ply")), "-o", str(tmp_path / "x.png"), "--up", "w"])
    assert r.returncode == 2 and "--up" in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_named_view_camera_up_only_turns_the_iso_view():
    pts = np.random.default_rng(1).normal(size=(200, 3))
    assert named_view_camera(pts, "iso", up="y")[2] == (0.0, 1.0, 0.0)
    assert named_view_camera(pts, "xz", up="y")[2] == (0.0, 0.0, 1.0)
    with pytest.raises(sg.InputError, match="up: expected"):
        named_view_camera(pts, "iso", up="up")


needs_data = pytest.mark.skipif(not SHARED_DATA.is_dir(), reason="no ../shared/data")


@needs_data
@pytest.mark.parametrize("name", ["hugo_site.asc", "pre_runout_DEM.asc"])
def test_birdseye_default_view_of_shared_dems(name):
    g = birdseye_gbuffer(SHARED_DATA / "dem" / name, window_size=SIZE, supersample=1)
    assert_framed(g.mask)


@needs_data
def test_shared_stl_teapot_and_ct_default_views():
    stl = read_mesh(SHARED_DATA / "meshes" / "vtkdata_42400-IDGH.stl")
    assert_framed(sg.capture(stl, window_size=SIZE, camera="iso").mask)
    teapot = surface_gbuffer(SHARED_DATA / "patches" / "teapot.bpt", window_size=SIZE,
                             supersample=1, resolution=8)  # fmt: skip
    assert_framed(teapot.mask)
    # z-up teapot: upright, wider than tall (spout and handle to the sides)
    _, _, _, bw, bh = box(teapot.mask)
    assert bw > 1.3 * bh
    ct = sg.recipes.medical.ct_gbuffer(
        SHARED_DATA / "ct" / "dcm_qa_ct_Philips_phantom_5mm", window_size=(96, 96),
        supersample=1, smooth=0,
    )  # fmt: skip
    assert_framed(ct.mask)


@pytest.mark.parametrize("azimuth, elevation, zoom", [(None, None, 1.0), (200.0, -20.0, 1.0)])
def test_explorer_orbit_views_follow_the_rule(azimuth, elevation, zoom):
    """The explorer's orbit camera frames the object by the one rule at any orbit position (a
    long ellipsoid: its bounding sphere would leave it at about half the frame)."""
    from sciviz_gbuf.apps.explorer import Explorer

    e = Explorer(pv.ParametricEllipsoid(3, 1, 0.6).triangulate(), window_size=SIZE)
    if azimuth is not None:
        e.set_camera(azimuth=azimuth, elevation=elevation, zoom=zoom)
    assert_framed(e.gbuffer.mask)
    # zoom 2 brings the eye twice as close to the focal point
    pos, focal, _ = e.camera_tuple()
    e.set_camera(zoom=2.0)
    pos2, focal2, _ = e.camera_tuple()
    np.testing.assert_allclose(focal2, focal)
    d1, d2 = (np.linalg.norm(np.subtract(p, focal)) for p in (pos, pos2))
    assert d2 == pytest.approx(d1 / 2.0)


def test_explorer_maps_a_small_dem_at_the_window_size():
    """A DEM smaller than the window is mapped at the window's size (smooth lines), not one
    picture pixel per cell."""
    from sciviz_gbuf.apps.explorer import Explorer
    from sciviz_gbuf.readers import read_dem

    y, x = np.mgrid[0:40, 0:60].astype(np.float32)
    dem = read_dem(np.hypot(x - 30, y - 20).astype(np.float32), spacing=10.0)
    e = Explorer(dem.to_pyvista(), window_size=(240, 200), kind="dem", dem=dem)
    img = e.render_image()
    assert img.shape[:2] == (160, 240)  # the grid's aspect, fitted in the window
