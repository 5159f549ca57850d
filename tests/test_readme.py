"""The README's Python example runs as written, and its quick start matches .ci/run."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_readme_python_example_runs(tmp_path, monkeypatch):
    text = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks
    monkeypatch.chdir(tmp_path)
    for code in blocks:
        namespace: dict[str, object] = {}
        exec(compile(code, "README.md", "exec"), namespace)
    g = namespace["g"]
    assert g.shape == (1200, 1600) and "Elevation" in g.scalars
    assert (tmp_path / "nut.npz").is_file()


def test_quick_start_has_two_commands_and_ci_runs_the_test_one():
    text = (ROOT / "README.md").read_text()
    quick = text.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    commands = re.findall(r"```bash\n(.*?)\n```", quick, flags=re.S)
    assert len(commands) == 2
    assert "sciviz-gbuf demo" in commands[0]
    ci = (ROOT / ".ci" / "run").read_text()
    assert f"TEST_CMD='{commands[1]}'" in ci
