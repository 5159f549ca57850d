"""Where the project and the shared data sets are, independent of the test file's depth."""

from __future__ import annotations

from pathlib import Path

# tests/helpers/paths.py -> parents: [0] tests/helpers, [1] tests, [2] the project.
PROJECT_ROOT = Path(__file__).resolve().parents[2]
SHARED_DATA = PROJECT_ROOT.parent / "shared" / "data"


def shared_dem(name: str):
    """The shared DEM ``name`` (``data/dem/``) read by ``read_dem``; the test is skipped when
    the shared data is not beside the project. The SRTM ``.asc`` has no CRS: its warning is
    not the test's subject."""
    import warnings

    import pytest

    from sciviz_gbuf.readers import read_dem

    path = SHARED_DATA / "dem" / name
    if not path.is_file():
        pytest.skip(f"{path} not available")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return read_dem(path)
