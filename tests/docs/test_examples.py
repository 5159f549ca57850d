"""Every example script runs and writes the PNGs it promises."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from tests.helpers.paths import PROJECT_ROOT

EXAMPLES = sorted((PROJECT_ROOT / "examples").glob("*.py"))


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
