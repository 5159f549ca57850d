"""No style fills an area solid black (issue: "no black blobs in any style").

Every style of the registry with a drawing function is drawn on a few small inputs: a torus
with texture coordinates, a sphere, the shared STL part, the torus and the STL part lit from
behind (every visible face in shadow: the STL part's small bolt holes and thin fins, whose
outlines crowd into clumps on the darkest shade) and a bird's-eye terrain. A solid-black
area is a connected set of black pixels (luminance < 26/255) that contains 3 x 3 blocks of
black, i.e. the opening of the black pixels by a 3 x 3 square: lines up to two pixels wide,
hatching and cross-hatching are not areas however far they connect, a blob or a face filled
black is. The largest one must stay below 0.5 % of the object's pixels; line drawings must
have none at all beyond a few pixels (the lines of a drawing never fill an area).
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
from sciviz_gbuf.styles import STYLES, toon
from sciviz_gbuf.styles.illustration import thin_edge_map
from sciviz_gbuf.styles.tone import TOON_BASE, TOON_LEVELS, toon_shades
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
    if name.startswith("stl"):
        if not STL.exists():
            pytest.skip(f"{STL} is missing")
        side = int(name[3:] or SIZE)  # "stl240": the size where toon's bolt holes filled
        return sg.capture(read_scene(STL)[0], window_size=(side, side), camera="iso", supersample=2)
    dem = load_jacksboro_dem()
    return birdseye_gbuffer(dem, window_size=(SIZE * 4 // 3, SIZE), vert_exag=2.0)


# input name -> (G-buffer, style options)
INPUTS = {
    "torus": ("torus", {}),
    "sphere": ("sphere", {}),
    "stl": ("stl", {}),
    "torus_behind": ("torus", {"light": BEHIND}),
    "stl_behind": ("stl240", {"light": BEHIND}),
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


def test_toon_darkest_band_stays_apart_from_the_outline():
    """The darkest default band is light enough that a half-inked outline pixel over it is
    not black (``1 / k`` of the base was black there: outline and band merged)."""
    darkest = toon_shades(TOON_LEVELS)[0] * np.asarray(TOON_BASE)
    assert 0.5 * luminance(darkest[None, None, :])[0, 0] > BLACK
    gb = gbuffer("torus")
    img = toon(gb, light=BEHIND, edges=False)  # all in the darkest band
    inside = gb.downsample(gb.mask.astype(np.float32)) > 0.999
    assert luminance(img)[inside].min() > 2 * BLACK


def _ring(size: int = 40, r_out: float = 7.0, r_in: float = 2.0) -> np.ndarray:
    """Ink of a small hole's outline, thicker than the hole (a solid clump), and a line two
    pixels wide running into it from the left; and the disc the outline covers."""
    y, x = np.mgrid[:size, :size] - size / 2 + 0.5
    d = np.hypot(x, y)
    ink = np.clip(r_out + 0.5 - d, 0, 1) * np.clip(d - r_in + 0.5, 0, 1)
    ink[size // 2 - 1 : size // 2 + 1, : size // 2 - 5] = 1.0
    return ink.astype(np.float32), d < r_out


def test_thin_edge_map_keeps_a_skeleton_of_a_clump_and_leaves_lines_alone():
    emap = np.zeros((40, 40, 4), np.float32)
    emap[..., 3], disc = _ring()
    thin = thin_edge_map(emap, 1.0)
    over_dark = 0.25 * (1.0 - thin[..., 3])  # drawn black over a dark shade
    assert largest_solid_black(1.0 - emap[..., 3]) > 60  # the clump as drawn before
    assert largest_solid_black(over_dark) == 0
    kept = thin[..., 3] > 0.5
    assert 0 < (kept & disc).sum() < (emap[..., 3] > 0.5)[disc].sum() / 3
    # the line entering the clump stays connected to what is left of it
    labels, _ = ndimage.label(kept, structure=SQUARE)
    assert labels[20, 2] > 0 and (labels[disc] == labels[20, 2]).sum() > 5
    # lines thinner than a clump, or white inner edges, are not touched (the same array)
    lines = np.zeros((40, 40, 4), np.float32)
    lines[10:12, :, 3] = 1.0
    lines[20, :, 3] = 0.5
    lines[25:29, :, :3] = 1.0  # thick white inner edges: not dark ink
    assert thin_edge_map(lines, 1.0) is lines
    # dark inner edges are thinned with the profiles: drawn one over the other they add up
    both = np.zeros((40, 40, 4), np.float32)
    both[10:15, :, 0:3] = 0.5
    both[10:15, :, 3] = 0.5
    assert thin_edge_map(both, 1.0, inner_color=(1, 1, 1)) is both  # half ink each: a line
    dark = thin_edge_map(both, 1.0, inner_color=(0, 0, 0))
    assert 0 < (dark[..., 3] > 0).sum() < (both[..., 3] > 0).sum()
