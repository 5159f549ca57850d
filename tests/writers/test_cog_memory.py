"""Out of core on a cluster whose workers cannot hold one block: refused at once with one line
naming the chunk size (issue 20), not workers restarted again and again."""

from __future__ import annotations

import numpy as np
import pytest

from tests.helpers.cli import assert_clean_failure, checksums, run_cli

rasterio = pytest.importorskip("rasterio")
pytest.importorskip("distributed")


def test_memory_limit_too_small_for_one_chunk(tmp_path):
    dem = tmp_path / "big.tif"
    z = np.add.outer(np.arange(2048.0), np.arange(2048.0)).astype(np.float32)
    profile = {"driver": "GTiff", "width": 2048, "height": 2048, "count": 1, "dtype": "float32"}
    with rasterio.open(
        dem, "w", crs="EPSG:32633", transform=(10, 0, 5e5, 0, -10, 5e6), **profile
    ) as d:
        d.write(z[None])
    out = tmp_path / "map.tif"
    args = ["topo", dem, "-o", out, "--chunks", "2048", "--dask", "--workers", "1"]
    proc = run_cli([*args, "--memory-limit", "120MB"], cwd=tmp_path)
    line = assert_clean_failure(
        proc, names=["memory limit"], outputs=[out], inputs=checksums([dem])
    )
    assert "2048x2048" in line and "--chunks" in line
