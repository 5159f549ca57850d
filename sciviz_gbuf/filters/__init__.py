"""Image-space operators on G-buffer channels: pure functions on numpy arrays (and a mask),
returning new float32 arrays; inputs are never modified. Shades are in [0, 1] with 1 = lit;
line images are ink in [0, 1] with 1 = full ink."""

from .shading import lambert

__all__ = ["lambert"]
