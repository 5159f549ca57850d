"""The example notebook runs top to bottom headless, on a real CT series and on the bundled frog."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import nbformat
import numpy as np
import pytest
from nbclient import NotebookClient
from PIL import Image

from tests.helpers.paths import PROJECT_ROOT, SHARED_DATA

NOTEBOOK = PROJECT_ROOT / "examples" / "medical_enhancement.ipynb"
PHILIPS = SHARED_DATA / "ct" / "dcm_qa_ct_Philips_phantom_5mm"


def run_notebook(tmp_path: Path, monkeypatch, ct_dir: str) -> nbformat.NotebookNode:
    monkeypatch.setenv("SCIVIZ_CT_DIR", ct_dir)
    monkeypatch.setenv("SCIVIZ_OUT", str(tmp_path / "out"))
    monkeypatch.setenv("MPLBACKEND", "module://matplotlib_inline.backend_inline")
    # The kernel is started as "python": make that this interpreter (the test's environment).
    monkeypatch.setenv("PATH", str(Path(sys.executable).parent) + os.pathsep + os.environ["PATH"])
    nb = nbformat.read(NOTEBOOK, as_version=4)
    client = NotebookClient(
        nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    )
    client.execute()
    return nb


def _outputs(nb, kind: str) -> list:
    cells = [c for c in nb.cells if c.cell_type == "code"]
    return [o for c in cells for o in c.outputs if o.output_type == kind]


@pytest.mark.parametrize(
    "source",
    [
        pytest.param(
            "philips",
            marks=pytest.mark.skipif(not PHILIPS.is_dir(), reason="shared CT data not present"),
        ),
        "frog",
    ],
)
def test_notebook_runs_headless(tmp_path, monkeypatch, source):
    nb = run_notebook(tmp_path, monkeypatch, str(PHILIPS) if source == "philips" else "")
    assert not _outputs(nb, "error")
    text = "".join(o.get("text", "") for o in _outputs(nb, "stream"))
    assert "reloaded image identical: True" in text
    if source == "philips":
        assert "28 slices" in text
    # Every figure was drawn (inline PNGs), and the files were written.
    figures = [o for o in _outputs(nb, "display_data") if "image/png" in o.get("data", {})]
    assert len(figures) == 3
    out = tmp_path / "out"
    pair = np.asarray(Image.open(out / "ct_fig14_pair.png"))
    assert pair.shape[0] == 768 and pair.shape[1] > 2 * 768
    assert len(np.unique(pair[..., :3].reshape(-1, 3), axis=0)) > 100  # a picture, not blank
    assert (out / "ct_gbuffer.npz").is_file()
