"""Every Python snippet of the documentation runs as written (and shows what it says), and the
README's quick start matches .ci/run."""

from __future__ import annotations

import re

import numpy as np

from tests.helpers.paths import PROJECT_ROOT

ROOT = PROJECT_ROOT
DOCS = ROOT / "docs"


def _blocks(path):
    return re.findall(r"```python\n(.*?)```", path.read_text(), flags=re.S)


def test_every_python_snippet_of_the_docs_and_readme_runs(tmp_path, monkeypatch):
    pages = [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]
    monkeypatch.chdir(tmp_path)
    spaces = []
    for page in pages:
        for code in _blocks(page):
            namespace: dict[str, object] = {}
            exec(compile(code, str(page.relative_to(ROOT)), "exec"), namespace)
            spaces.append(namespace)
    assert len(spaces) >= 10

    def having(*names):
        return next(ns for ns in spaces if all(n in ns for n in names))

    first = having("first")
    assert first["first"].shape == (480, 640, 3) and (tmp_path / "nut_enhanced.png").is_file()
    assert first["first"].min() < 0.05 and first["first"].max() > 0.95  # black lines, white
    g = having("hills")["g"]
    assert g.shape == (1200, 1600) and "Elevation" in g.scalars
    assert (tmp_path / "nut.npz").is_file()
    edges = having("picture", "emap")
    assert edges["picture"].shape == (768, 1024, 3)
    assert edges["profile"].max() == 1.0 and edges["inner"].max() > 0.5
    medical = having("pair")
    assert medical["pair"].shape == (384, 2 * 512 + 16, 4)
    assert (tmp_path / "frog_fig14.png").is_file()
    surface = having("zebra")
    assert surface["zebra"].shape == (360, 480) and surface["lines"].max() > 0.9
    assert (tmp_path / "zebra.png").is_file()
    npr = having("cartoon")
    assert npr["tech"].shape == npr["cartoon"].shape == npr["ink"].shape == (360, 480, 3)
    assert npr["drawing"].shape == npr["copied"].shape == (360, 480)
    assert (tmp_path / "nut_gooch.png").is_file()
    plug = having("enhanced")
    assert plug["drawn"]["RGB"].shape == (320 * 240, 3)
    assert plug["g"].output_shape == (240, 320)
    assert not np.array_equal(plug["enhanced"], plug["plain"])
    assert not np.array_equal(plug["enhanced"], plug["moved"])
    pipe = having("runs")
    assert pipe["runs"] == (1, 2)
    scale = having("cog")
    assert scale["rgba"].shape == (1500, 2000, 4) and scale["cog"].is_file()
    assert (tmp_path / "big_map.png").is_file()
    contours = having("fig5a")
    assert contours["topo"].shape == (344, 403) and contours["geojson"]


def test_quick_start_has_two_commands_and_ci_runs_the_test_one():
    text = (ROOT / "README.md").read_text()
    quick = text.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    commands = re.findall(r"```bash\n(.*?)\n```", quick, flags=re.S)
    assert len(commands) == 2
    assert "sciviz-gbuf demo" in commands[0]
    ci = (ROOT / ".ci" / "run").read_text()
    assert f"TEST_CMD='{commands[1]}'" in ci
