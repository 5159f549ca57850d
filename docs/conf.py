"""Sphinx configuration of the sciviz-gbuf documentation.

Build (offline, warnings are errors): ``python -m sphinx docs docs/_build -W``. The gallery
runs every script in ``examples/`` and shows the pictures it writes.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))
sys.path.insert(0, str(HERE.parent))

# Headless like the CI machine: VTK renders offscreen through EGL.
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

import sciviz_gbuf  # noqa: E402

project = "sciviz-gbuf"
author = "the sciviz-gbuf developers"
copyright = "2026, the sciviz-gbuf developers"
release = version = sciviz_gbuf.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    "sphinxarg.ext",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "cli_usage.md", "**.ipynb_checkpoints", "auto_examples/*.ipynb"]
myst_heading_anchors = 3
# No "smart" typography: argparse's help and the docs' option names are code a reader copies
# ("--up" would otherwise render as an en dash "–up", which a shell does not take).
smartquotes = False
myst_enable_extensions = ["colon_fence"]

html_theme = "furo"
html_title = f"sciviz-gbuf {release}"
html_static_path = ["_static"]

autodoc_default_options = {"members": True}
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types
autodoc_member_order = "bysource"
autosummary_generate = False
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

sphinx_gallery_conf = {
    "examples_dirs": str(HERE.parent / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r".*\.py$",  # run every example
    "image_scrapers": ("sg_hooks.png_scraper",),
    "reset_argv": "sg_hooks.reset_argv",
    "abort_on_example_error": True,
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "capture_repr": (),
    "show_memory": False,
    "run_stale_examples": True,  # every build runs every example (the tests rely on it)
}
