"""Shared helpers: independent (hand-derived) pinhole geometry to check captures against."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage

# Without a display, let PyVista's own Plotter go straight to EGL instead of trying X first.
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"

_WARMUP: subprocess.Popen | None = None


def pytest_configure(config):
    """Compile numba kernels on the other core meanwhile (see ``_numba_warmup.py``): on a
    fresh clone compiling them is most of the run, and numba compiles on one core."""
    global _WARMUP
    if os.environ.get("SCIVIZ_GBUF_NO_WARMUP") or hasattr(config, "workerinput"):
        return
    _WARMUP = subprocess.Popen(
        [sys.executable, str(Path(__file__).with_name("_numba_warmup.py"))],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def pytest_unconfigure(config):
    if _WARMUP is not None and _WARMUP.poll() is None:
        _WARMUP.kill()
        _WARMUP.wait()


def camera_basis(cam):
    """Unit (direction, right, up) of a CameraInfo, from its position/focal point/view up only."""
    d = np.subtract(cam.focal_point, cam.position)
    d = d / np.linalg.norm(d)
    right = np.cross(d, cam.view_up)
    right /= np.linalg.norm(right)
    up = np.cross(right, d)
    return d, right, up


def rays_by_hand(cam):
    """Ray origins and unit directions through pixel centres (row 0 on top), float64.

    Textbook pinhole / orthographic camera from the view angle or parallel scale; shares no code
    with the package.
    """
    w, h = cam.window_size
    d, right, up = camera_basis(cam)
    x = (np.arange(w) + 0.5) / w * 2 - 1
    y = 1 - (np.arange(h) + 0.5) / h * 2
    xx, yy = np.meshgrid(x, y)
    aspect = w / h
    eye = np.asarray(cam.position, dtype=np.float64)
    if cam.parallel_projection:
        s = cam.parallel_scale
        origin = eye + (xx[..., None] * s * aspect) * right + (yy[..., None] * s) * up
        direction = np.broadcast_to(d, origin.shape).copy()
    else:
        t = np.tan(np.radians(cam.view_angle) / 2)
        direction = d + (xx[..., None] * t * aspect) * right + (yy[..., None] * t) * up
        direction /= np.linalg.norm(direction, axis=-1, keepdims=True)
        origin = np.broadcast_to(eye, direction.shape).copy()
    return origin, direction


def to_eye(cam, v):
    """World vectors -> eye space (x right, y up, z towards the viewer)."""
    d, right, up = camera_basis(cam)
    return np.stack([v @ right, v @ up, -(v @ d)], axis=-1)


def angle_deg(a, b):
    """Angle between vectors in degrees; atan2 form (arccos of a dot product near 1 is
    ill-conditioned: float32 rounding alone would read as 0.01 degree)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    return np.degrees(np.arctan2(cross, np.sum(a * b, axis=-1)))


def interior(mask, px: int = 1):
    """Covered pixels at least ``px`` pixels away from any uncovered pixel or the image border."""
    padded = np.pad(mask, px, constant_values=False)
    return ndimage.binary_erosion(padded, np.ones((2 * px + 1, 2 * px + 1)))[px:-px, px:-px]


@pytest.fixture(scope="session")
def shared_data() -> Path:
    if not SHARED_DATA.is_dir():
        pytest.skip("../shared/data is not beside the project")
    return SHARED_DATA
