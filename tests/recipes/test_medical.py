"""Isosurfaces of volumes and the Fig. 14 CT recipe, on analytic volumes and the real phantom."""

from __future__ import annotations

import json
import random
import shutil

import numpy as np
import pytest
import pyvista as pv
from scipy.spatial.transform import Rotation

import sciviz_gbuf as sg
from sciviz_gbuf.cli import main
from sciviz_gbuf.core.isosurface import ISO_PRESETS, isosurface
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.recipes.medical import (
    VIEWS,
    ct_enhance,
    ct_gbuffer,
    ct_layers,
    ct_panels,
    view_camera,
)
from tests.helpers.paths import SHARED_DATA

PHILIPS = SHARED_DATA / "ct" / "dcm_qa_ct_Philips_phantom_5mm"
CENTRE = np.array([3.0, -2.0, 40.0])
RADIUS = 20.0


def ball_volume(kind: str = "image", rotate: float = 0.0) -> pv.DataSet:
    """HU = 1300 - 50 r (mm): bone (300 HU) inside r = 20 mm of CENTRE, anisotropic voxels."""
    im = pv.ImageData(dimensions=(40, 36, 24), spacing=(1.4, 1.5, 2.5))
    im.origin = CENTRE - np.array([19.5 * 1.4, 17.5 * 1.5, 11.5 * 2.5])
    if rotate:
        im.direction_matrix = Rotation.from_euler(
            "zx", [rotate, rotate / 2], degrees=True
        ).as_matrix()
        # Keep the ball inside: rotate about the volume's centre.
        shift = CENTRE - np.asarray(im.points).mean(axis=0)
        im.origin = np.asarray(im.origin) + shift
    if kind == "sheared":
        grid = im.cast_to_structured_grid()
        pts = np.asarray(grid.points).copy()
        # A gantry-tilt-like shear: each slice shifted in y in proportion to its z.
        pts[:, 1] += 0.3 * (pts[:, 2] - CENTRE[2])
        grid.points = pts
        im = grid
    r = np.linalg.norm(np.asarray(im.points) - CENTRE, axis=1)
    im.point_data["HU"] = (1300.0 - 50.0 * r).astype(np.float32)
    return im


# ------------------------------------------------------------------------------ isosurface


@pytest.mark.parametrize(("kind", "rotate"), [("image", 0.0), ("image", 35.0), ("sheared", 0.0)])
def test_isosurface_of_a_ball_is_the_sphere(kind, rotate):
    vol = ball_volume(kind, rotate)
    surf = isosurface(vol, iso="bone", smooth=0)
    r = np.linalg.norm(surf.points - CENTRE, axis=1)
    # HU is linear in r, so linear interpolation along an edge errs only by the chord's sag.
    assert np.abs(r - RADIUS).max() < 0.05
    radial = (surf.points - CENTRE) / r[:, None]
    cosine = np.sum(surf.point_data["Normals"] * radial, axis=1)
    assert np.abs(cosine).min() > np.cos(np.radians(5.0))
    meta = json.loads(surf.field_data["isosurface"][0])
    assert meta["iso"] == ISO_PRESETS["bone"]
    assert meta["method"] == ("flying_edges" if kind == "image" else "contour")


def test_isosurface_smoothing_keeps_the_size_and_decimation_reduces():
    vol = ball_volume()
    plain = isosurface(vol, smooth=0)
    smooth = isosurface(vol, smooth=30)
    r = np.linalg.norm(smooth.points - CENTRE, axis=1)
    # Windowed-sinc smoothing does not shrink the ball (Laplacian smoothing would).
    assert abs(np.mean(r) - RADIUS) < 0.1
    half = isosurface(vol, smooth=0, decimate=0.5)
    assert 0.4 < half.n_cells / plain.n_cells < 0.6


def test_isosurface_nan_padding_and_largest_piece():
    vol = ball_volume()
    hu = np.asarray(vol.point_data["HU"]).copy()
    # A second, smaller ball and a NaN slab (padding read as NaN) at the volume's edge.
    pts = np.asarray(vol.points)
    r2 = np.linalg.norm(pts - (CENTRE + np.array([22.0, 18.0, 0.0])), axis=1)
    hu = np.maximum(hu, 1300.0 - 200.0 * r2)
    hu[pts[:, 2] < pts[:, 2].min() + 3] = np.nan
    vol.point_data["HU"] = hu.astype(np.float32)
    both = isosurface(vol, smooth=0)
    one = isosurface(vol, smooth=0, largest=True)
    assert np.isfinite(both.points).all() and np.isfinite(both.point_data["Normals"]).all()
    assert both.connectivity("all").point_data["RegionId"].max() == 1
    assert one.n_points < both.n_points
    assert np.abs(np.linalg.norm(one.points - CENTRE, axis=1) - RADIUS).max() < 0.05


@pytest.mark.parametrize(
    ("kwargs", "word"),
    [
        ({"iso": 5000.0}, "outside the range"),
        ({"iso": "marrow"}, "expected a number or one of"),
        ({"iso": float("nan")}, "finite"),
        ({"smooth": -1}, "smooth"),
        ({"smooth": 2.5}, "smooth"),
        ({"decimate": 1.0}, "decimate"),
        ({"scalars": "density"}, "no point array 'density'"),
    ],
)
def test_isosurface_rejects(kwargs, word):
    with pytest.raises(InputError, match=word):
        isosurface(ball_volume(), **kwargs)


def test_isosurface_preset_needs_hounsfield_units():
    vol = ball_volume()
    vol.point_data["density"] = vol.point_data.pop("HU")
    with pytest.raises(InputError, match="Hounsfield"):
        isosurface(vol, iso="bone", scalars="density")
    assert isosurface(vol, iso=300.0, scalars="density").n_points > 0
    with pytest.raises(InputError, match="PyVista dataset"):
        isosurface(np.zeros((4, 4, 4)))


# ---------------------------------------------------------------------------- views, layers


@pytest.mark.parametrize("view", [*VIEWS, "anterior-left", (1.0, -2.0, 0.5)])
def test_view_camera_looks_from_the_named_side_and_frames_everything(view):
    pts = np.random.default_rng(1).normal(size=(500, 3)) * [30.0, 20.0, 60.0] + CENTRE
    pos, focal, up = view_camera(pts, view, view_angle=20.0, aspect=1.5, margin=0.04)
    to_eye = np.subtract(pos, focal)
    to_eye /= np.linalg.norm(to_eye)
    if isinstance(view, str):
        want = np.sum([VIEWS[v][0] for v in view.split("-")], axis=0)
    else:
        want = np.asarray(view)
    assert np.allclose(to_eye, want / np.linalg.norm(want), atol=1e-9)
    assert abs(np.dot(up, to_eye)) < 1e-9
    if view == "anterior":  # the head is up, the patient's left on the image's right
        assert np.allclose(np.asarray(up) / np.linalg.norm(up), [0, 0, 1])
    # Every point projects inside the picture, and some touch the margin.
    d = -to_eye
    right = np.cross(d, up) / np.linalg.norm(np.cross(d, up))
    upv = np.cross(right, d)
    rel = pts - pos
    depth = rel @ d
    tan = np.tan(np.radians(10.0))
    x = (rel @ right) / depth / (tan * 1.5)
    y = (rel @ upv) / depth / tan
    assert max(np.abs(x).max(), np.abs(y).max()) == pytest.approx(0.96, abs=1e-6)


@pytest.mark.parametrize("view", ["front", "anterior-posterior", (0, 0, 0), "x"])
def test_view_camera_rejects(view):
    with pytest.raises(InputError, match="view"):
        view_camera(np.array([[0, 0, 0], [1, 1, 1], [2, 0, 1]]), view)


@pytest.fixture(scope="module")
def ball_gbuffer():
    return ct_gbuffer(ball_volume(), view="anterior", window_size=(160, 160), supersample=2)


def test_layers_contours_lie_on_the_axial_levels(ball_gbuffer):
    gb = ball_gbuffer
    lay = ct_layers(gb, contour_interval=4.0, contour_width=1.0)
    z = gb.downsample(np.where(gb.mask, gb.world[..., 2], np.nan))
    cn = lay["cn"]
    inked = (cn > 0.5) & np.isfinite(z)
    assert inked.sum() > 100
    # Where the line is drawn, z is within a pixel's worth of z change of a multiple of 4 mm.
    dz_px = np.hypot(*np.gradient(z))
    off = np.abs(z - 4.0 * np.round(z / 4.0))
    inner = inked & np.isfinite(dz_px)  # np.gradient is NaN beside the background
    assert inner.sum() > 0.9 * inked.sum()
    assert np.all(off[inner] <= 1.0 * dz_px[inner] + 1e-3)
    # Every level crossing the ball's middle (z = 32..48, the steep part of each ring) is drawn.
    rows = np.nonzero(inked.any(axis=1))[0]
    levels_hit = set(np.round(z[inked] / 4.0).astype(int).tolist())
    assert set(range(8, 13)) <= levels_hit
    assert rows.size > 0


def test_layers_bands_profiles_and_shade(ball_gbuffer):
    gb = ball_gbuffer
    lay = ct_layers(gb, bands=4.0, band_axis="y")
    y = gb.downsample(np.where(gb.mask, gb.world[..., 1], np.nan))
    solid = lay["alpha"] > 0.999
    # Bands: one colour per 4 mm band of y (shading is not in this layer).
    band = np.floor(y / 4.0)
    rgb = lay["bands"]
    for b in np.unique(band[solid]):
        sel = solid & (band == b)
        inner = sel & (np.abs(y - 4.0 * (b + 0.5)) < 1.0)
        if inner.sum() > 5:
            assert np.ptp(rgb[inner], axis=0).max() < 1e-6
    # Near (small y, anterior) is warm, far is cool.
    near, far = solid & (y < np.nanmin(y) + 4), solid & (y > np.nanmax(y[solid]) - 4)
    warm = rgb[..., 0] - rgb[..., 2]
    assert warm[near].mean() > warm[far].mean() + 0.2
    # Profiles on the ball's outline, none at its centre.
    yy, xx = np.nonzero(lay["pr"] > 0.5)
    cy, cx = np.nonzero(solid)[0].mean(), np.nonzero(solid)[1].mean()
    rr = np.hypot(yy - cy, xx - cx)
    radius_px = np.sqrt(solid.sum() / np.pi)
    # (the limb of a sphere is steep in depth: a rare pixel just inside it counts as a profile)
    assert np.all(np.abs(rr - radius_px) < 4.0)
    assert np.mean(np.abs(rr - radius_px) < 2.0) > 0.98
    assert lay["pr"][int(cy) - 40 : int(cy) + 40, int(cx) - 40 : int(cx) + 40].max() < 0.01
    # Shade: the upper-left (towards the light) is brighter than the lower-right.
    assert (
        lay["sh"][int(cy - radius_px / 2), int(cx - radius_px / 2)]
        > lay["sh"][int(cy + radius_px / 2), int(cx + radius_px / 2)]
    )


def test_ct_enhance_layouts_and_determinism(ball_gbuffer):
    pair = ct_enhance(ball_gbuffer)
    again = ct_enhance(ball_gbuffer)
    assert np.array_equal(pair, again)
    assert pair.dtype == np.uint8 and pair.shape == (160, 2 * 160 + 5, 4)
    enhanced = ct_enhance(ball_gbuffer, layout="enhanced")
    shaded = ct_enhance(ball_gbuffer, layout="shaded")
    assert np.array_equal(pair[:, :160], shaded) and np.array_equal(pair[:, -160:], enhanced)
    assert enhanced[0, 0, 3] == 0 and enhanced[80, 80, 3] == 255
    white = ct_enhance(ball_gbuffer, layout="enhanced", background=(1, 1, 1))
    assert (white[..., 3] == 255).all() and (white[0, 0, :3] == 255).all()
    panels = ct_panels(ball_gbuffer)
    assert set(panels) == {"shaded", "enhanced", "pr", "cn", "sh", "bands"}
    with pytest.raises(InputError, match="layout"):
        ct_enhance(ball_gbuffer, layout="grid")
    with pytest.raises(InputError, match="bands"):
        ct_enhance(ball_gbuffer, bands=0)
    with pytest.raises(InputError, match="contour_axis"):
        ct_enhance(ball_gbuffer, contour_axis="w")


def test_top_level_export():
    assert sg.ct_enhance is ct_enhance


# ------------------------------------------------------------------------ the real phantom

needs_philips = pytest.mark.skipif(not PHILIPS.is_dir(), reason="shared CT data not present")


@needs_philips
def test_ct_enhance_on_the_philips_phantom_is_independent_of_file_order(tmp_path):
    files = sorted(PHILIPS.glob("*.dcm"))
    shuffled = files[:]
    random.Random(7).shuffle(shuffled)
    a = ct_enhance(PHILIPS, window_size=(128, 128), supersample=1, layout="enhanced")
    b = ct_enhance(shuffled, window_size=(128, 128), supersample=1, layout="enhanced")
    assert np.array_equal(a, b)
    cover = a[..., 3] > 0
    assert 0.2 < cover.mean() < 0.95
    # Anterior view: the face (near, warm bands) is in the middle of the picture.
    mid = a[48:80, 48:80]
    assert (mid[..., 3] == 255).all()


@needs_philips
def test_cli_ct(tmp_path, capsys):
    out = tmp_path / "ct.png"
    assert main(["ct", str(PHILIPS), "-o", str(out), "--size", "96x96", "--supersample", "1"]) == 0
    text = capsys.readouterr().out
    assert "28 slices" in text and out.is_file()
    from PIL import Image

    assert Image.open(out).size == (2 * 96 + 3, 96)


def test_cli_ct_errors(tmp_path, capsys):
    missing = tmp_path / "nothing_here"
    assert main(["ct", str(missing), "-o", str(tmp_path / "x.png")]) == 2
    assert "nothing_here" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["ct", str(tmp_path), "-o", str(tmp_path / "x.png"), "--iso", "hard"])
    assert exc.value.code == 2
    assert "bone" in capsys.readouterr().err


@needs_philips
def test_cli_ct_does_not_touch_the_input(tmp_path):
    src = tmp_path / "series"
    shutil.copytree(PHILIPS, src)
    before = {p.name: p.read_bytes() for p in src.iterdir()}
    assert main(["ct", str(src), "-o", str(tmp_path / "o.png"), "--size", "64x64"]) == 0
    assert {p.name: p.read_bytes() for p in src.iterdir()} == before
