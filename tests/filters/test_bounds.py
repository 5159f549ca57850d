"""Upper bounds of every size-like parameter (issue 20, item 7), and the hypothesis acceptance:
every public filter and style, with random parameters at their bounds and beyond (huge,
negative, NaN, inf, strings, bools, arrays where a number is expected), on small inputs,
returns a result of the right shape or raises InputError, never another exception.

The filters are walked from ``sciviz_gbuf.filters.__all__`` (registry entries by what they
take; the others through ``OTHER_FILTERS``) and the styles from ``STYLES``, so a new filter or
style is fuzzed as soon as it is public (or this test says how to call it is missing).
"""

from __future__ import annotations

import dataclasses
import inspect

import numpy as np
import pytest
import pyvista as pv
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import sciviz_gbuf.filters as F
from sciviz_gbuf import _validate
from sciviz_gbuf._validate import LIMITS
from sciviz_gbuf.core.capture import capture
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters.bands import band_tables
from sciviz_gbuf.filters.registry import FILTERS
from sciviz_gbuf.styles import STYLES, illustrate, line_drawing, photocopy

N = 16
_Y, _X = np.mgrid[0:N, 0:N].astype(np.float32)
FIELD = (np.sin(_X / 3.0) * 4.0 + _Y * 0.5).astype(np.float32)  # a small height field
NORMALS = np.dstack([np.zeros((N, N)), np.zeros((N, N)), np.ones((N, N))]).astype(np.float32)


@pytest.fixture(scope="module")
def gb():
    """A tiny supersampled capture with texture coordinates (every style can draw it) and the
    surfaces behind (hidden_edges)."""
    torus = pv.ParametricTorus(texture_coordinates=True)
    return capture(torus, window_size=(12, 10), camera="iso", supersample=2, layers=2)


def _array_call(entry):
    image = NORMALS if entry.components == 3 else FIELD
    extra = {"interval": 1.0} if entry.needs_levels else {}
    return lambda gb, **kw: entry.func(image, **{**extra, **kw}), (N, N)


def _composite(gb, **kw):
    tables = band_tables(
        FIELD.ravel(), interval=2.0, levels=None, base=0.0, cmap=None,
        vmin=None, vmax=None, sea_level=None, sea_cmap=None,
    )  # fmt: skip
    return F.composite_map(FIELD, **{"tables": tables, **kw})


def _enhance(gb, **kw):
    return F.enhance(np.full((N, N), 0.5), np.zeros((N, N, 4)), **kw)


def _suppress(gb, **kw):
    return F.suppress_zeroth_order(FIELD * 0.01, FIELD * 0.1, **kw)


# Public filters that are not one-image-to-one-image (not in the registry): how to call them
# on a small input and the leading shape of their result (None: not an image).
OTHER_FILTERS = {
    "enhance": (_enhance, (N, N)),
    "profile_and_crease_edges": (lambda gb, **kw: F.profile_and_crease_edges(gb, **kw)[1], "gb"),
    "suppress_zeroth_order": (_suppress, (N, N)),
    "composite_map": (_composite, (N, N)),
    "contour_polylines": (
        lambda gb, **kw: F.contour_polylines(FIELD, **({"interval": 1.0} | kw)),
        None,
    ),
    "contour_line_parameters": (
        lambda gb, **kw: F.contour_line_parameters(**({"interval": 1.0} | kw)),
        None,
    ),
    "fill_nodata_ring": (lambda gb, **kw: F.fill_nodata_ring(FIELD, **kw), (N, N)),
    "modulated_hatching": (
        lambda gb, **kw: F.modulated_hatching(FIELD, np.full(FIELD.shape, 0.7), **kw),
        (N, N),
    ),
    "band_heights": (
        lambda gb, **kw: F.band_heights(FIELD, **({"band_interval": 2.0} | kw)),
        (N, N),
    ),
    "highlight_lines": (lambda gb, **kw: F.highlight_lines(gb, **kw), "gb"),
    "polylines_to_geojson": (lambda gb, **kw: F.polylines_to_geojson([], **kw), None),
    "vectorize": (lambda gb, **kw: F.vectorize(np.abs(np.sin(FIELD)), **kw), None),
    "edge_strokes": (lambda gb, **kw: F.edge_strokes(gb, **kw), None),
    "hidden_edges": (lambda gb, **kw: F.hidden_edges(gb, **kw), "gb"),
    "bridge": (
        lambda gb, **kw: F.bridge([F.Stroke(np.eye(2), 1.0, "x")] * 2, **({"gap": 3.0} | kw)),
        None,
    ),
    "dash_pieces": (lambda gb, **kw: F.dash_pieces(F.Stroke(np.eye(2), 1.0, "x", **kw)), None),
    "draw_strokes": (
        lambda gb, **kw: F.draw_strokes(
            [F.Stroke(np.eye(2), 1.0, "x")], **({"shape": (N, N)} | kw)
        ),
        None,
    ),
    "paint_strokes": (
        lambda gb, **kw: F.paint_strokes(
            [F.Stroke(np.eye(2), 1.0, "x")], **({"background": np.ones((N, N))} | kw)
        ),
        None,
    ),
    "simplify": (lambda gb, **kw: F.simplify(np.column_stack([_X[0], FIELD[0]]), **kw), None),
}
# The parameters of a filter whose options are passed on to another function.
OPTION_TARGETS = {"highlight_lines": F.reflection_lines}


def filter_calls():
    """name -> (call(gb, **params), expected leading shape, fuzzable parameter names)."""
    calls = {}
    for name in F.__all__:
        obj = getattr(F, name)
        if not inspect.isfunction(obj):
            continue  # colour maps, ContourPolyline
        if name in FILTERS:
            entry = FILTERS[name]
            if entry.takes == "gbuffer":
                call, shape = (lambda f: lambda gb, **kw: f(gb, **kw))(entry.func), "gb"
            else:
                call, shape = _array_call(entry)
        else:
            assert name in OTHER_FILTERS, f"add {name} to OTHER_FILTERS (how to call it)"
            call, shape = OTHER_FILTERS[name]
        target = OPTION_TARGETS.get(name, obj)
        params = [
            p.name
            for p in inspect.signature(target).parameters.values()
            if p.kind is p.KEYWORD_ONLY
            or (p.default is not p.empty and p.kind is not p.VAR_KEYWORD)
        ]
        if name in OPTION_TARGETS:
            params = [p for p in params if p != "mode"]
        calls[name] = (call, shape, params)
    return calls


def style_calls():
    """style name -> (draw, fuzzable parameter names), from the registry."""
    calls = {}
    for name, style in STYLES.items():
        if style.draw is None:
            continue  # overlay-only
        sig = inspect.signature(style.draw).parameters
        params = [p.name for p in sig.values() if p.kind is p.KEYWORD_ONLY]
        if any(p.kind is p.VAR_KEYWORD for p in sig.values()):
            # the illustrate styles and drawing pass their options on
            target = line_drawing if name == "drawing" else illustrate
            params += [
                p.name
                for p in inspect.signature(target).parameters.values()
                if p.kind is p.KEYWORD_ONLY and p.name not in ("style", "combo")
            ]
        calls[name] = (style.draw, sorted(set(params)))
    return calls


FILTER_CALLS = filter_calls()
STYLE_CALLS = style_calls()

_BOUNDS = sorted({float(v) for v in LIMITS.values()})
_SPECIAL = [
    0, 1, -1, 2, 3.5, 0.5, 1e-300, 1e4, 1e6, 10**6, 10**9, 1e300, -1e300,
    float("nan"), float("inf"), -float("inf"), np.float32("nan"), np.int64(7),
    True, False, None, "1", "abc", b"x", "", [], [1.0], [1.0, 2.0, 3.0], (0.0, 0.0, 1.0),
    np.array([2.0, 3.0]), np.zeros((2, 2)), np.zeros((N, N), bool), {"a": 1},
    np.linspace(100.0, 200.0, int(LIMITS["levels"]) + 1),  # one level too many
    *_BOUNDS, *(b + 1 for b in _BOUNDS), *(b * 8 + 1 for b in _BOUNDS), *(-b for b in _BOUNDS),
]  # fmt: skip
NASTY = st.one_of(
    st.sampled_from(_SPECIAL),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(10**12), 10**12),
    st.lists(st.floats(-1e3, 1e3), max_size=4),
)


# the module's G-buffer is made once and only read
FIXTURE_OK = [HealthCheck.function_scoped_fixture]


def _check(result, shape, gb) -> None:
    if shape is None:
        return
    # G-buffer filters: the output size (reflection_angle: the buffer's own size)
    wants = (tuple(gb.output_shape), tuple(gb.shape)) if shape == "gb" else (tuple(shape),)
    assert isinstance(result, np.ndarray), type(result)
    assert result.shape[:2] in wants, (result.shape, wants)


def _try(call, gb, params, shape):
    try:
        result = call(gb, **params)
    except InputError as exc:
        assert "\n" not in str(exc), str(exc)  # one line
        return
    _check(result, shape, gb)


@pytest.mark.parametrize("name", sorted(FILTER_CALLS))
@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(data=st.data())
def test_filters_return_or_raise_input_error(gb, name, data):
    call, shape, params = FILTER_CALLS[name]
    if not params:
        _try(call, gb, {}, shape)
        return
    chosen = data.draw(st.lists(st.sampled_from(params), min_size=1, max_size=3, unique=True))
    values = {p: data.draw(NASTY, label=p) for p in chosen}
    _try(call, gb, values, shape)


@pytest.mark.parametrize("name", sorted(STYLE_CALLS))
@settings(
    max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(data=st.data())
def test_styles_return_or_raise_input_error(gb, name, data):
    draw, params = STYLE_CALLS[name]
    chosen = data.draw(st.lists(st.sampled_from(params), min_size=1, max_size=3, unique=True))
    values = {p: data.draw(NASTY, label=p) for p in chosen}
    _try(draw, gb, values, "gb")


@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_photocopy_returns_or_raises_input_error(data):
    params = ["copies", "blur", "pivot", "contrast", "noise", "seed"]
    chosen = data.draw(st.lists(st.sampled_from(params), min_size=1, max_size=3, unique=True))
    values = {p: data.draw(NASTY, label=p) for p in chosen}
    _try(lambda gb, **kw: photocopy(np.full((N, N), 0.5), **kw), None, values, (N, N))


# ----------------------------------------------------------------------- each bound, by name
def _filter(name):
    return FILTER_CALLS[name][0]


LINE_WIDTH = LIMITS["line_width"]
BEYOND = [
    ("edge_map", {"width": 1e4}, "width"),
    ("profile_edges", {"width": LINE_WIDTH + 1}, "width"),
    ("crease_edges", {"width": LINE_WIDTH + 1}, "width"),
    ("internal_edges", {"width": LINE_WIDTH + 1}, "width"),
    ("id_edges", {"width": LINE_WIDTH + 1}, "width"),
    ("contour_lines", {"width": LINE_WIDTH * LIMITS["supersample"] + 1}, "width"),
    (
        "contour_lines",
        {"levels": np.linspace(100, 200, 10**6), "interval": None},
        "at most 100000",
    ),
    ("contour_lines", {"c_dense": 1.0, "dense_spacing": 1e6}, "dense_spacing"),
    ("contour_lines", {"major_interval": 5.0, "major_width": 1e4}, "major_width"),
    ("hatching", {"spacing": 1e6}, "spacing"),
    ("hatching", {"width": 1e4}, "width"),
    ("modulated_hatching", {"spacing": 1e6}, "spacing"),
    ("modulated_hatching", {"width": 1e4}, "width"),
    ("contour_polylines", {"levels": np.linspace(100, 200, 10**6), "interval": None}, "levels"),
    ("contour_polylines", {"interval": 1e-9}, "levels"),
    ("color_bands", {"levels": np.linspace(0, 10, 5000), "interval": None}, "levels"),
    ("sky_view", {"directions": 10**6}, "directions"),
    ("sky_view", {"directions": LIMITS["directions"] + 1}, "directions"),
    ("sky_view", {"radius": 1e6}, "radius"),
    ("openness", {"directions": LIMITS["directions"] + 1}, "directions"),
    ("openness", {"radius": 1e6}, "radius"),
    ("texture_shade", {"detail": 2.5}, "detail"),
    ("local_relief", {"radius": 1e9}, "radius"),
    ("reflection_lines", {"stripes": 1e9}, "stripes"),
    ("reflection_lines", {"width": 1e4}, "width"),
    ("isophotes", {"width": 1e4}, "width"),
    ("isophotes", {"interval": 1e-9}, "interval"),
    ("isophotes", {"levels": np.linspace(-1, 1, 10**6)}, "levels"),
]


@pytest.mark.parametrize(("name", "params", "word"), BEYOND, ids=lambda v: str(v)[:30])
def test_beyond_a_bound_is_refused_by_name(gb, name, params, word):
    with pytest.raises(InputError, match=word):
        _filter(name)(gb, **params)


AT_BOUND = [
    ("edge_map", {"width": LINE_WIDTH}),
    ("profile_edges", {"width": LINE_WIDTH}),
    ("contour_lines", {"width": LINE_WIDTH * LIMITS["supersample"]}),
    ("contour_lines", {"levels": np.linspace(-50, 50, int(LIMITS["levels"])), "interval": None}),
    ("hatching", {"spacing": LIMITS["spacing"] * LIMITS["supersample"]}),
    ("sky_view", {"directions": int(LIMITS["directions"]), "radius": LIMITS["reach"]}),
    ("openness", {"directions": int(LIMITS["directions"]), "radius": LIMITS["reach"]}),
    ("texture_shade", {"detail": 2.0}),
    ("local_relief", {"radius": LIMITS["reach"]}),
    ("reflection_lines", {"stripes": LIMITS["levels"], "width": LINE_WIDTH}),
    ("isophotes", {"width": LINE_WIDTH}),
]


@pytest.mark.parametrize(("name", "params"), AT_BOUND, ids=lambda v: str(v)[:30])
def test_at_a_bound_is_accepted(gb, name, params):
    call, shape, _ = FILTER_CALLS[name]
    _check(call(gb, **params), shape, gb)


def test_style_bounds(gb):
    draw = {name: d for name, (d, _) in STYLE_CALLS.items()}
    with pytest.raises(InputError, match="levels"):
        draw["toon"](gb, levels=int(LIMITS["shade_levels"]) + 1)
    with pytest.raises(InputError, match="angles"):
        draw["hatch"](gb, angles=np.zeros(int(LIMITS["families"]) + 1))
    for style, param in (("hatch", "spacing"), ("hatch", "max_width"), ("gooch", "width")):
        with pytest.raises(InputError, match=param):
            draw[style](gb, **{param: 1e6})
    with pytest.raises(InputError, match="copies"):
        photocopy(np.ones((4, 4)), copies=int(LIMITS["copies"]) + 1)
    with pytest.raises(InputError, match="blur"):
        photocopy(np.ones((4, 4)), blur=1e6)
    assert draw["toon"](gb, levels=int(LIMITS["shade_levels"])).shape[:2] == gb.output_shape


def test_downsample_checks_its_supersample(gb):
    odd = dataclasses.replace(gb, supersample=0)
    with pytest.raises(InputError, match="supersample"):
        odd.downsample(gb.depth)
    with pytest.raises(InputError, match="image"):
        gb.downsample(np.zeros((2, 2, 2, 2)))


# ----------------------------------------------------------------------------- the helpers
@pytest.mark.parametrize(
    "value", [0, -1, 65, 1e300, float("nan"), float("inf"), True, "3", [3], np.ones(2), None]
)
def test_size_refuses(value):
    with pytest.raises(InputError, match=r"^width: expected a number in \(0, 64\]"):
        _validate.size(value, "width", "line_width")


def test_size_and_count_accept_numbers_up_to_the_bound():
    assert _validate.size(64, "width", "line_width") == 64.0
    assert _validate.size(np.float32(0.5), "width", "line_width") == 0.5
    assert _validate.size(512, "width", "line_width", buffer=True) == 512.0
    assert _validate.count(np.int64(360), "directions", "directions") == 360
    for bad in (361, 0, 2.0, True, "5"):
        with pytest.raises(InputError, match="directions: expected an integer in"):
            _validate.count(bad, "directions", "directions")


def test_check_memory_names_the_parameter():
    avail = _validate.available_memory()
    assert avail is None or avail > 0
    if avail is not None:
        with pytest.raises(InputError, match=r"^window_size: .* needs .* GiB"):
            _validate.check_memory(avail * 4 + 2**40, "window_size", "a capture")
    _validate.check_memory(1, "window_size", "a capture")
