"""The NPR recipe (one picture per style name) and the ``sciviz-gbuf mesh`` command."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv
from PIL import Image

import sciviz_gbuf as sg
from sciviz_gbuf import styles
from sciviz_gbuf.cli import main
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.recipes.npr import STYLES, npr_image, with_section_uv
from tests.helpers.paths import SHARED_DATA

STL = SHARED_DATA / "meshes" / "vtkdata_42400-IDGH.stl"


@pytest.fixture(scope="module")
def nut_gb():
    return sg.capture(sg.datasets.load_nut(), window_size=(160, 120), supersample=2)


@pytest.mark.parametrize("style", list(STYLES))
def test_npr_image_is_the_style_function_in_8_bit(nut_gb, style):
    img = npr_image(nut_gb, style=style)
    assert img.dtype == np.uint8 and img.shape == (120, 160, 3)
    assert np.array_equal(img, npr_image(nut_gb, style=style))  # deterministic
    direct = {
        "gooch": lambda: styles.gooch(nut_gb),
        "toon": lambda: styles.toon(nut_gb),
        "hatch": lambda: styles.hatch(nut_gb),
        # the nut has no texture coordinates: sections along one world axis
        "drawing": lambda: styles.line_drawing(with_section_uv(nut_gb), combo="shu"),
    }[style]()
    if direct.ndim == 2:
        direct = np.repeat(direct[..., None], 3, axis=2)
    assert np.abs(img.astype(int) - np.rint(direct * 255)).max() <= 1
    assert img[0, 0].tolist() == [255, 255, 255]  # paper


def test_old_style_name_lines_is_the_drawing(nut_gb, tmp_path):
    assert np.array_equal(npr_image(nut_gb, style="lines"), npr_image(nut_gb, style="drawing"))
    with pytest.raises(InputError, match="style: expected one of"):
        npr_image(nut_gb, style="fig7")  # an illustrate style, not an NPR one


def test_section_uv_are_world_coordinates_across_the_line_of_sight(nut_gb):
    g = with_section_uv(nut_gb)
    sight = np.abs(nut_gb.camera.direction)
    a, b = sorted(np.argsort(sight)[:2])
    m = nut_gb.mask
    assert np.array_equal(g.uv[m], nut_gb.world[m][:, [a, b]])
    assert np.isnan(g.uv[~m]).all() and nut_gb.uv is None  # the original is unchanged


def test_named_views_are_framed_on_the_object():
    nut = sg.datasets.load_nut()
    img = npr_image(nut, style="toon", window_size=(120, 90), supersample=1)
    ink = img.min(axis=2) < 250
    rows, cols = np.nonzero(ink)
    # the object reaches (almost) two opposite borders of the picture
    assert (rows.min() <= 6 and rows.max() >= 83) or (cols.min() <= 6 and cols.max() >= 113)


def test_npr_rejects(nut_gb):
    with pytest.raises(InputError, match="style"):
        npr_image(nut_gb, style="watercolour")
    with pytest.raises(InputError, match="levels"):
        npr_image(nut_gb, style="toon", levels=0)


@pytest.mark.skipif(not STL.is_file(), reason="shared mesh data absent")
@pytest.mark.parametrize("style", list(STYLES))
def test_cli_mesh(tmp_path, capsys, style):
    out = tmp_path / f"{style}.png"
    args = ["mesh", str(STL), "-o", str(out), "--style", style, "--size", "96x72"]
    assert main([*args, "--supersample", "1"]) == 0
    assert style in capsys.readouterr().out
    with Image.open(out) as im:
        assert im.size == (96, 72)
        assert len(np.unique(np.asarray(im.convert("L")))) > 2


def test_cli_mesh_errors(tmp_path, capsys):
    assert main(["mesh", str(tmp_path / "none.stl"), "-o", str(tmp_path / "x.png")]) == 2
    assert "none.stl" in capsys.readouterr().err
    stl = tmp_path / "ball.stl"
    pv.Sphere().save(stl)
    with pytest.raises(SystemExit):
        main(["mesh", str(stl), "-o", str(tmp_path / "x.png"), "--light", "0,0"])
    assert main(["mesh", str(stl), "-o", str(tmp_path / "x.png"), "--light", "0,0,1"]) == 0
