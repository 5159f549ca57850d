"""The README's Python example runs as written, and its quick start matches .ci/run."""

from __future__ import annotations

import re

import numpy as np

from tests.helpers.paths import PROJECT_ROOT

ROOT = PROJECT_ROOT


def test_readme_python_example_runs(tmp_path, monkeypatch):
    text = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks
    monkeypatch.chdir(tmp_path)
    spaces = []
    for code in blocks:
        namespace: dict[str, object] = {}
        exec(compile(code, "README.md", "exec"), namespace)
        spaces.append(namespace)
    g = spaces[0]["g"]
    assert g.shape == (1200, 1600) and "Elevation" in g.scalars
    assert (tmp_path / "nut.npz").is_file()
    edges = spaces[1]
    assert edges["picture"].shape == (768, 1024, 3)
    assert edges["profile"].max() == 1.0 and edges["inner"].max() > 0.5
    medical = next(ns for ns in spaces if "pair" in ns)
    assert medical["pair"].shape == (384, 2 * 512 + 16, 4)
    assert (tmp_path / "frog_fig14.png").is_file()
    surface = next(ns for ns in spaces if "zebra" in ns)
    assert surface["zebra"].shape == (360, 480) and surface["lines"].max() > 0.9
    assert (tmp_path / "zebra.png").is_file()
    npr = next(ns for ns in spaces if "cartoon" in ns)
    assert npr["tech"].shape == npr["cartoon"].shape == npr["ink"].shape == (360, 480, 3)
    assert npr["drawing"].shape == npr["copied"].shape == (360, 480)
    assert (tmp_path / "nut_gooch.png").is_file()
    plug = next(ns for ns in spaces if "enhanced" in ns)
    assert plug["drawn"]["RGB"].shape == (320 * 240, 3)
    assert plug["g"].output_shape == (240, 320)
    assert not np.array_equal(plug["enhanced"], plug["plain"])
    assert not np.array_equal(plug["enhanced"], plug["moved"])
    pipe = next(ns for ns in spaces if "runs" in ns)
    assert pipe["runs"] == (1, 2)
    scale = next(ns for ns in spaces if "cog" in ns)
    assert scale["rgba"].shape == (1500, 2000, 4) and scale["cog"].is_file()
    assert (tmp_path / "big_map.png").is_file()


def test_quick_start_has_two_commands_and_ci_runs_the_test_one():
    text = (ROOT / "README.md").read_text()
    quick = text.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    commands = re.findall(r"```bash\n(.*?)\n```", quick, flags=re.S)
    assert len(commands) == 2
    assert "sciviz-gbuf demo" in commands[0]
    ci = (ROOT / ".ci" / "run").read_text()
    assert f"TEST_CMD='{commands[1]}'" in ci
