"""Cast shadows, sky-view factor and openness: analytic walls, pillars, planes, valleys and
pits, and an independent brute-force numpy ray march."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters import _terrain_light_kernels as K
from sciviz_gbuf.filters import terrain_light as T
from sciviz_gbuf.filters.terrain_light import cast_shadows, openness, sky_view

# ---------------------------------------------------------------------------------------------
# independent reference: march every cell at once with numpy, no early exits


def ray_step(azimuth, dx, dy):
    """(rows, cols, metres) per step towards ``azimuth``: one pixel along the dominant axis."""
    east, north = np.sin(np.radians(azimuth)), np.cos(np.radians(azimuth))
    east = 0.0 if abs(east) < 1e-9 else east
    north = 0.0 if abs(north) < 1e-9 else north
    cols, rows = east / dx, -north / dy  # pixels per metre
    m = max(abs(cols), abs(rows))
    r, c = rows / m, cols / m
    r = float(np.round(r)) if abs(abs(r) - 1) < 1e-9 else r
    c = float(np.round(c)) if abs(abs(c) - 1) < 1e-9 else c
    return r, c, 1.0 / m


def reference_horizon(z, azimuth, dx, dy, max_dist=np.inf):
    """Largest (height - own height) / distance along each cell's ray (-inf if no sample)."""
    z = z.astype(np.float64)
    h, w = z.shape
    dr, dc, step = ray_step(azimuth, dx, dy)
    ii, jj = np.mgrid[0:h, 0:w]
    best = np.full((h, w), -np.inf)
    alive = np.ones((h, w), bool)
    k = 1
    while alive.any() and k <= h + w and k * step <= max_dist * (1 + 1e-12):
        r, c = ii + k * dr, jj + k * dc
        # positions within rounding of a cell are on it (a step of 0.5000000000000002 cells
        # lands 4e-16 beyond the first column after two steps), as in the kernels
        r = np.where(np.abs(r - np.round(r)) < 1e-9, np.round(r), r)
        c = np.where(np.abs(c - np.round(c)) < 1e-9, np.round(c), c)
        r0, c0 = np.floor(r).astype(int), np.floor(c).astype(int)
        fr, fc = r - r0, c - c0
        inside = (r0 >= 0) & (r0 < h) & (c0 >= 0) & (c0 < w)
        inside &= ((fr == 0) | (r0 + 1 < h)) & ((fc == 0) | (c0 + 1 < w))
        alive &= inside  # once outside, the ray never comes back
        r0c, c0c = np.clip(r0, 0, h - 1), np.clip(c0, 0, w - 1)
        r1c, c1c = np.clip(r0 + 1, 0, h - 1), np.clip(c0 + 1, 0, w - 1)
        a = z[r0c, c0c]
        b = np.where(fr > 0, z[r1c, c0c], np.where(fc > 0, z[r0c, c1c], a))
        f = np.where(fr > 0, fr, fc)
        v = np.where(f > 0, a + f * (b - a), a)
        t = (v - z) / (k * step)
        t = np.where(alive & np.isfinite(t), t, -np.inf)
        best = np.maximum(best, t)
        k += 1
    return best


def reference_shadows(z, azimuth, altitude, dx, dy):
    lit = reference_horizon(z, azimuth, dx, dy) <= np.tan(np.radians(altitude))
    return np.where(np.isnan(z), np.nan, lit.astype(np.float64))


def reference_sky_view(z, directions, radius, dx, dy):
    acc = np.zeros(z.shape)
    for k in range(directions):
        t = np.maximum(reference_horizon(z, 360.0 * k / directions, dx, dy, radius), 0.0)
        acc += np.sin(np.arctan(t))
    return np.where(np.isnan(z), np.nan, 1.0 - acc / directions)


def rough_terrain(shape, seed):
    rng = np.random.default_rng(seed)
    z = rng.normal(size=shape).cumsum(0).cumsum(1) * 0.3 + rng.normal(size=shape) * 2.0
    return z.astype(np.float32)


# ---------------------------------------------------------------------------------------------
# cast_shadows


@pytest.mark.parametrize("altitude", [0.5, 10.0, 45.0, 89.0, 90.0])
@pytest.mark.parametrize("azimuth", [0.0, 37.0, 135.0, 270.0])
def test_flat_plane_is_lit(altitude, azimuth):
    z = np.full((20, 30), 7.5, dtype=np.float32)
    np.testing.assert_array_equal(cast_shadows(z, azimuth=azimuth, altitude=altitude), 1.0)


def wall_scene(azimuth, height, dx, dy, n=160):
    """Flat ground with a wall across the middle, perpendicular to a cardinal sun."""
    z = np.zeros((n, n))
    mid = n // 2
    if azimuth in (0.0, 180.0):
        z[mid, :] = height
    else:
        z[:, mid] = height
    return z, mid


def shadow_run(shade, azimuth, mid):
    """Shadowed cells behind the wall (away from the sun) and in front of it, along the centre
    line through the wall."""
    line = shade[:, 5] if azimuth in (0.0, 180.0) else shade[5, :]
    # the sun in the north (0) or east (90) shadows higher rows / lower columns respectively
    away_is_higher = azimuth in (0.0, 270.0)
    behind = line[mid + 1 :] if away_is_higher else line[:mid][::-1]
    front = line[:mid] if away_is_higher else line[mid + 1 :]
    run = int(np.argmax(behind > 0.5)) if (behind > 0.5).any() else behind.size
    return run, int((behind[run:] < 0.5).sum()), int((front < 0.5).sum())


@pytest.mark.parametrize("azimuth", [0.0, 90.0, 180.0, 270.0])
@pytest.mark.parametrize("altitude", [20.0, 30.0, 45.0, 60.0])
@pytest.mark.parametrize(("dx", "dy"), [(1.0, 1.0), (2.0, 0.5)])
def test_wall_shadow_length(azimuth, altitude, dx, dy):
    height = 12.0
    z, mid = wall_scene(azimuth, height, dx, dy)
    shade = cast_shadows(z, dx=dx, dy=dy, azimuth=azimuth, altitude=altitude)
    cell = dy if azimuth in (0.0, 180.0) else dx
    expected = height / math.tan(math.radians(altitude)) / cell  # pixels
    run, stray_behind, stray_front = shadow_run(shade, azimuth, mid)
    assert abs(run - expected) <= 1.0
    assert stray_behind == 0  # one contiguous shadow, then lit ground
    assert stray_front == 0  # nothing is shadowed on the sun's side
    assert shade[mid if azimuth in (0.0, 180.0) else 5, 5 if azimuth in (0.0, 180.0) else mid] == 1


@pytest.mark.parametrize("z_factor", [0.5, 2.0, 3.0])
def test_z_factor_scales_shadow_length(z_factor):
    z, mid = wall_scene(270.0, 6.0, 1.0, 1.0)
    shade = cast_shadows(z, azimuth=270.0, altitude=30.0, z_factor=z_factor)
    run, _, _ = shadow_run(shade, 270.0, mid)
    assert abs(run - z_factor * 6.0 / math.tan(math.radians(30.0))) <= 1.0
    z2 = z * z_factor
    np.testing.assert_array_equal(shade, cast_shadows(z2, azimuth=270.0, altitude=30.0))


@pytest.mark.parametrize("method", ["sweep", "march"])
@pytest.mark.parametrize("azimuth", [0.0, 45.0, 90.0, 135.0, 200.0, 270.0, 315.0])
@pytest.mark.parametrize(("dx", "dy"), [(1.0, 1.0), (1.0, 2.0)])
def test_pillar_shadow_points_away_from_sun(azimuth, dx, dy, method):
    n, height, altitude = 61, 10.0, 35.0
    z = np.zeros((n, n))
    c = n // 2
    z[c, c] = height
    shade = cast_shadows(z, dx=dx, dy=dy, azimuth=azimuth, altitude=altitude, method=method)
    centres = azimuth % 90 == 0 or (dx == dy and azimuth % 45 == 0)
    rows, cols = np.nonzero(shade < 0.5)
    assert rows.size > 0
    east, north = (cols - c) * dx, -(rows - c) * dy
    az = math.radians(azimuth)
    along = -(east * math.sin(az) + north * math.cos(az))  # distance away from the sun
    across = east * math.cos(az) - north * math.sin(az)
    assert (along > 0).all()
    # a thin streak along azimuth + 180; off the axes the sweep's interpolated shadow surface
    # spreads it by up to a cell at its sides
    wide = 1.0 if centres or method == "march" else 2.0
    assert np.abs(across).max() <= wide * max(dx, dy)
    length = height / math.tan(math.radians(altitude))
    tol = max(dx, dy) * math.sqrt(2)
    if centres:
        # rays through cell centres see the pillar's full height: the exact length
        assert abs(along.max() - length) <= tol
    else:
        # between centres the one-cell pillar is blended with its neighbours: never longer
        assert along.max() <= length + tol
    assert shade[c, c] == 1.0


@pytest.mark.parametrize("method", ["sweep", "march"])
@pytest.mark.parametrize("azimuth", [20.0, 123.0, 200.0, 300.0])
def test_block_shadow_length_off_axis(azimuth, method):
    """A 5x5 block is wide enough that off-axis rays meet its full height; the sweep's
    shadow has the march's length (its lines carry the block's height undamped) and is at
    most a cell wider."""
    n, height, altitude = 81, 10.0, 30.0
    z = np.zeros((n, n))
    c = n // 2
    z[c - 2 : c + 3, c - 2 : c + 3] = height
    shade = cast_shadows(z, azimuth=azimuth, altitude=altitude, method=method)
    rows, cols = np.nonzero(shade < 0.5)
    az = math.radians(azimuth)
    east, north = cols - c, -(rows - c)
    along = -(east * math.sin(az) + north * math.cos(az))
    across = east * math.cos(az) - north * math.sin(az)
    wider = 1.0 if method == "sweep" else 0.0
    assert (along > -3).all() and np.abs(across).max() <= 2 * math.sqrt(2) + 1 + wider
    # the far end: the block's corner/edge (2 to 2.8 px from the centre) plus the shadow length
    reach = along.max() - height / math.tan(math.radians(altitude))
    assert 1.0 <= reach <= 2 * math.sqrt(2) + 1


@pytest.mark.parametrize("azimuth", [90.0, 270.0])
def test_tilted_plane_self_shadow_is_documented(azimuth):
    """Slopes facing away from a sun lower than the slope are shadowed by their own upslope
    (as documented), except the edge line towards the sun; gentler or sun-facing slopes are lit."""
    cols = np.arange(40.0)
    down_to_east = np.tile(-cols, (10, 1))  # slope 45 degrees, facing east
    sun_west = azimuth == 270.0
    steep = cast_shadows(down_to_east, azimuth=azimuth, altitude=30.0)
    if sun_west:  # facing away from a 30 degree sun: shadowed but for the west edge column
        np.testing.assert_array_equal(steep[:, 0], 1.0)
        np.testing.assert_array_equal(steep[:, 1:], 0.0)
        np.testing.assert_array_equal(cast_shadows(down_to_east, azimuth=270, altitude=50), 1)
    else:  # facing the sun
        np.testing.assert_array_equal(steep, 1.0)


def test_nodata_does_not_cast_and_stays_nan():
    z, mid = wall_scene(270.0, 10.0, 1.0, 1.0, n=40)
    z[:, mid] = np.nan
    z[3, 3] = np.inf
    before = z.copy()
    shade = cast_shadows(z, azimuth=270.0, altitude=30.0)
    np.testing.assert_array_equal(z, before)  # input not modified
    assert np.isnan(shade[:, mid]).all() and np.isnan(shade[3, 3])
    assert np.isnan(shade).sum() == 41
    np.testing.assert_array_equal(shade[~np.isnan(shade)], 1.0)
    mask = np.ones(z.shape, bool)
    mask[7, 9] = False
    assert np.isnan(cast_shadows(z, mask=mask)[7, 9])


def test_matches_rowwise_numpy_for_west_sun():
    z = rough_terrain((50, 70), 1)
    tan = math.tan(math.radians(25.0))
    blocked = np.zeros(z.shape, bool)
    for s in range(1, z.shape[1]):  # terrain s columns west higher than the ray at s metres
        blocked[:, s:] |= z[:, :-s].astype(np.float64) - z[:, s:] > s * tan
    np.testing.assert_array_equal(cast_shadows(z, azimuth=270.0, altitude=25.0), ~blocked)


@pytest.mark.parametrize(
    ("azimuth", "altitude", "dx", "dy"),
    [(315.0, 20.0, 1.0, 1.0), (10.0, 35.0, 2.0, 1.0), (123.0, 15.0, 0.7, 1.3), (250.0, 40.0, 1, 1)],
)
def test_matches_brute_force(azimuth, altitude, dx, dy):
    z = rough_terrain((37, 45), 2)
    z[5:8, 10:20] = np.nan
    got = cast_shadows(z, dx=dx, dy=dy, azimuth=azimuth, altitude=altitude, method="march")
    want = reference_shadows(z, azimuth, altitude, dx, dy)
    assert 0 < np.nanmean(want) < 1  # a mix of lit and shadowed cells
    np.testing.assert_array_equal(got, want)


def test_soft_shadows():
    z, mid = wall_scene(270.0, 20.0, 1.0, 1.0)
    hard = cast_shadows(z, azimuth=270.0, altitude=30.0)
    soft = cast_shadows(z, azimuth=270.0, altitude=30.0, sun_radius=3.0)
    line = soft[5, mid + 1 :]
    assert (np.diff(line) >= -1e-7).all()  # brightens away from the wall
    assert line[0] == 0.0 and line[-1] == 1.0
    assert ((line > 0.01) & (line < 0.99)).sum() >= 4  # a penumbra several cells wide
    # the disc's centre sits on the hard shadow's edge: about half lit there
    edge = int(np.argmax(hard[5, mid + 1 :] > 0.5))
    assert 0.2 < line[edge - 1] < 0.8 or 0.2 < line[edge] < 0.8
    tiny = cast_shadows(z, azimuth=270.0, altitude=30.0, sun_radius=1e-4)
    assert np.abs(tiny - hard).sum() <= 2
    np.testing.assert_array_equal(cast_shadows(np.zeros((5, 5)), sun_radius=5.0), 1.0)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"altitude": 0.0}, "altitude"),
        ({"altitude": -5.0}, "altitude"),
        ({"altitude": 90.5}, "altitude"),
        ({"azimuth": float("nan")}, "azimuth"),
        ({"dx": 0.0}, "dx"),
        ({"dy": -1.0}, "dy"),
        ({"z_factor": float("inf")}, "z_factor"),
        ({"sun_radius": -1.0}, "sun_radius"),
        ({"altitude": 10.0, "sun_radius": 11.0}, "sun_radius"),
        ({"mask": np.ones((2, 2), bool)}, "mask"),
        ({"method": "fast"}, "method"),
    ],
)
def test_cast_shadows_bad_parameters(kwargs, name):
    with pytest.raises(InputError, match=name):
        cast_shadows(np.zeros((4, 5)), **kwargs)


def test_bad_heights():
    for bad in (np.zeros(5), np.zeros((2, 3, 4)), np.array([["a", "b"]])):
        with pytest.raises(InputError, match="heights"):
            cast_shadows(bad)
        with pytest.raises(InputError, match="heights"):
            sky_view(bad)


grids = arrays(
    np.float64,
    st.tuples(st.integers(1, 9), st.integers(1, 9)),
    elements=st.one_of(st.floats(-50, 50), st.just(np.nan)),
)


@settings(max_examples=60, deadline=None)
@given(z=grids, azimuth=st.floats(0, 360), altitude=st.floats(1, 89))
# a sun a hair off north over a one-column grid: the ray must still be cardinal (found by CI)
@example(z=np.array([[1.0], [0.0]]), azimuth=1.8290039299158206e-10, altitude=1.0)
def test_cast_shadows_odd_inputs(z, azimuth, altitude):
    out = cast_shadows(z, azimuth=azimuth, altitude=altitude, method="march")
    assert out.shape == z.shape and out.dtype == np.float32
    np.testing.assert_array_equal(np.isnan(out), np.isnan(z))
    assert ((out[~np.isnan(out)] == 0) | (out[~np.isnan(out)] == 1)).all()
    np.testing.assert_array_equal(out, reference_shadows(z, azimuth, altitude, 1.0, 1.0))
    swept = cast_shadows(z, azimuth=azimuth, altitude=altitude)
    np.testing.assert_array_equal(np.isnan(swept), np.isnan(z))
    assert ((swept[~np.isnan(swept)] == 0) | (swept[~np.isnan(swept)] == 1)).all()


def _sweep_agrees_with_the_march(z, azimuth, altitude, dx=1.0, dy=1.0):
    """The sweep marks the reference march's shadows, but where the ray's horizon ties the
    sun's altitude within float32 rounding (the sweep accumulates in float32)."""
    got = cast_shadows(z, dx=dx, dy=dy, azimuth=azimuth, altitude=altitude)
    want = reference_shadows(z, azimuth, altitude, dx, dy)
    tan = math.tan(math.radians(altitude))
    with np.errstate(invalid="ignore"):
        tie = np.abs(reference_horizon(z, azimuth, dx, dy) - tan) <= 1e-4 * (1.0 + tan)
    bad = (got != want) & ~np.isnan(want) & ~tie
    assert not bad.any(), np.argwhere(bad)[:5]
    np.testing.assert_array_equal(np.isnan(got), np.isnan(want))


@settings(max_examples=80, deadline=None)
@given(
    z=grids,
    azimuth=st.sampled_from([0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0]),
    altitude=st.floats(1, 89),
)
def test_shadow_sweep_is_the_march_along_axes_and_diagonals(z, azimuth, altitude):
    """Rays along the rows, columns and (square cells) diagonals sample cell centres: the
    sweep's carried shadow surface is then exactly the march's maximum."""
    _sweep_agrees_with_the_march(z, azimuth, altitude)


@pytest.mark.parametrize("azimuth", [0.0, 90.0, 135.0, 315.0])
@pytest.mark.parametrize(("dx", "dy"), [(1.0, 1.0), (2.0, 0.5)])
def test_shadow_sweep_on_rough_terrain_along_axes(azimuth, dx, dy):
    if dx != dy and azimuth % 90:
        pytest.skip("diagonal rays sample cell centres only with square cells")
    z = rough_terrain((61, 83), 5)
    z[10:14, 30:50] = np.nan
    _sweep_agrees_with_the_march(z, azimuth, 25.0, dx, dy)


@pytest.mark.parametrize("azimuth", [20.0, 110.0, 200.0, 300.0, 333.0])
def test_shadow_sweep_off_axis_differs_only_at_shadow_edges(azimuth):
    """Off the axes a cell between two of the sweep's lines gets the interpolation of their
    shadow surfaces: its shadows differ from the march's on a few % of the cells of very
    rough terrain, next to a shadow edge of the march (on the Boulder SRTM tile, a real DEM,
    0.01-1 % of the cells, 82-99 % of them within one cell of an edge)."""
    from scipy import ndimage

    z = rough_terrain((120, 150), 7)
    sweep = cast_shadows(z, azimuth=azimuth, altitude=30.0)
    march = cast_shadows(z, azimuth=azimuth, altitude=30.0, method="march")
    lit, shade = march == 1, march == 0
    assert 0.1 < shade.mean() < 0.9
    edge_dist = np.where(
        lit, ndimage.distance_transform_edt(~shade), ndimage.distance_transform_edt(~lit)
    )
    differ = sweep != march
    assert differ.mean() < 0.05
    assert (edge_dist[differ] <= 6.0).all()
    assert (edge_dist[differ] <= 1.5).mean() > 0.95


# ---------------------------------------------------------------------------------------------
# sky_view


def test_sky_view_flat_plane():
    np.testing.assert_allclose(sky_view(np.full((30, 30), 3.0)), 1.0, atol=1e-6)


def v_valley_expected(slope, directions):
    """A long N-S V-valley z = slope * |east|: from the floor, the horizon in direction phi is
    atan(slope * |sin phi|) at every distance."""
    phi = np.radians(360.0 * np.arange(directions) / directions)
    return 1.0 - np.mean(np.sin(np.arctan(slope * np.abs(np.sin(phi)))))


@pytest.mark.parametrize("directions", [4, 8, 16, 7])
@pytest.mark.parametrize(("dx", "dy"), [(1.0, 1.0), (2.0, 1.0), (1.0, 3.0)])
def test_sky_view_v_valley_floor(directions, dx, dy):
    slope = 0.8
    n = 61
    c = n // 2
    east = (np.arange(n) - c) * dx
    z = np.tile(slope * np.abs(east), (n, 1))
    svf = sky_view(z, dx=dx, dy=dy, directions=directions, radius=8.0 * max(dx, dy))
    np.testing.assert_allclose(svf[c, c], v_valley_expected(slope, directions), atol=1e-3)
    # along the whole floor away from the north/south edges
    np.testing.assert_allclose(svf[10:-10, c], v_valley_expected(slope, directions), atol=1e-3)


def test_sky_view_deeper_trench_is_darker():
    n = 41
    east = np.abs(np.arange(n) - n // 2).astype(float)
    values = [sky_view(np.tile(s * east, (n, 1)), radius=10.0)[20, 20] for s in (0.2, 0.5, 1, 3)]
    assert np.all(np.diff(values) < 0)
    assert values[-1] < 0.5


def test_sky_view_peak_is_one_pit_is_less():
    n = 41
    rows, cols = np.mgrid[0:n, 0:n] - n // 2
    r = np.hypot(rows, cols)
    np.testing.assert_allclose(sky_view(-0.7 * r)[20, 20], 1.0, atol=1e-6)  # cone peak
    ridge = -0.9 * np.abs(cols).astype(float)
    np.testing.assert_allclose(sky_view(ridge)[5:-5, 20], 1.0, atol=1e-6)  # convex ridge
    pit = sky_view(0.7 * r, radius=15.0)[20, 20]
    exact = 1.0 - math.sin(math.atan(0.7))
    # linear interpolation across a cone only over-estimates its heights: a bit darker
    assert exact - 0.02 < pit <= exact + 1e-6


def test_sky_view_matches_brute_force():
    z = rough_terrain((33, 40), 3)
    z[10:12, 5:9] = np.nan
    for directions, radius, dx, dy in ((16, 12.0, 1.0, 1.0), (9, 20.0, 1.5, 0.8)):
        got = sky_view(z, dx=dx, dy=dy, directions=directions, radius=radius)
        want = reference_sky_view(z, directions, radius, dx, dy)
        np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
        np.testing.assert_allclose(got, want, atol=2e-6, equal_nan=True)
        assert np.nanmin(got) < 0.9


def test_sky_view_nodata():
    z = np.zeros((31, 41))
    z[:, 20] = 50.0  # a tall wall 5 m east of the cell (15, 15)
    walled = sky_view(z, directions=8, radius=10.0)
    assert walled[15, 15] < 0.9
    z[:, 20] = np.nan  # as nodata it must not block
    z[2, 3] = -np.inf
    before = z.copy()
    svf = sky_view(z, directions=8, radius=10.0)
    np.testing.assert_array_equal(z, before)
    np.testing.assert_array_equal(np.isnan(svf), ~np.isfinite(z))
    np.testing.assert_allclose(svf[~np.isnan(svf)], 1.0, atol=1e-6)
    mask = np.ones(z.shape, bool)
    mask[4, 4] = False
    assert np.isnan(sky_view(z, mask=mask)[4, 4])


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"directions": 0}, "directions"),
        ({"directions": 2.5}, "directions"),
        ({"directions": True}, "directions"),
        ({"radius": 0.0}, "radius"),
        ({"radius": float("nan")}, "radius"),
        ({"dx": float("inf")}, "dx"),
        ({"z_factor": float("nan")}, "z_factor"),
        ({"mask": np.ones((4, 4), bool)}, "mask"),
    ],
)
def test_sky_view_bad_parameters(kwargs, name):
    with pytest.raises(InputError, match=name):
        sky_view(np.zeros((4, 5)), **kwargs)


@settings(max_examples=60, deadline=None)
@given(z=grids, directions=st.integers(1, 12), radius=st.floats(0.5, 12))
def test_sky_view_odd_inputs(z, directions, radius):
    out = sky_view(z, directions=directions, radius=radius)
    assert out.shape == z.shape and out.dtype == np.float32
    np.testing.assert_array_equal(np.isnan(out), np.isnan(z))
    valid = out[~np.isnan(out)]
    assert ((valid >= 0) & (valid <= 1)).all()
    want = reference_sky_view(z, directions, radius, 1.0, 1.0)
    np.testing.assert_allclose(out, want, atol=2e-6, equal_nan=True)


# ---------------------------------------------------------------------------------------------
# openness


def reference_openness(z, directions, radius, dx, dy):
    """Positive openness from the brute-force horizons: 90 - atan(t) per direction, 90 where a
    ray has no sample, NaN at nodata."""
    acc = np.zeros(z.shape)
    for k in range(directions):
        t = reference_horizon(z, 360.0 * k / directions, dx, dy, radius)
        acc += np.where(np.isfinite(t), 90.0 - np.degrees(np.arctan(t)), 90.0)
    return np.where(np.isnan(z), np.nan, acc / directions)


@pytest.mark.parametrize("directions", [8, 16, 32])
@pytest.mark.parametrize(("sx", "sy"), [(0.0, 0.0), (0.3, 0.1), (-1.5, 2.0)])
def test_openness_of_a_plane_is_90_degrees(directions, sx, sy):
    y, x = np.mgrid[0:41, 0:41].astype(np.float64)
    z = sx * x + sy * y
    inner = (slice(10, 31), slice(10, 31))  # every ray reaches the radius inside the grid
    for kind in ("positive", "negative"):
        o = openness(z, kind=kind, directions=directions, radius=8.0)
        np.testing.assert_allclose(o[inner], 90.0, atol=1e-4)


@pytest.mark.parametrize("slope", [0.2, 0.7, 3.0])
def test_openness_at_a_cone_apex(slope):
    """Eight directions on a square grid sample the cone on cells: the apex of a peak sees
    ``-atan(slope)`` all round, a pit's ``+atan(slope)``."""
    y, x = np.mgrid[-20:21, -20:21].astype(np.float64)
    r = np.hypot(x, y)
    a = math.degrees(math.atan(slope))
    peak = openness(-slope * r, directions=8, radius=10.0)[20, 20]
    pit = openness(slope * r, directions=8, radius=10.0)[20, 20]
    assert peak == pytest.approx(90.0 + a, abs=1e-4)
    assert pit == pytest.approx(90.0 - a, abs=1e-4)
    # negative openness is the positive openness of the inverted terrain
    assert openness(slope * r, kind="negative", directions=8, radius=10.0)[20, 20] == peak


def test_openness_ridges_high_valleys_low():
    x = np.mgrid[0:40, 0:40][1].astype(np.float64)
    ridge = -np.abs(x - 20.0)  # a ridge along column 20, planes either side
    o = openness(ridge, radius=10.0)
    neg = openness(ridge, kind="negative", radius=10.0)
    assert o[20, 20] > 100.0 and neg[20, 20] < 80.0  # the crest: open above, closed below
    assert o[20, 10] == pytest.approx(90.0, abs=1e-4)  # a flank within reach is a plane


def test_openness_matches_brute_force():
    z = rough_terrain((37, 45), 3)
    cases = ((1.0, 1.0, 16, 9.0), (2.0, 1.0, 8, 11.0), (1.0, 3.0, 12, 14.0))
    for dx, dy, directions, radius in cases:
        for kind, zz in (("positive", z), ("negative", -z)):
            got = openness(z, kind=kind, dx=dx, dy=dy, directions=directions, radius=radius)
            want = reference_openness(zz, directions, radius, dx, dy)
            np.testing.assert_allclose(got, want, atol=2e-4)


def test_openness_nodata():
    z = rough_terrain((30, 30), 5)
    z[10:14, 8:20] = np.nan
    got = openness(z, directions=8, radius=6.0)
    assert np.isnan(got[10:14, 8:20]).all() and np.isfinite(got[~np.isnan(z)]).all()
    np.testing.assert_allclose(got, reference_openness(z, 8, 6.0, 1.0, 1.0), atol=2e-4)
    lone = np.full((5, 5), np.nan)
    lone[2, 2] = 4.0  # no sample in any direction: a horizontal horizon all round
    assert openness(lone)[2, 2] == 90.0
    mask = np.ones((9, 9), bool)
    mask[4, 4] = False
    assert np.isnan(openness(np.zeros((9, 9)), mask=mask)[4, 4])


def test_openness_does_not_modify_its_input():
    z = rough_terrain((20, 24), 7).astype(np.float64)
    before = z.copy()
    openness(z, kind="negative", radius=5.0)
    np.testing.assert_array_equal(z, before)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"kind": "both"}, "kind"),
        ({"kind": np.array([2.0, 3.0])}, "kind"),
        ({"radius": -1.0}, "radius"),
        ({"radius": 1e7}, "radius"),
        ({"directions": 0}, "directions"),
        ({"dx": 0.0}, "dx"),
        ({"z_factor": np.inf}, "z_factor"),
    ],
)
def test_openness_bad_parameters(kwargs, name):
    with pytest.raises(InputError, match=name):
        openness(np.zeros((4, 5)), **kwargs)


@given(
    z=arrays(np.float64, st.tuples(st.integers(1, 9), st.integers(1, 9)),
             elements=st.floats(-1e3, 1e3) | st.just(np.nan)),
    directions=st.integers(1, 12),
    radius=st.floats(0.5, 12.0),
)  # fmt: skip
@settings(max_examples=60, deadline=None)
def test_openness_odd_inputs(z, directions, radius):
    got = openness(z, directions=directions, radius=radius)
    assert got.shape == z.shape and got.dtype == np.float32
    assert np.array_equal(np.isnan(got), np.isnan(z))
    ok = ~np.isnan(got)
    assert ((got[ok] >= 0.0) & (got[ok] <= 180.0)).all()
    # against the float64 statement on the float32 heights the operator works on: at -310.65
    # m and -310 m a cell apart the height's own rounding (3e-5 m) is 1e-3 degrees
    z32 = z.astype(np.float32).astype(np.float64)
    np.testing.assert_allclose(got, reference_openness(z32, directions, radius, 1.0, 1.0),
                               atol=2e-4)  # fmt: skip


# ---------------------------------------------------------------- row march vs per-cell march


def _rough(h, w, seed=0):
    rng = np.random.default_rng(seed)
    z = np.cumsum(np.cumsum(rng.standard_normal((h, w)), 0), 1).astype(np.float32)
    z[rng.random(z.shape) < 0.02] = np.nan
    z[h // 3 : h // 3 + 9, w // 2 : w // 2 + 14] = np.nan
    return z


@pytest.mark.parametrize(
    ("directions", "dx", "dy", "radius"),
    [(16, 30.0, 30.0, None), (5, 30.0, 18.0, 700.0), (36, 10.0, 25.0, 250.0), (1, 1.0, 1.0, 3.0)],
)
def test_row_march_equals_the_per_cell_march(directions, dx, dy, radius):
    """The vectorised row march takes the per-cell march's samples: the same sky-view factor
    (within float32 rounding) and openness (within 1e-4 degrees), nodata at the same cells."""
    z = T._prepare(_rough(97, 131), dx, dy, 1.0, None)
    r = T.default_sky_radius(dx, dy) if radius is None else radius
    rays = T._sky_rays(z, dx, dy, directions, r)
    for fast, slow, tol in ((K.sky_view_kernel, K.sky_view_reference_kernel, 1e-6),
                            (K.openness_kernel, K.openness_reference_kernel, 1e-4)):  # fmt: skip
        a, b = fast(z, *rays), slow(z, *rays)
        np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
        np.testing.assert_allclose(a, b, atol=tol, rtol=0)
        assert np.nanstd(b) > 0.01  # the rays see something


@settings(max_examples=40, deadline=None)
@given(
    arrays(
        np.float32,
        st.tuples(st.integers(1, 9), st.integers(1, 9)),
        elements=st.one_of(st.floats(-50, 50, width=32), st.just(np.nan)),
    ),
    st.integers(1, 12),
    st.floats(0.5, 12.0),
)
def test_row_march_on_odd_grids(z, directions, radius):
    zz = T._prepare(z, 1.0, 1.5, 1.0, None)
    rays = T._sky_rays(zz, 1.0, 1.5, directions, radius)
    for fast, slow, tol in ((K.sky_view_kernel, K.sky_view_reference_kernel, 1e-6),
                            (K.openness_kernel, K.openness_reference_kernel, 1e-4)):  # fmt: skip
        a, b = fast(zz, *rays), slow(zz, *rays)
        np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
        np.testing.assert_allclose(a, b, atol=tol, rtol=0)


# ------------------------------------------- fused row march (four steps at a time) vs one step


def _spectral(h, w, beta, seed, relief=1500.0):
    """Fractal heights with a 1/f^beta power spectrum (Hurst exponent (beta - 2) / 2)."""
    rng = np.random.default_rng(seed)
    f = np.hypot(np.fft.fftfreq(h)[:, None], np.fft.rfftfreq(w)[None, :])
    f[0, 0] = 1.0
    amp = f ** (-beta / 2.0)
    amp[0, 0] = 0.0
    z = np.fft.irfft2(amp * np.exp(2j * np.pi * rng.random(amp.shape)), s=(h, w))
    return ((z - z.min()) / (z.max() - z.min()) * relief).astype(np.float32)


def _canyons(h, w):
    """Steep terrain: a deep V canyon, a slot with vertical walls and a cliff step."""
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    z = 400.0 + 6.0 * np.abs(x - 0.4 * y - w / 3)  # a V canyon, walls ~80 degrees at 1 m
    z[:, w // 2 : w // 2 + 3] -= 300.0  # a slot 3 cells wide
    z[h // 2 :, :] += 250.0  # a cliff across the grid
    return z.astype(np.float32)


def _fused_and_march_agree(z, dx, dy, directions, radius):
    """The fused route (the kernels the public functions call) equals the one-step row
    march it replaced bit for bit: sky-view factor and openness of the terrain and of the
    inverted terrain (negative openness), NaN at the same cells."""
    zz = T._prepare(z, dx, dy, 1.0, None)
    r = T.default_sky_radius(dx, dy) if radius is None else radius
    for grid in (zz, -zz):
        rays = T._sky_rays(grid, dx, dy, directions, r, local=False)
        for fast, march in ((K.sky_view_kernel, K.sky_view_march_kernel),
                            (K.openness_kernel, K.openness_march_kernel)):  # fmt: skip
            a, b = fast(grid, *rays), march(grid, *rays)
            np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
            np.testing.assert_array_equal(a, b)  # the same bits (NaN where nodata)


@pytest.mark.parametrize("beta", [2.2, 2.8, 3.4])
@pytest.mark.parametrize(("dx", "dy"), [(30.0, 30.0), (30.0, 18.0), (10.0, 25.0)])
def test_fused_march_on_fractal_terrain(beta, dx, dy):
    z = _spectral(150, 233, beta, seed=int(beta * 10))
    _fused_and_march_agree(z, dx, dy, 16, None)


@pytest.mark.parametrize("case", ["integer", "holes", "canyons"])
def test_fused_march_on_hard_terrain(case):
    z = _spectral(140, 210, 2.6, seed=4)
    if case == "integer":
        z = np.round(z)  # ties between samples and heights everywhere
    elif case == "holes":
        rng = np.random.default_rng(9)
        z[rng.random(z.shape) < 0.03] = np.nan
        z[30:60, 80:150] = np.nan
        z[:, -3:] = np.nan
    else:
        z = _canyons(140, 210)
    for directions, radius, dx, dy in ((16, None, 1.0, 1.0), (7, 40.0, 1.0, 0.6), (32, 25.0, 2, 1)):
        _fused_and_march_agree(z, dx, dy, directions, radius)


@pytest.mark.parametrize(
    "name",
    ["hugo_site.asc", "pre_runout_DEM.asc", "SRTMGL3_40.09_-105.55_40.21_-105.35.asc",
     "N10W110.hgt"],
)  # fmt: skip
def test_fused_march_on_real_dems(name):
    from tests.helpers.paths import shared_dem

    dem = shared_dem(name)
    z = np.where(dem.mask, dem.heights, np.nan) if dem.mask is not None else dem.heights
    z = np.asarray(z, dtype=np.float32)
    dx, dy = (abs(float(v)) for v in dem.pixel_size)  # metres, geographic grids too
    if z.shape[0] > 400:  # the 1201^2 SRTM tile: a crop keeps the test short
        z = z[200:520, 300:700]
    _fused_and_march_agree(z, dx, dy, 16, None)


@settings(max_examples=60, deadline=None)
@given(
    arrays(
        np.float32,
        st.tuples(st.integers(1, 12), st.integers(1, 12)),
        elements=st.one_of(st.floats(-50, 50, width=32), st.just(np.nan)),
    ),
    st.integers(1, 16),
    st.floats(0.5, 14.0),
    st.sampled_from([(1.0, 1.0), (1.0, 1.5), (0.7, 0.3)]),
)
@example(np.full((5, 9), np.nan, np.float32), 8, 6.0, (1.0, 1.0))  # all nodata
@example(np.full((9, 9), 3.0, np.float32), 16, 14.0, (1.0, 1.0))  # constant
def test_fused_march_on_odd_grids(z, directions, radius, cells):
    _fused_and_march_agree(z, *cells, directions, radius)
