"""The sciviz-gbuf command line and the mesh reader, on real data."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import sciviz_gbuf as sg
from sciviz_gbuf.cli import main
from sciviz_gbuf.readers import read_mesh


def test_capture_and_info_on_the_cad_part(shared_data, tmp_path, capsys):
    stl = shared_data / "meshes" / "vtkdata_42400-IDGH.stl"
    before = stl.read_bytes()
    out = tmp_path / "part.npz"
    assert (
        main(
            ["capture", str(stl), "-o", str(out), "--size", "200x150", "--view", "xy", "--parallel"]
        )
        == 0
    )
    g = sg.GBuffer.load(out)
    assert g.shape == (150, 200) and g.camera.parallel_projection
    mesh = read_mesh(stl)
    assert g.cell_id[g.mask].max() < mesh.n_cells
    # looking down -z in parallel projection: world x/y of a pixel is its position on screen
    xs = g.world[..., 0][g.mask]
    assert xs.min() >= mesh.bounds[0] - 1e-3 and xs.max() <= mesh.bounds[1] + 1e-3
    assert stl.read_bytes() == before  # input file untouched
    assert main(["info", str(out)]) == 0
    assert "cell_id" in capsys.readouterr().out


def test_cli_errors_are_clear(tmp_path, capsys):
    assert main(["capture", str(tmp_path / "none.stl"), "-o", str(tmp_path / "x.npz")]) == 2
    assert "none.stl: no such mesh file" in capsys.readouterr().err
    bad = tmp_path / "bad.stl"
    bad.write_text("solid nothing\nendsolid nothing\n")
    assert main(["capture", str(bad), "-o", str(tmp_path / "x.npz")]) == 2
    assert "bad.stl" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["capture", "a.stl", "-o", "x.npz", "--size", "12by4"])


def test_read_mesh_rejects_unknown_format(tmp_path):
    f = tmp_path / "mesh.xyz123"
    f.write_text("1 2 3\n")
    with pytest.raises(sg.InputError, match=r"mesh\.xyz123"):
        read_mesh(f)


def test_python_m_entry_point():
    r = subprocess.run(
        [sys.executable, "-m", "sciviz_gbuf", "--version"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert r.returncode == 0 and sg.__version__ in r.stdout


def test_read_mesh_returns_the_points(shared_data):
    m = read_mesh(shared_data / "meshes" / "vtkdata_42400-IDGH.stl")
    assert m.n_cells == 11036
    assert np.isfinite(np.asarray(m.points)).all()
