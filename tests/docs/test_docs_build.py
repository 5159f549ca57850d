"""The documentation site builds offline with warnings as errors, every gallery example runs
and shows the pictures it wrote, and the CLI reference lists every command."""

from __future__ import annotations

import html
import os
import re
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from tests.helpers.paths import PROJECT_ROOT

EXAMPLES = sorted((PROJECT_ROOT / "examples").glob("*.py"))

pytest.importorskip("sphinx_gallery")


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    root = tmp_path_factory.mktemp("docs")
    out, pictures = root / "html", root / "examples"
    env = {**os.environ, "SCIVIZ_GBUF_GALLERY_OUTPUT": str(pictures)}
    r = subprocess.run(
        [sys.executable, "-m", "sphinx", "docs", str(out), "-W", "-q"],
        cwd=PROJECT_ROOT,
        capture_output=True,
        text=True,
        timeout=3000,
        check=False,
        env=env,
        stdin=subprocess.DEVNULL,
    )
    assert r.returncode == 0, r.stderr[-4000:]
    return out, pictures


def test_the_site_has_every_page(site):
    out, _ = site
    pages = ["index", "getting_started", "terrain", "medical", "surface", "npr", "pyvista"]
    for page in [*pages, "out_of_core", "api", "cli", "performance", "auto_examples/index"]:
        assert (out / f"{page}.html").is_file(), page
    api = (out / "api.html").read_text()
    names = ["core.capture", "filters.contour_lines", "recipes.topographic_map"]
    names += ["readers.read_volume", "styles.gooch", "pyvista_plugin.GBufAccessor"]
    for name in (f"sciviz_gbuf.{n}" for n in names):
        assert f'id="{name}"' in api, name
    assert "Eq. 9" in api  # the docstrings' paper equations are in the reference
    for page in out.rglob("*.html"):  # no error box of docutils or the theme on any page
        text = page.read_text()
        # (Furo shows a red error over a `contents` directive, by CSS: no Sphinx warning)
        assert "system-message" not in text and 'class="contents' not in text, page


def test_cli_reference_lists_every_command_and_option(site):
    from sciviz_gbuf.cli import build_parser

    html = (site[0] / "cli.html").read_text()
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    for name, parser in sub.choices.items():
        assert f'id="sciviz-gbuf-{name}"' in html, name  # its section
        for action in parser._actions:
            for flag in action.option_strings:
                assert flag in html, (name, flag)


def test_cli_reference_shows_options_as_typed(site):
    """Copied from the page, an option must work: ``--up``, not an en dash ``–up``."""
    page = (site[0] / "cli.html").read_text()
    text = html.unescape(re.sub(r"<[^>]+>", " ", page))
    assert re.search(r"(?<![-\w])--up\b", text), "no --up in the visible text"
    dashed = re.findall(r"[\u2013\u2014][a-z][\w-]*", text)
    assert not dashed, dashed[:10]
    assert "\u201c" not in text and "\u201d" not in text  # no curly quotes around values


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_every_example_ran_and_its_pictures_are_in_the_gallery(site, script):
    out, pictures = site
    pngs = list((pictures / script.stem).rglob("*.png"))
    assert pngs, f"{script.name} wrote no PNG"
    for p in pngs:
        with Image.open(p) as im:
            assert im.size[0] > 16 and im.size[1] > 16
            assert len(np.unique(np.asarray(im.convert("L")))) > 1  # not a blank picture
    page = (out / "auto_examples" / f"{script.stem}.html").read_text()
    shown = [f for f in (out / "_images").glob(f"sphx_glr_{script.stem}_[0-9]*.png")]
    assert shown and all(f.name in page for f in shown)
