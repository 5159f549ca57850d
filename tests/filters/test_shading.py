"""The Lambert shade (Saito's sh image) on an analytic sphere and bad input."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import sciviz_gbuf as sg
from sciviz_gbuf.filters import lambert


def test_headlight_shade_of_a_sphere_is_the_cosine_of_incidence():
    s = pv.Sphere(radius=1.0, theta_resolution=120, phi_resolution=120)
    g = sg.capture(s, window_size=(120, 120), camera="xy", parallel_projection=True)
    sh = lambert(g.normal, mask=g.mask)
    assert np.isnan(sh[~g.mask]).all()
    # orthographic view along -z: the eye-space normal's z is sqrt(1 - x^2 - y^2) of the hit
    x, y = g.world[..., 0][g.mask], g.world[..., 1][g.mask]
    expected = np.sqrt(np.clip(1 - x**2 - y**2, 0, 1))
    assert np.abs(sh[g.mask] - expected).max() < 0.02
    # a light from the +x side lights the +x half only
    side = lambert(g.normal, light=(1, 0, 0), ambient=0.2, mask=g.mask)
    assert side[g.mask][x < -0.05] == pytest.approx(0.2)
    assert (side[g.mask][x > 0.5] > 0.6).all()


@settings(max_examples=50, deadline=None)
@given(arrays(np.float32, (4, 5, 3), elements=st.floats(-1, 1, width=32)), st.floats(0, 1))
def test_shade_is_in_range_and_input_untouched(n, ambient):
    before = n.copy()
    sh = lambert(n, light=(0.3, -0.2, 1.0), ambient=ambient)
    assert sh.dtype == np.float32 and sh.shape == (4, 5)
    assert (sh >= ambient - 1e-6).all() and (sh <= 1.0).all()
    assert np.array_equal(n, before)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(normal=np.zeros((4, 4))), "normal"),
        (dict(normal=np.zeros((4, 4, 3)), light=(0, 0, 0)), "light"),
        (dict(normal=np.zeros((4, 4, 3)), light=(0, 1)), "light"),
        (dict(normal=np.zeros((4, 4, 3)), ambient=2.0), "ambient"),
        (dict(normal=np.zeros((4, 4, 3)), mask=np.ones((3, 3), bool)), "mask"),
    ],
)
def test_bad_input(kwargs, match):
    n = kwargs.pop("normal")
    with pytest.raises(sg.InputError, match=match):
        lambert(n, **kwargs)
