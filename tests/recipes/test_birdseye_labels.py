"""Contour labels in bird's-eye maps: placed on the picture's own height image (``wz``), each
label on an index contour as drawn, its number that contour's height, its top towards higher
ground as seen; the contour ink knocked out under it and nothing else changed; the CLI."""

from __future__ import annotations

import math

import numpy as np
import pytest
from PIL import Image

import sciviz_gbuf as sg
from sciviz_gbuf.core.gbuffer import GBuffer
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.readers import read_dem
from sciviz_gbuf.recipes import birdseye
from sciviz_gbuf.recipes._intervals import contour_intervals
from sciviz_gbuf.recipes.birdseye import (
    birdseye_gbuffer,
    birdseye_label_heights,
    birdseye_layers,
    birdseye_panels,
)
from sciviz_gbuf.recipes.labels import label_boxes, label_ink, label_options, label_text
from tests.helpers.cli import assert_clean_failure, checksums, run_cli
from tests.helpers.label_checks import bilinear, problems

SIZE = (400, 300)


def cone(shape=(200, 260), slope=1.0, top=300.0) -> np.ndarray:
    """A cone on 1 m pixels, apex at the grid's centre, heights falling ``slope`` per px."""
    h, w = shape
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    return (top - slope * np.hypot(x - (w - 1) / 2, y - (h - 1) / 2)).astype(np.float32)


# The cone with the picture's automatic intervals and with explicit ones; the bundled DEM
# (its lines crowd at 400 px: larger, and labels closer along a line).
CASES = {
    "cone": ({}, {}),
    "cone-25": ({}, {"interval": 5.0, "major_interval": 25.0}),
    "jacksboro": ({"size": (640, 480)}, {"label_spacing": 150.0}),
}


@pytest.fixture(scope="module")
def gbuffers() -> dict[str, GBuffer]:
    return {
        "cone": birdseye_gbuffer(read_dem(cone(), spacing=1.0), size=SIZE),
        "jacksboro": birdseye_gbuffer(sg.datasets.load_jacksboro_dem(), size=(640, 480)),
    }


@pytest.fixture(scope="module", params=sorted(CASES))
def case(request, gbuffers):
    """``(gbuffer, options, layers without labels, layers with labels, step, minor)``."""
    name = request.param
    gb = gbuffers[name.split("-")[0]]
    opts = CASES[name][1]
    lines = {k: v for k, v in opts.items() if k in ("interval", "major_interval")}
    plain = birdseye_layers(gb, **lines)
    lay = birdseye_layers(gb, labels=True, **opts)
    # the intervals the picture's contours use (those birdseye_layers takes for cn)
    elev = np.where(gb.mask, gb.scalars["elevation"], np.float32(np.nan))
    _, _, minor, major = contour_intervals(
        elev, lines.get("interval"), lines.get("major_interval"),
        pixels_per_sample=1.0 / gb.supersample,
    )  # fmt: skip
    return gb, opts, plain, lay, float(major if major is not None else minor), float(minor)


def _up(lab) -> np.ndarray:
    """The text's up vector in image coordinates (column, row; rows down)."""
    a = math.radians(lab.angle)
    return np.array([-math.sin(a), -math.cos(a)])


def test_labels_exist_and_break_no_placement_rule(case):
    _gb, opts, _plain, lay, step, _ = case
    labels = lay["labels"]
    assert len(labels) >= 5
    z = birdseye_label_heights(lay)
    _, spacing = label_options(opts.get("label_size"), opts.get("label_spacing"))
    found = problems(labels, z, step, spacing)
    found["unlabelled"] = []  # in perspective an index line may be hidden behind a ridge
    bad = {k: v[:3] for k, v in found.items() if v}
    assert not bad, bad
    # every box lies on whole terrain pixels clear of the profile lines (and the outline)
    for lab in labels:
        box = label_boxes([lab], z.shape) > 0
        assert (lay["alpha"][box] == 1.0).all()
        assert (lay["pr"][box] == 0.0).all()


def test_each_label_is_the_height_of_the_index_contour_under_it(case):
    """The image-space height at the label's centre is its level within half a (minor)
    interval, the level is a multiple of the major interval the picture's contours use, and
    the text is that number; the centre lies on a major line as drawn (labels=False)."""
    _gb, _opts, plain, lay, step, minor = case
    wz = lay["wz"].astype(np.float64)
    for lab in lay["labels"]:
        assert abs(bilinear(wz, lab.x, lab.y) - lab.level) < minor / 2
        assert lab.level / step == pytest.approx(round(lab.level / step), abs=1e-9)
        assert lab.text == label_text(lab.level, step)
        r, c = round(lab.y), round(lab.x)
        assert plain["cn"][r - 1 : r + 2, c - 1 : c + 2].max() > 0.5


def test_text_faces_uphill_in_the_image(case):
    """A few pixels along the text's up vector the ground seen is higher than as far the
    other way."""
    _gb, _opts, _plain, lay, _step, _ = case
    wz = lay["wz"].astype(np.float64)
    for lab in lay["labels"]:
        up = _up(lab)
        above = bilinear(wz, lab.x + 3 * up[0], lab.y + 3 * up[1])
        below = bilinear(wz, lab.x - 3 * up[0], lab.y - 3 * up[1])
        assert above > lab.level > below


def test_cone_labels_read_upright_and_face_the_apex(gbuffers):
    """Seen from the south-east the cone's near flank faces the eye: its labels read upright
    (angle within 90 degrees of the screen's +x), their tops towards the apex as seen."""
    gb = gbuffers["cone"]
    lay = birdseye_layers(gb, labels=True)
    wz = lay["wz"]
    apex = np.unravel_index(np.nanargmax(wz), wz.shape)  # (row, column) of the summit
    for lab in lay["labels"]:
        assert abs(lab.angle) <= 90.0
        to_apex = np.array([apex[1] - lab.x, apex[0] - lab.y])
        assert _up(lab) @ to_apex > 0


def test_contour_ink_knocked_out_under_the_boxes_only(case):
    """Inside every box the contour ink is zero (it was there before: the label sits on a
    line); outside every box ``cn`` is unchanged bit for bit, and no other layer changes."""
    _gb, _opts, plain, lay, _step, _ = case
    boxes = label_boxes(lay["labels"], lay["cn"].shape)
    inside = boxes >= 1.0
    assert (lay["cn"][inside] == 0).all()
    for lab in lay["labels"]:
        one = label_boxes([lab], lay["cn"].shape) >= 1.0
        assert (plain["cn"][one] > 0.5).sum() >= 3
    np.testing.assert_array_equal(lay["cn"][boxes == 0], plain["cn"][boxes == 0])
    for key in ("pr", "sh", "bands", "alpha", "wz", "depth"):
        np.testing.assert_array_equal(lay[key], plain[key])


def test_picture_changes_only_in_the_boxes_and_the_text_is_drawn(gbuffers):
    """Red lines, blue text on white (``cn`` panel): in the boxes only white and blue mix
    (no line ink), each box holds text, and outside the boxes every panel is unchanged."""
    gb = gbuffers["cone"]
    opts = {"contour_color": (1.0, 0.0, 0.0), "bands": False}
    plain = birdseye_panels(gb, **opts)
    lab = birdseye_panels(gb, labels=True, label_color=(0.0, 0.0, 1.0), **opts)
    placed = birdseye_layers(gb, labels=True, bands=False)["labels"]
    assert placed
    boxes = label_boxes(placed, SIZE[::-1])
    inside = boxes >= 1.0
    img = lab["cn"]
    r, g = img[..., 0].astype(int), img[..., 1].astype(int)
    assert np.abs(r - g)[inside].max() <= 1
    ref = plain["cn"]
    assert (np.abs(ref[..., 0].astype(int) - ref[..., 1])[inside] > 50).sum() > 50
    ink = label_ink(placed, SIZE[::-1], label_options(None, None)[0])
    for one in placed:
        box = label_boxes([one], SIZE[::-1]) >= 1.0
        assert ink[box].max() > 0.9
        assert (img[box][:, 2].astype(int) - img[box][:, 0] > 100).any()  # blue text
    for key in plain:
        np.testing.assert_array_equal(lab[key][boxes == 0], plain[key][boxes == 0])
    # the profile picture has no contour lines and gets no text
    np.testing.assert_array_equal(lab["pr"], plain["pr"])


def test_labels_false_is_the_picture_without_labels(gbuffers):
    """``labels=False`` (the default) draws the picture as before, whatever the other label
    options say; the layers carry no ``labels``."""
    gb = gbuffers["cone"]
    base = sg.birdseye_map(gb)
    same = sg.birdseye_map(gb, labels=False, label_size=20.0, label_spacing=50.0,
                           label_color=(0.0, 0.0, 1.0))  # fmt: skip
    np.testing.assert_array_equal(base, same)
    np.testing.assert_array_equal(base, birdseye_panels(gb)["mx4"])
    assert "labels" not in birdseye_layers(gb)
    with_labels = sg.birdseye_map(gb, labels=True)
    assert (with_labels != base).any()


def test_no_contours_no_labels(gbuffers):
    gb = gbuffers["cone"]
    lay = birdseye_layers(gb, labels=True, contours=False)
    assert lay["labels"] == []
    assert (lay["cn"] == 0).all()


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"label_size": 0}, "label_size"),
        ({"label_size": 2}, "label_size"),
        ({"label_size": math.nan}, "label_size"),
        ({"label_spacing": -1}, "label_spacing"),
        ({"label_spacing": 1e9}, "label_spacing"),
        ({"labels": "yes"}, "labels"),
        ({"label_color": (2, 0, 0)}, "label_color"),
    ],
)
def test_bad_label_options_fail_before_rendering(monkeypatch, kw, match):
    def no_render(*args, **kwargs):
        raise AssertionError("rendered before the options were checked")

    monkeypatch.setattr(birdseye, "birdseye_gbuffer", no_render)
    with pytest.raises(InputError, match=match):
        sg.birdseye_map(cone((40, 50)), **{"labels": True, **kw})
    with pytest.raises(InputError, match=match):
        birdseye_panels(cone((40, 50)), **{"labels": True, **kw})


def test_cli_birdseye_labels(tmp_path):
    """The command writes the labelled map: the PNG is the labelled ``mx4`` of the G-buffer
    it saved, bit for bit, and differs from the picture without labels."""
    dem, out, saved = tmp_path / "cone.npy", tmp_path / "out.png", tmp_path / "gb.npz"
    np.save(dem, cone())
    proc = run_cli(["birdseye", dem, "-o", out, "--labels", "--size", "400x300",
                    "--save-gbuffer", saved, "--no-progress"])  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    img = np.asarray(Image.open(out))
    assert img.shape == (300, 400, 4)
    gb = GBuffer.load(saved)
    np.testing.assert_array_equal(img, birdseye_panels(gb, labels=True)["mx4"])
    assert (img != birdseye_panels(gb)["mx4"]).any()


@pytest.mark.parametrize(
    "argv, match",
    [
        (["--labels", "--label-size", "0"], ["label_size", "--label-size"]),
        (["--labels", "--label-size", "2"], ["label_size", "--label-size"]),
        (["--labels", "--label-spacing", "-5"], ["label_spacing", "--label-spacing"]),
        (["--labels", "--style", "sumi-e"], ["--labels"]),
        (["--labels", "--contours", "none"], ["--labels"]),
    ],
)
def test_cli_bad_label_options(tmp_path, argv, match):
    dem, out = tmp_path / "d.npy", tmp_path / "m.png"
    np.save(dem, cone((60, 70)))
    inputs = checksums([dem])
    proc = run_cli(["birdseye", dem, "-o", out, "--size", "80x60", *argv], cwd=tmp_path)
    assert_clean_failure(proc, names=match, outputs=[out], inputs=inputs)
