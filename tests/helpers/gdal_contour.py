"""``gdal_contour``'s lines as pixel samples: the independent reference for contour positions,
shared by the tests and ``benchmarks/picture_audit.py``."""

from __future__ import annotations

import itertools
import json
import shutil
import subprocess
from pathlib import Path

import numpy as np

#: Spacing (px) of the samples taken along each GDAL line segment.
STEP = 0.05


def gdal_samples(src: Path, interval: float, tmp: Path, base: float = 0.0) -> np.ndarray | None:
    """``gdal_contour -i interval -off base`` lines of the raster ``src`` as (N, 2) (row, col)
    samples in pixel-centre coordinates (GDAL's values sit at the pixel centres), or None when
    ``gdal_contour`` (gdal-bin) is not installed or draws no line."""
    import rasterio

    if shutil.which("gdal_contour") is None:
        return None
    out = Path(tmp) / f"{Path(src).stem}.{interval:g}.{base:g}.geojson"
    cmd = ["gdal_contour", "-q", "-i", repr(interval), "-off", repr(base), "-f", "GeoJSON"]
    subprocess.run([*cmd, str(src), str(out)], check=True, capture_output=True)
    with rasterio.open(src) as ds:
        x0, dx, rx, y0, ry, dy = ds.transform.to_gdal()
    inv = np.linalg.inv([[dx, rx], [ry, dy]])
    pts = []
    for feature in json.loads(out.read_text())["features"]:
        geom = feature["geometry"]
        parts = geom["coordinates"] if geom["type"] == "MultiLineString" else [geom["coordinates"]]
        for line in parts:
            # corners -> pixel-centre coordinates
            cr = (np.asarray(line, float)[:, :2] - [x0, y0]) @ inv.T - 0.5
            for a, b in itertools.pairwise(cr):
                n = int(np.ceil(np.hypot(*(b - a)) / STEP)) + 1
                pts.append(a + (b - a) * np.linspace(0.0, 1.0, n)[:, None])
    return np.concatenate(pts)[:, ::-1] if pts else None
