"""Recipes: the data flow capture -> filters -> compose, packaged for one kind of picture each.

- :mod:`.framing`: cameras that frame a bounding box from a given direction.
- :mod:`.illustration`: shaded + edge illustrations of a G-buffer (the ``edges`` command).
- :mod:`.saito1990`: the panels of Saito & Takahashi's Fig. 3 and Fig. 7 (and the 2003 edge map).
"""

from .framing import framed_camera, oblique_camera
from .illustration import STYLES, fig7_edge_map, illustrate, shade_image, signed_to_grey
from .saito1990 import CAPTIONS, fig3_panels, fig7_panels, nut_camera

__all__ = [
    "CAPTIONS",
    "STYLES",
    "fig3_panels",
    "fig7_edge_map",
    "fig7_panels",
    "framed_camera",
    "illustrate",
    "nut_camera",
    "oblique_camera",
    "shade_image",
    "signed_to_grey",
]
