"""The files of a web-map tile pyramid: encoded tiles, its TileJSON and a Leaflet viewer.

The viewer is ``index.html`` beside the ``z/x/y`` folders with Leaflet 1.9.4 (BSD-2-Clause,
bundled in ``_web/leaflet`` from its npm package, with its licence) copied next to it: it opens
from the file system or any static web server, with no network access.
"""

from __future__ import annotations

import io
import json
import shutil
from collections.abc import Sequence
from html import escape
from pathlib import Path

import numpy as np

from ..errors import InputError

__all__ = ["LEAFLET", "TILE_FORMATS", "encode_tile", "write_tile_viewer", "write_tilejson"]

#: Tile encodings: lossless PNG and lossless WebP, both with transparency.
TILE_FORMATS = ("png", "webp")

#: The bundled Leaflet files (leaflet.js, leaflet.css, LICENSE).
LEAFLET = Path(__file__).resolve().parent / "_web" / "leaflet"


def encode_tile(rgba: np.ndarray, fmt: str = "png") -> bytes:
    """The bytes of one (T, T, 4) uint8 tile as PNG or lossless WebP."""
    from PIL import Image

    a = np.asarray(rgba)
    if a.ndim != 3 or a.shape[2] != 4 or a.dtype != np.uint8:
        raise InputError(f"tile: expected (T, T, 4) uint8 RGBA, got {a.dtype} {a.shape}")
    buf = io.BytesIO()
    image = Image.fromarray(np.ascontiguousarray(a), "RGBA")
    if fmt == "png":
        # level 6: tiles are small; the default (and optimize) cost 3-5x the time for ~5 %
        image.save(buf, format="PNG", compress_level=6)
    elif fmt == "webp":
        image.save(buf, format="WEBP", lossless=True, quality=60, method=2, exact=True)
    else:
        raise InputError(f"format: expected one of {', '.join(TILE_FORMATS)}, got {fmt!r}")
    return buf.getvalue()


def write_tilejson(
    path: Path,
    *,
    name: str,
    bounds: Sequence[float],
    zooms: tuple[int, int],
    fmt: str,
    tile_size: int,
) -> Path:
    """``tiles.json``: TileJSON 3.0.0 of the pyramid (relative tile URL, bounds, zooms)."""
    west, south, east, north = (float(v) for v in bounds)
    doc = {
        "tilejson": "3.0.0",
        "name": name,
        "scheme": "xyz",
        "tiles": [f"{{z}}/{{x}}/{{y}}.{fmt}"],
        "minzoom": int(zooms[0]),
        "maxzoom": int(zooms[1]),
        "bounds": [west, south, east, north],
        "center": [(west + east) / 2.0, (south + north) / 2.0, int(zooms[0])],
        "tileSize": int(tile_size),
    }
    path.write_text(json.dumps(doc, indent=1))
    return path


_PAGE = """<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{title}</title>
<link rel="stylesheet" href="leaflet/leaflet.css">
<style>html, body, #map {{ height: 100%; margin: 0; background: #fff; }}</style>
</head>
<body>
<div id="map"></div>
<script src="leaflet/leaflet.js"></script>
<script>
// The pyramid beside this page: z/x/y.{fmt}, zooms {zmin}-{zmax}, {tile} px tiles.
var bounds = L.latLngBounds([{south}, {west}], [{north}, {east}]);
var map = L.map("map", {{minZoom: 0, maxZoom: {zmax_view}, zoomSnap: 1}});
var layer = L.tileLayer("{{z}}/{{x}}/{{y}}.{fmt}", {{
  minZoom: {zmin}, maxZoom: {zmax_view}, minNativeZoom: {zmin}, maxNativeZoom: {zmax},
  tileSize: {tile}, zoomOffset: {offset}, bounds: bounds, noWrap: true,
  attribution: {credit}
}}).addTo(map);
map.fitBounds(bounds);
if (map.getZoom() < {zmin}) map.setZoom({zmin});
L.control.scale({{imperial: false}}).addTo(map);
</script>
</body>
</html>
"""


def write_tile_viewer(
    folder: Path,
    *,
    title: str,
    bounds: Sequence[float],
    zooms: tuple[int, int],
    fmt: str,
    tile_size: int,
) -> Path:
    """``index.html`` and ``leaflet/`` in ``folder``: a map page showing the pyramid,
    fitted to ``bounds`` (lon/lat degrees), magnifying the last level two zooms further."""
    west, south, east, north = (float(v) for v in bounds)
    lib = folder / "leaflet"
    lib.mkdir(exist_ok=True)
    for name in ("leaflet.js", "leaflet.css", "LICENSE"):
        shutil.copyfile(LEAFLET / name, lib / name)
    # Leaflet's zoom counts 256 px tiles: a 512 px pyramid's level z is Leaflet's z + 1
    offset = -1 if tile_size == 512 else 0
    shift = -offset
    page = _PAGE.format(
        title=escape(title), fmt=fmt, zmin=zooms[0] + shift, zmax=zooms[1] + shift,
        zmax_view=zooms[1] + shift + 2, tile=tile_size, offset=offset, west=west, south=south,
        east=east, north=north,
        credit=json.dumps(f"{escape(title)} &middot; sciviz-gbuf"),
    )  # fmt: skip
    out = folder / "index.html"
    out.write_text(page, encoding="utf-8")
    return out
