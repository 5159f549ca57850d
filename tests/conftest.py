"""pytest hooks and fixtures only; shared helpers live in ``tests.helpers``."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.helpers.paths import SHARED_DATA

# Without a display, let PyVista's own Plotter go straight to EGL instead of trying X first.
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

_WARMUP: subprocess.Popen | None = None


def pytest_configure(config):
    """Compile numba kernels on the other core meanwhile (``sciviz_gbuf.apps.warmup``'s
    ``all`` job): on a fresh clone compiling them is most of the run, and numba compiles on
    one core."""
    global _WARMUP
    if os.environ.get("SCIVIZ_GBUF_NO_WARMUP") or hasattr(config, "workerinput"):
        return
    _WARMUP = subprocess.Popen(
        [sys.executable, "-m", "sciviz_gbuf.apps.warmup", "all"],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def pytest_unconfigure(config):
    if _WARMUP is not None and _WARMUP.poll() is None:
        _WARMUP.kill()
        _WARMUP.wait()


@pytest.fixture(scope="session")
def shared_data() -> Path:
    if not SHARED_DATA.is_dir():
        pytest.skip("../shared/data is not beside the project")
    return SHARED_DATA
