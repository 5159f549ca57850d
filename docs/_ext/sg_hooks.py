"""sphinx-gallery hooks of the documentation: the examples write PNG files into the folder
given as their first argument (as on the command line), and each one's new PNGs become the
pictures of the code block that wrote them."""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

from sphinx_gallery.scrapers import figure_rst

#: Where the examples write, one folder each: ``SCIVIZ_GBUF_GALLERY_OUTPUT`` (the tests look
#: at every PNG there), else a new temporary folder.
OUTPUT = Path(
    os.environ.get("SCIVIZ_GBUF_GALLERY_OUTPUT") or tempfile.mkdtemp(prefix="sciviz_gbuf_gallery_")
)
#: At most this many pictures per example: its montages if it writes any, else its first PNGs.
MAX_PICTURES = 6
_seen: dict[str, set[Path]] = {}


def reset_argv(gallery_conf: dict, script_vars: dict) -> list[str]:
    """The example's argument: its own output folder."""
    stem = Path(script_vars["src_file"]).stem
    return [str(OUTPUT / stem)]


def png_scraper(block, block_vars: dict, gallery_conf: dict, **kwargs) -> str:
    """The PNGs the block wrote into the example's folder, as reST image directives."""
    stem = Path(block_vars["src_file"]).stem
    seen = _seen.setdefault(stem, set())
    folder = OUTPUT / stem
    new = sorted(p for p in folder.rglob("*.png") if p not in seen) if folder.is_dir() else []
    seen.update(new)
    montages = [p for p in new if "montage" in p.name]
    chosen = (montages or new)[:MAX_PICTURES]
    paths = []
    for src, dest in zip(chosen, block_vars["image_path_iterator"], strict=False):
        shutil.copyfile(src, dest)
        paths.append(dest)
    return figure_rst(paths, gallery_conf["src_dir"])
