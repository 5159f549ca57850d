"""GeoJSON files of vector features (contour polylines, contour label points)."""

from __future__ import annotations

import json
import math
import os
from typing import Any

from .._atomic import atomic_output
from ..errors import InputError

__all__ = ["write_geojson"]


def _finite(value: Any) -> bool:
    """True if every number in a JSON-like value is finite (JSON has no NaN or infinity)."""
    if isinstance(value, float):
        return math.isfinite(value)
    if isinstance(value, dict):
        return all(_finite(v) for v in value.values())
    if isinstance(value, (list, tuple)):
        return all(_finite(v) for v in value)
    return True


def write_geojson(path: str | os.PathLike, collection: dict[str, Any]) -> None:
    """Write a GeoJSON FeatureCollection (of
    :func:`~sciviz_gbuf.filters.polylines_to_geojson` or
    :func:`~sciviz_gbuf.recipes.labels.labels_to_geojson`) as UTF-8, all or nothing
    (:func:`~sciviz_gbuf._atomic.atomic_output`).

    Raises
    ------
    InputError
        If ``collection`` is not a FeatureCollection or holds a NaN or infinite number
        (strict JSON, RFC 8259, has none).
    """
    if not (isinstance(collection, dict) and collection.get("type") == "FeatureCollection"):
        raise InputError("collection: expected a GeoJSON FeatureCollection (a dict)")
    if not _finite(collection):
        raise InputError("collection: expected finite coordinates and properties (no NaN)")
    text = json.dumps(collection, ensure_ascii=False, allow_nan=False)
    data = text.encode("utf-8")
    with atomic_output(path) as part:
        with open(part.path, "wb") as f:
            f.write(data)
        part.expected_size = len(data)
