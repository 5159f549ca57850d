"""Wrong files and silly values that used to succeed or fail obscurely (issue 46, point 5):
each gets one line naming the file or parameter and exit 2, and leaves nothing behind."""

from __future__ import annotations

import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import pyvista as pv
from PIL import Image

import sciviz_gbuf as sg
from sciviz_gbuf.apps.demo import run_demo
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.readers import read_mesh
from tests.helpers.cli import assert_clean_failure, checksums, run_cli


@pytest.fixture(scope="module")
def dem(tmp_path_factory):
    """An integer-metre ESRI ASCII grid of 120 x 90 cells of 10 m: a hill 150-300 m."""
    d = tmp_path_factory.mktemp("dem")
    y, x = np.mgrid[0:90, 0:120]
    z = np.rint(150 + 150 * np.exp(-((x - 60) ** 2 + (y - 45) ** 2) / 900.0)).astype(int)
    path = d / "hill.asc"
    rows = "\n".join(" ".join(map(str, r)) for r in z)
    path.write_text(
        f"ncols 120\nnrows 90\nxllcorner 500000\nyllcorner 4000000\ncellsize 10\n"
        f"NODATA_value -9999\n{rows}\n"
    )
    return path


def test_a_picture_is_not_a_mesh(tmp_path):
    png = tmp_path / "photo.png"
    Image.fromarray(np.zeros((20, 20, 3), np.uint8)).save(png)
    out = tmp_path / "out.png"
    before = checksums([png])
    line = assert_clean_failure(
        run_cli(["edges", png, "-o", out]), names=png, outputs=[out], inputs=before
    )
    assert "image, not a mesh" in line
    with pytest.raises(InputError, match="image, not a mesh"):
        read_mesh(png)


def test_a_dem_is_not_a_mesh(tmp_path, dem):
    out = tmp_path / "out.png"
    line = assert_clean_failure(run_cli(["mesh", dem, "-o", out]), names=dem, outputs=[out])
    assert "DEM" in line and "topo" in line


@pytest.mark.parametrize("command", ["edges", "mesh", "capture"])
def test_a_folder_is_not_a_mesh_file(tmp_path, command):
    folder = tmp_path / "scans"
    folder.mkdir()
    out = tmp_path / ("out.npz" if command == "capture" else "out.png")
    line = assert_clean_failure(run_cli([command, folder, "-o", out]), names=folder)
    assert "is a folder" in line and "no such" not in line


@pytest.mark.parametrize(
    ("args", "name"),
    [
        (["--size", "-5x10"], "--size"),
        (["--width", "-3"], "--width"),
        (["--crease-angle", "-.5"], "--crease-angle"),
    ],
)
def test_negative_values_reach_the_options_own_check(tmp_path, args, name):
    """argparse takes "-5x10" for an option ("expected one argument"): the value is attached."""
    mesh = tmp_path / "m.stl"
    pv.Sphere().save(mesh)
    out = tmp_path / "out.png"
    line = assert_clean_failure(run_cli(["edges", mesh, *args, "-o", out]), names=name)
    assert "expected one argument" not in line
    assert args[1] in line  # the value as given


def test_negative_contour_intervals_are_named(tmp_path, dem):
    out = tmp_path / "map.png"
    line = assert_clean_failure(
        run_cli(["topo", dem, "--contours", "-20,100", "-o", out]), names="--contours"
    )
    assert "-20,100" in line


@pytest.mark.parametrize("contours", ["0.0001", "0.05,0.25"])
def test_lines_closer_than_a_pixel_are_refused_with_the_useful_range(tmp_path, dem, contours):
    out = tmp_path / "map.png"
    line = assert_clean_failure(
        run_cli(["topo", dem, "--contours", contours, "-o", out]),
        names="major_interval",
        outputs=[out],
    )
    assert "px apart" in line and "expected at least" in line
    # the automatic choice it names draws a map of lines, not of ink
    major = float(line.split("major ")[-1].split(",")[0])
    proc = run_cli(["topo", dem, "--contours", f"{major / 5:g},{major:g}", "-o", out])
    assert proc.returncode == 0, proc.stderr
    grey = np.asarray(Image.open(out).convert("L")).astype(int)
    assert (grey < 90).mean() < 0.3  # the dark brown lines cover less than a third
    # busy but drawable spacings (1-2 px on the median slope) are left to the user
    busy = run_cli(["topo", dem, "--contours", "1,5", "-o", tmp_path / "busy.png"])
    assert busy.returncode == 0, busy.stderr


def test_major_interval_is_named_as_itself(dem):
    with pytest.raises(InputError, match=r"^major_interval"):
        sg.topographic_map(str(dem), interval=10, major_interval=-5)


def test_demo_refuses_thumbnail_sizes(tmp_path):
    out = tmp_path / "demo"
    line = assert_clean_failure(run_cli(["demo", "--size", "5x5", "-o", out]), names="window_size")
    assert "160x120" in line
    assert not out.exists()
    with pytest.raises(InputError, match="at least 160x120"):
        run_demo(out, window_size=(159, 400))


def test_an_interrupted_demo_leaves_no_empty_folder(tmp_path):
    out = tmp_path / "demo"
    proc = subprocess.Popen(
        [sys.executable, "-m", "sciviz_gbuf", "demo", "-o", str(out), "--no-progress"],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    for _ in range(1200):  # the folder is made once the libraries are loaded
        if out.exists() or proc.poll() is not None:
            break
        time.sleep(0.1)
    assert out.exists(), proc.communicate()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 2, err
    assert "Traceback" not in err
    # gone, unless a first figure was written before the signal arrived
    assert not out.exists() or any(out.iterdir())
