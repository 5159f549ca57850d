"""No style fills an area solid black (issue: "no black blobs in any style").

Every style of the registry with a drawing function is drawn on a few small inputs: a torus
with texture coordinates, a sphere, the shared STL part, the torus lit from behind (every
visible face in shadow) and a bird's-eye terrain. A solid-black area is a connected set of
black pixels (luminance < 26/255) that contains 3 x 3 blocks of black, i.e. the opening of
the black pixels by a 3 x 3 square: lines up to two pixels wide, hatching and cross-hatching
are not areas however far they connect, a blob or a face filled black is. The largest one
must stay below 0.5 % of the object's pixels; line drawings must have none at all beyond a
few pixels (the lines of a drawing never fill an area).
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
import pyvista as pv
from scipy import ndimage

import sciviz_gbuf as sg
from sciviz_gbuf.datasets import load_jacksboro_dem
from sciviz_gbuf.readers import read_scene
from sciviz_gbuf.recipes.birdseye import birdseye_gbuffer
from sciviz_gbuf.styles import STYLES
from tests.helpers.paths import SHARED_DATA

SIZE = 200
BLACK = 26 / 255
#: Light from behind the object (eye space): all of the visible surface is in shadow.
BEHIND = (0.2, 0.3, -1.0)
SQUARE = np.ones((3, 3), dtype=bool)
STL = SHARED_DATA / "meshes" / "vtkdata_42400-IDGH.stl"


@cache
def gbuffer(name: str):
    if name == "torus":
        t = pv.ParametricTorus(texture_coordinates=True)
        return sg.capture(t, window_size=(SIZE, SIZE), camera="iso", supersample=2)
    if name == "sphere":
        s = pv.Sphere(theta_resolution=96, phi_resolution=96)
        return sg.capture(s, window_size=(SIZE, SIZE), camera="iso", supersample=2)
    if name == "stl":
        if not STL.exists():
            pytest.skip(f"{STL} is missing")
        return sg.capture(read_scene(STL)[0], window_size=(SIZE, SIZE), camera="iso", supersample=2)
    dem = load_jacksboro_dem()
    return birdseye_gbuffer(dem, window_size=(SIZE * 4 // 3, SIZE), vert_exag=2.0)


# input name -> (G-buffer, style options)
INPUTS = {
    "torus": ("torus", {}),
    "sphere": ("sphere", {}),
    "stl": ("stl", {}),
    "torus_behind": ("torus", {"light": BEHIND}),
    "terrain": ("terrain", {}),
}
DRAWN = sorted(name for name, s in STYLES.items() if s.draw is not None)
LINE_STYLES = {"drawing", "lines", "edgemap"}


def luminance(img: np.ndarray) -> np.ndarray:
    """Rec. 709 luminance of a picture as seen on white paper (RGBA composited over it)."""
    img = np.asarray(img, dtype=np.float32)
    if img.ndim == 2:
        return img
    rgb = img[..., :3]
    if img.shape[-1] == 4:
        a = img[..., 3:4]
        rgb = rgb * a + (1.0 - a)
    return rgb @ np.float32([0.2126, 0.7152, 0.0722])


def largest_solid_black(img: np.ndarray) -> int:
    """Pixels of the largest solid-black area (see the module notes)."""
    black = luminance(img) < BLACK
    solid = ndimage.binary_opening(black, SQUARE)
    labels, n = ndimage.label(solid, structure=SQUARE)
    return int(np.bincount(labels.ravel())[1:].max()) if n else 0


def test_the_measure_tells_areas_from_lines():
    img = np.ones((60, 60), np.float32)
    img[5, :] = 0.0  # a one-pixel line ...
    img[:, 7:9] = 0.0  # ... and a two-pixel one, crossing it
    img[20:50:4, 20:50] = 0.0  # hatching
    img[20:50, 20:50:4] = 0.0  # cross-hatching
    assert largest_solid_black(img) < 10
    img[30:40, 30:40] = 0.0  # a blob
    assert largest_solid_black(img) >= 100


def test_every_style_is_walked():
    # a new style is covered by being registered; these are the ones known today
    assert {"drawing", "enhance", "fig7", "gooch", "hatch", "lines", "toon"} <= set(DRAWN)


@pytest.mark.parametrize("inp", sorted(INPUTS))
@pytest.mark.parametrize("style", DRAWN)
def test_no_style_fills_an_area_solid_black(style, inp):
    key, options = INPUTS[inp]
    gb = gbuffer(key)
    img = STYLES[style].draw(gb, **options)
    cover = gb.downsample(gb.mask.astype(np.float32))
    n_object = int((cover > 0.5).sum())
    blob = largest_solid_black(img)
    print(f"{style} on {inp}: largest solid black {blob} px = {100 * blob / n_object:.3f} %")
    assert blob <= 0.005 * n_object
    if style in LINE_STYLES:
        assert blob <= 16, "a line drawing filled an area"


def test_hatch_keeps_strokes_in_the_darkest_tone():
    """Lit from behind, the torus is at the darkest tone everywhere: it stays cross-hatched
    (paper between the strokes), not black, and its inner profile is still drawn."""
    gb = gbuffer("torus")
    img = STYLES["hatch"].draw(gb, light=BEHIND)
    lum = luminance(img)
    inside = ndimage.binary_erosion(gb.downsample(gb.mask.astype(np.float32)) > 0.999, SQUARE, 3)
    assert 0.2 < lum[inside].mean() < 0.45  # dark, but with paper in it
    assert (lum[inside] > 0.9).mean() > 0.1  # paper between the strokes
