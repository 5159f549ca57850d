"""The vocabularies of map options shared by the recipes and the command line, in a module that
imports nothing heavy (building the ``topo`` parser reads them)."""

from __future__ import annotations

__all__ = ["PAGES", "RELIEFS"]

#: Relief style -> what it shows (the vocabulary of ``topographic_map(relief=)`` and
#: ``topo --relief``).
RELIEFS = {
    "hillshade": "GDAL's hillshade",
    "vat": "RVT's VAT blend of hillshade, slope, positive openness and sky view",
    "openness": "hillshade with positive openness overlaid (ridges light, valleys dark)",
    "texture": "hillshade with Brown's texture shading overlaid (drainage at every scale)",
    "local_relief": "hillshade with the local relief model overlaid (small landforms)",
}
#: Page sizes of the printable map pages (width, height in mm, portrait).
PAGES = {"A4": (210.0, 297.0), "A3": (297.0, 420.0), "letter": (215.9, 279.4)}
