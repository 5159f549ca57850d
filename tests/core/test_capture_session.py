"""A capture session re-renders only: every capture equals a fresh ``capture`` of that view."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import pyvista as pv

import sciviz_gbuf as sg
from sciviz_gbuf.errors import InputError


def _assert_same(a: sg.GBuffer, b: sg.GBuffer) -> None:
    for f in dataclasses.fields(sg.GBuffer):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            np.testing.assert_array_equal(x, y, err_msg=f.name)
        elif f.name == "scalars":
            assert x.keys() == y.keys()
            for k in x:
                np.testing.assert_array_equal(x[k], y[k], err_msg=k)
        elif f.name == "camera":
            assert x.to_json() == y.to_json()
        else:
            assert x == y, f.name


def test_session_captures_equal_fresh_captures_across_views_and_sizes():
    mesh = pv.Sphere(theta_resolution=40, phi_resolution=40)
    mesh["h"] = mesh.points[:, 2]
    other = pv.Cube(center=(1.5, 0, 0)).triangulate()
    scene = [mesh, other]
    views = [
        dict(camera="iso", window_size=(120, 90)),
        dict(camera=((4, 3, 2), (0.5, 0, 0), (0, 0, 1)), window_size=(64, 48), supersample=2),
        dict(camera="xy", window_size=(50, 70), parallel_projection=True),
        dict(camera="iso", window_size=(120, 90), up="y"),
    ]
    with sg.CaptureSession(scene, scalars="h") as session:
        for kw in views:
            _assert_same(session.capture(**kw), sg.capture(scene, scalars="h", **kw))
        session.close()  # closing releases the window; a later capture opens a new one
        _assert_same(session.capture(**views[0]), sg.capture(scene, scalars="h", **views[0]))


def test_session_checks_like_capture():
    with pytest.raises(InputError, match="scalars"):
        sg.CaptureSession(pv.Sphere(), scalars="nope")
    with pytest.raises(InputError, match="feature_angle"):
        sg.CaptureSession(pv.Sphere(), feature_angle=200)
    with sg.CaptureSession(pv.Sphere()) as session, pytest.raises(InputError, match="window"):
        session.capture(window_size=(0, 10))


def test_reused_buffers_are_rewritten_and_equal_fresh_captures():
    mesh = pv.Sphere(theta_resolution=30, phi_resolution=30)
    with sg.CaptureSession(mesh) as session:
        a = session.capture(camera="iso", window_size=(80, 60), reuse=True)
        depth_a = a.depth.copy()
        b = session.capture(
            camera=((0, 4, 1), (0, 0, 0), (0, 0, 1)), window_size=(80, 60), reuse=True
        )
        assert b.depth is a.depth  # the same memory, rewritten
        assert not np.array_equal(depth_a, b.depth, equal_nan=True)
        _assert_same(
            b, sg.capture(mesh, camera=((0, 4, 1), (0, 0, 0), (0, 0, 1)), window_size=(80, 60))
        )
        c = session.capture(camera="iso", window_size=(80, 60))  # not reused: its own arrays
        assert c.depth is not b.depth
        np.testing.assert_array_equal(c.depth, depth_a)
