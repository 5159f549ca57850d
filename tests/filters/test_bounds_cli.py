"""Size-like parameters beyond their bounds, through the command line (issue 20, item 7):
each run exits 2 with one line naming the parameter, no traceback, no output left behind and
the inputs unchanged. Also the largest allowed capture under a memory cap (``ulimit -v``):
an InputError before any allocation, not ``std::bad_alloc``."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import pyvista as pv

from tests.helpers.cli import assert_clean_failure, checksums, run_cli


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """A small mesh, a small ESRI ASCII DEM and a two-patch .bpt file of our own."""
    d = tmp_path_factory.mktemp("bounds_inputs")
    pv.Sphere(theta_resolution=12, phi_resolution=12).save(d / "ball.vtp")
    z = (np.add.outer(np.arange(24.0), np.arange(20.0)) * 3.0).round(1)
    header = "ncols 20\nnrows 24\nxllcorner 0\nyllcorner 0\ncellsize 10\nNODATA_value -9999\n"
    (d / "hill.asc").write_text(header + "\n".join(" ".join(map(str, r)) for r in z) + "\n")
    net = "\n".join(
        f"{u / 3:g} {v / 3:g} {(u - 1.5) ** 2 / 9:g}" for u in range(4) for v in range(4)
    )
    (d / "two.bpt").write_text(f"2\n3 3\n{net}\n3 3\n{net.replace(' 0', ' 1')}\n")
    return d


# (command, input file, extra arguments, output name, the parameter the message must name).
# Values below a lower bound are refused by the command line's own option types (one line too).
CASES = [
    ("edges", "ball.vtp", ["--width", "nan"], "e.png", "--width"),
    ("edges", "ball.vtp", ["--width", "0.5"], "e.png", "--width"),
    ("edges", "ball.vtp", ["--width", "-1"], "e.png", "--width"),
    ("edges", "ball.vtp", ["--supersample", "0"], "e.png", "--supersample"),
    ("mesh", "ball.vtp", ["--levels", "0"], "m.png", "--levels"),
    ("topo", "hill.asc", ["--width", "nan"], "t.png", "--width"),
    ("topo", "hill.asc", ["--major-width", "-2"], "t.png", "--major-width"),
    ("edges", "ball.vtp", ["--width", "1e4"], "e.png", "width"),
    ("edges", "ball.vtp", ["--width", "65"], "e.png", "width"),
    ("edges", "ball.vtp", ["--supersample", "9"], "e.png", "supersample"),
    ("edges", "ball.vtp", ["--size", "16385x16"], "e.png", "window_size"),
    ("edges", "ball.vtp", ["--size", "8192x8192", "--supersample", "4"], "e.png", "window_size"),
    ("capture", "ball.vtp", ["--size", "20000x10"], "g.npz", "window_size"),
    ("capture", "ball.vtp", ["--supersample", "1000"], "g.npz", "supersample"),
    ("capture", "ball.vtp", ["--size", "4096x4096", "--supersample", "8"], "g.npz", "window_size"),
    ("mesh", "ball.vtp", ["--style", "toon", "--levels", "1000"], "m.png", "levels"),
    ("mesh", "ball.vtp", ["--supersample", "16"], "m.png", "supersample"),
    ("topo", "hill.asc", ["--width", "1e4"], "t.png", "width"),
    ("topo", "hill.asc", ["--major-width", "1e4"], "t.png", "major_width"),
    ("patches", "two.bpt", ["--stripes", "1e9"], "p.png", "stripes"),
    ("patches", "two.bpt", ["--width", "1e4"], "p.png", "width"),
    ("patches", "two.bpt", ["--resolution", "100000"], "p.png", "resolution"),
    ("patches", "two.bpt", ["--supersample", "9"], "p.png", "supersample"),
    ("patches", "two.bpt", ["--size", "16385x10"], "p.png", "window_size"),
]


@pytest.mark.parametrize(
    ("command", "source", "extra", "out", "name"),
    CASES,
    ids=[f"{c}-{' '.join(e)}" for c, _, e, _, _ in CASES],
)
def test_beyond_a_bound_is_one_clean_line(tmp_path, inputs, command, source, extra, out, name):
    before = checksums([inputs])
    output = tmp_path / out
    proc = run_cli([command, str(inputs / source), "-o", str(output), *extra], cwd=tmp_path)
    line = assert_clean_failure(proc, names=name, outputs=[output], inputs=before)
    assert "expected" in line or "exceeds" in line or "needs" in line, line


_CAPPED = textwrap.dedent(
    """
    import resource, sys
    import pyvista as pv
    import sciviz_gbuf as sg
    from sciviz_gbuf._validate import LIMITS

    ball = pv.Sphere()
    with open("/proc/self/statm") as f:
        used = int(f.read().split()[0]) * resource.getpagesize()
    cap = used + 2 * 2**30  # 2 GiB more than the process has mapped now
    resource.setrlimit(resource.RLIMIT_AS, (cap, cap))
    side = int(LIMITS["image_side"])
    try:
        sg.capture(ball, window_size=(side, side))
    except sg.InputError as exc:
        print("InputError", exc)
        sys.exit(0)
    print("no error")
    sys.exit(1)
    """
)


def test_largest_allowed_capture_under_a_memory_cap_is_refused(tmp_path):
    env = {**os.environ, "SCIVIZ_GBUF_NO_WARMUP": "1"}
    proc = subprocess.run(
        [sys.executable, "-c", _CAPPED],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        timeout=600,
        check=False,
    )
    assert proc.returncode == 0, (proc.returncode, proc.stdout, proc.stderr[-3000:])
    assert proc.stdout.startswith("InputError window_size:"), proc.stdout
    assert "GiB" in proc.stdout and "\n" not in proc.stdout.strip()
