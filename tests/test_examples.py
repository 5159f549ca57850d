"""Every example script runs and writes the PNGs it promises."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "examples").glob("*.py"))


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_writes_pngs(script, tmp_path):
    r = subprocess.run(
        [sys.executable, str(script), str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert r.returncode == 0, r.stderr
    pngs = list(tmp_path.rglob("*.png"))
    assert pngs
    for p in pngs:
        with Image.open(p) as im:
            assert im.size[0] > 16 and im.size[1] > 16
            assert len(np.unique(np.asarray(im.convert("L")))) > 1  # not a blank picture
