"""PNG files of images: float in [0, 1], uint8 or bool; large ones encoded on several threads."""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from .. import _validate
from .._atomic import atomic_output
from ..errors import InputError
from ._png_encoder import encode_rows, write_png_fast, write_png_parts

__all__ = [
    "LARGE_IMAGE",
    "check_image",
    "encode_png_rows",
    "to_uint8",
    "write_png",
    "write_png_blocks",
]

#: Images of at least this many pixels are encoded fast (multithreaded, low zlib level).
LARGE_IMAGE = 4_000_000


def check_image(image: object, name: str = "image") -> np.ndarray:
    """An image the writers take: (H, W), (H, W, 3) or (H, W, 4); float, uint8 or bool."""
    a = np.asarray(image)
    ok_shape = a.ndim == 2 or (a.ndim == 3 and a.shape[2] in (3, 4))
    if not ok_shape or a.size == 0:
        raise InputError(f"{name}: expected shape (H, W), (H, W, 3) or (H, W, 4), got {a.shape}")
    if a.dtype not in (np.uint8, np.bool_) and not np.issubdtype(a.dtype, np.floating):
        raise InputError(f"{name}: expected float in [0, 1], uint8 or bool, got dtype {a.dtype}")
    return a


def to_uint8(rgb: np.ndarray) -> np.ndarray:
    """Convert an image to 8 bits: float ``[0, 1]`` -> ``round(255 x)``; bool -> 0/255.

    Parameters
    ----------
    rgb : (H, W), (H, W, 3) or (H, W, 4) array_like
        Float in ``[0, 1]`` (values outside are clipped), uint8 (copied) or bool.

    Returns
    -------
    uint8 ndarray of the same shape
    """
    a = check_image(rgb, "rgb")
    if a.dtype == np.uint8:
        return a.copy()
    if a.dtype == np.bool_:
        return np.where(a, np.uint8(255), np.uint8(0))
    if not np.isfinite(a).all():
        raise InputError("rgb: expected finite values in [0, 1], got NaN or infinity")
    return np.rint(np.clip(a, 0.0, 1.0) * 255.0).astype(np.uint8)


def write_png(path: str | os.PathLike, image: np.ndarray, *, dpi: float | None = None) -> Path:
    """Write an image as PNG with Pillow.

    Parameters
    ----------
    path : str or path-like
        Output file; its directory must exist.
    image : (H, W), (H, W, 3) or (H, W, 4) array_like
        Float in ``[0, 1]``, uint8 or bool (grey, RGB or RGBA).
    dpi : float, optional
        Record this print resolution in the file (the PNG ``pHYs`` chunk, in whole pixels per
        metre: 300 dpi is stored as 11811 px/m and read back as 299.9994); at most
        ``LIMITS["dpi"]`` = 9600. Default: none recorded.

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    InputError
        A name not ending in ``.png``, a missing folder, an image of another shape or dtype.
    OutputError
        The file could not be written completely (disk full, file too large, no permission,
        interrupted): nothing new is left under its name (it is written to a temporary file
        beside it, checked, then renamed).
    """
    from PIL import Image

    p, dpi = _png_target(path, dpi)
    pixels = check_image(image)
    if pixels.dtype != np.uint8:
        pixels = to_uint8(pixels)  # (uint8 is written as it is: the file only reads it)
    with atomic_output(path) as part:
        if pixels.shape[0] * pixels.shape[1] >= LARGE_IMAGE:
            write_png_fast(part.path, pixels, dpi=dpi)  # checks the size on disk itself
        else:
            extra = {} if dpi is None else {"dpi": (dpi, dpi)}
            with open(part.path, "wb") as f:
                Image.fromarray(pixels).save(f, format="PNG", **extra)
                # Pillow writes through this buffered file: the size it reached is what the
                # disk must hold once the buffer is flushed by close().
                part.expected_size = f.tell()
    return p


def _png_target(path: str | os.PathLike, dpi: float | None) -> tuple[Path, float | None]:
    """``(path, dpi)`` of a PNG to write, checked: a ``.png`` name in an existing folder, a
    DPI within ``LIMITS["dpi"]``."""
    p = Path(path)
    if p.suffix.lower() != ".png":
        raise InputError(f"path: expected a file name ending in .png, got {str(p)!r}")
    if not p.parent.is_dir():
        raise InputError(f"path: no such directory {str(p.parent)!r}")
    return p, (None if dpi is None else _validate.size(dpi, "dpi", "dpi"))


def encode_png_rows(rows: np.ndarray, *, last: bool) -> tuple[bytes, int, int]:
    """A block of rows of a PNG (uint8 ``(n, W)``, ``(n, W, 3)`` or ``(n, W, 4)``), filtered
    and deflated on its own, for :func:`write_png_blocks`; ``last``: the image's last block.
    Blocks may be encoded at once on several threads (the deflate releases the GIL)."""
    return encode_rows(rows, last=last)


def write_png_blocks(
    path: str | os.PathLike, shape: tuple[int, ...], blocks: Iterable[tuple[bytes, int, int]],
    *, dpi: float | None = None,
) -> Path:  # fmt: skip
    """Write a PNG of ``shape`` ((H, W), (H, W, 3) or (H, W, 4), uint8) from its blocks of
    rows encoded by :func:`encode_png_rows`, top to bottom, each written as it comes: the
    image is never whole in memory. Same checks, ``dpi`` and atomic write as
    :func:`write_png` (a failure while the blocks are made leaves no file)."""
    p, dpi = _png_target(path, dpi)
    ok = len(shape) == 2 or (len(shape) == 3 and shape[2] in (3, 4))
    if not ok or min(shape[:2]) < 1:
        raise InputError(f"shape: expected (H, W), (H, W, 3) or (H, W, 4), got {tuple(shape)}")
    with atomic_output(path) as part:
        write_png_parts(part.path, tuple(int(v) for v in shape), iter(blocks), dpi)
    return p
