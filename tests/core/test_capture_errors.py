"""Bad and odd input: clear InputErrors naming the problem, never a deep traceback."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import sciviz_gbuf as sg

SPHERE = pv.Sphere(theta_resolution=16, phi_resolution=16)


@pytest.mark.parametrize(
    ("scene", "match"),
    [
        ([], "empty scene"),
        (pv.PolyData(), "empty"),
        (pv.PolyData(np.random.default_rng(0).random((5, 3))), "no surface"),
        (pv.Line(), "no surface"),
        (np.zeros((3, 3)), "expected a PyVista/VTK dataset"),
        ("mesh.stl", "expected a PyVista/VTK dataset"),
        ([SPHERE, 3], r"scene\[1\]"),
    ],
)
def test_bad_scenes(scene, match):
    with pytest.raises(sg.InputError, match=match):
        sg.capture(scene, window_size=(16, 16))


def test_nan_coordinates_are_named():
    bad = SPHERE.copy()
    pts = np.asarray(bad.points).copy()
    pts[3] = np.nan
    bad.points = pts
    with pytest.raises(sg.InputError, match=r"dataset 1 .*1 point\(s\) have NaN"):
        sg.capture([SPHERE, bad], window_size=(16, 16))


def test_empty_plotter():
    pl = pv.Plotter(off_screen=True)
    pl.add_text("only text")
    with pytest.raises(sg.InputError, match="no visible actor"):
        sg.capture(pl)
    pl.close()


def test_unknown_scalar_lists_available_arrays():
    s = SPHERE.copy()
    s.point_data["elevation"] = s.points[:, 2]
    with pytest.raises(sg.InputError, match=r"'height'.*available: \['Normals', 'elevation'\]"):
        sg.capture(s, window_size=(16, 16), scalars=["height"])


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(window_size=(0, 10)), "window_size"),
        (dict(window_size=(10, -3)), "window_size"),
        (dict(window_size=(10.5, 3)), "window_size"),
        (dict(window_size="big"), "window_size"),
        (dict(window_size=(1, 2, 3)), "window_size"),
        (dict(window_size=(20000, 10)), "exceeds"),
        (dict(window_size=(5000, 10), supersample=4), "exceeds"),
        (dict(supersample=0), "supersample"),
        (dict(supersample=2.5), "supersample"),
        (dict(supersample=True), "supersample"),
        (dict(feature_angle=-1), "feature_angle"),
        (dict(scalars=[""]), "scalars"),
        (dict(scalars=3), "scalars"),
        (dict(camera="top"), "unknown view 'top'"),
        (dict(camera=[(0, 0, 1), (0, 0, 1), (0, 1, 0)]), "coincide"),
        (dict(camera=[(0, 0, 5), (0, 0, 0), (0, 0, 1)]), "view up is parallel"),
        (dict(camera=[(0, 0, np.nan), (0, 0, 0), (0, 1, 0)]), "finite"),
        (dict(camera=[(0, 0, -5), (0, 0, -10), (0, 1, 0)]), "behind the camera"),
        (dict(camera=42), "camera: expected"),
    ],
)
def test_bad_parameters(kwargs, match):
    kwargs.setdefault("window_size", (16, 16))
    with pytest.raises(sg.InputError, match=match):
        sg.capture(SPHERE, **kwargs)


def test_input_error_is_a_value_error():
    with pytest.raises(ValueError):
        sg.capture([], window_size=(8, 8))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    w=st.integers(1, 48),
    h=st.integers(1, 48),
    parallel=st.booleans(),
    view=st.sampled_from(["iso", "xy", "xz", "zy"]),
)
def test_any_window_size_gives_consistent_buffers(w, h, parallel, view):
    g = sg.capture(SPHERE, window_size=(w, h), camera=view, parallel_projection=parallel)
    assert g.shape == (h, w)
    m = g.mask
    assert np.array_equal(np.isnan(g.depth), ~m)
    assert np.array_equal(np.isnan(g.sz), ~m)
    assert (g.object_id[m] == 0).all() and (g.object_id[~m] == -1).all()
    if m.any():
        assert np.allclose(np.linalg.norm(g.normal[m], axis=-1), 1.0, atol=1e-5)
        assert (g.depth[m] > 0).all()
        # on the coarse (16-segment) sphere: within its facets' sagitta of the radius
        r = np.linalg.norm(g.world[m], axis=-1)
        # A pixel centre the rasteriser gives to a facet may lie a vertex snap (a fraction of
        # a pixel) outside it: allow a quarter of the pixel footprint beyond the sphere.
        foot = g.camera.pixel_size * (g.depth[m] / g.camera.distance if not parallel else 1.0)
        assert (r <= 0.5 + 0.25 * foot).all() and (r >= 0.5 * np.cos(np.pi / 15) ** 2).all()


@settings(max_examples=40, deadline=None)
@given(
    size=st.one_of(
        st.tuples(st.integers(-5, 0), st.integers(1, 5)),
        st.tuples(st.integers(1, 5), st.integers(-5, 0)),
        st.tuples(
            st.floats(allow_nan=True).filter(lambda v: v != int(v) if np.isfinite(v) else True),
            st.just(4),
        ),
        st.text(max_size=3),
        st.none().map(lambda _: (1,)),
    )
)
def test_invalid_window_sizes_raise_input_error(size):
    with pytest.raises(sg.InputError, match="window_size"):
        sg.capture(SPHERE, window_size=size)


def test_non_numeric_array_is_refused():
    s = SPHERE.copy()
    s.cell_data["names"] = np.array(["a"] * s.n_cells)
    with pytest.raises(sg.InputError, match=r"'names' of dataset 0 .* not numeric"):
        sg.capture(s, window_size=(16, 16), scalars="names")
