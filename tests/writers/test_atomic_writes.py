"""Outputs are complete or absent (issue 20, item 2 and the disk-full part of item 5).

A full disk is made two ways: a real small file system (a 200 KiB tmpfs, mounted here when
the test runs as root and may mount; skipped otherwise), and, everywhere, a file size limit
(``RLIMIT_FSIZE`` in the child process: writes past it fail with ``EFBIG``, a real OS error,
like a full disk; Python ignores the ``SIGXFSZ`` that comes with it). Each case runs the
command line in a subprocess and checks, with ``tests.helpers.cli.assert_clean_failure``,
exit status 2, one line naming the file, no traceback, no output and no temporary left, the
inputs unchanged. The Python API is checked the same way (``OutputError``), and SIGTERM /
SIGINT during a long ``.tif`` write.
"""

from __future__ import annotations

import os
import resource
import shutil
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path

import numpy as np
import pytest

from sciviz_gbuf._atomic import (
    Interrupted,
    atomic_output,
    native_stderr,
    one_line,
    output_group,
    raising_signals,
)
from sciviz_gbuf.errors import OutputError
from tests.helpers.cli import assert_clean_failure, checksums

#: Size of the small file system: every output of the cases below is larger.
SMALL_DISK = "200k"
#: File size limit of the child processes: below every output of the cases, above anything
#: else the command line writes (it writes nothing else once numba's cache is warm).
FSIZE_LIMIT = 100_000
#: A transform for the API writers (10 m cells, north up).
TRANSFORM = (500000.0, 10.0, 0.0, 4004000.0, 0.0, -10.0)


# ----------------------------------------------------------------------------- the disks
def _mount_small_disk(where: Path) -> bool:
    where.mkdir(parents=True, exist_ok=True)
    mount = shutil.which("mount")
    if mount is None or os.geteuid() != 0:
        return False
    proc = subprocess.run(
        [mount, "-t", "tmpfs", "-o", f"size={SMALL_DISK}", "tmpfs", str(where)],
        capture_output=True,
        stdin=subprocess.DEVNULL,
    )
    return proc.returncode == 0


def _unmount(where: Path) -> None:
    subprocess.run(["umount", "-l", str(where)], capture_output=True, stdin=subprocess.DEVNULL)


@pytest.fixture
def small_disk(tmp_path):
    """A 200 KiB tmpfs (skip where mounting is not permitted)."""
    where = tmp_path / "small"
    if not _mount_small_disk(where):
        pytest.skip("cannot mount a tmpfs here (needs root and the permission to mount)")
    try:
        yield where
    finally:
        _unmount(where)


def _limit_file_size(limit: int):
    def apply() -> None:  # in the child, before exec: inherited by the interpreter
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.RLIM_INFINITY))

    return apply


def run(args, *, limit: int | None = None, timeout: float = 600.0) -> subprocess.CompletedProcess:
    """``python -m sciviz_gbuf ARGS`` like ``tests.helpers.cli.run_cli``, optionally under a
    file size limit."""
    return subprocess.run(
        [sys.executable, "-m", "sciviz_gbuf", *map(str, args)],
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        errors="replace",
        timeout=timeout,
        preexec_fn=None if limit is None else _limit_file_size(limit),
    )


def _listing(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


# ----------------------------------------------------------------------------- inputs
@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> Path:
    """A 400 x 400 DEM (``.asc``, georeferenced, rough enough that its maps do not compress
    below the limits) and a finely tessellated sphere (``.stl``)."""
    import pyvista as pv

    folder = tmp_path_factory.mktemp("inputs")
    rng = np.random.default_rng(3)
    n = 400
    y, x = np.mgrid[0:n, 0:n]
    z = 300 + 80 * np.sin(x / 37.0) * np.cos(y / 53.0) + 20 * rng.standard_normal((n, n))
    with open(folder / "dem.asc", "w") as f:
        f.write(f"ncols {n}\nnrows {n}\nxllcorner 500000\nyllcorner 4000000\n")
        f.write("cellsize 10\nNODATA_value -9999\n")
        np.savetxt(f, z, fmt="%.2f")
    pv.Sphere(theta_resolution=80, phi_resolution=80).save(folder / "ball.stl")
    return folder


# Each case: the command (``{in}`` the inputs, ``{big}`` the folder of the outputs that
# overflow, ``{ok}`` of those that would fit) and the outputs it names. With the file size
# limit every output overflows (``{ok}`` is ``{big}``), and the first one written fails; on
# the small disk only the ``{big}`` ones do. Either way none of the outputs may be left: the
# outputs of one command are renamed together at its end.
CLI_CASES = {
    "capture-npz": (
        ["capture", "{in}/ball.stl", "-o", "{big}/g.npz", "--size", "320x240"],
        ["{big}/g.npz"],
    ),
    "capture-vti": (
        ["capture", "{in}/ball.stl", "-o", "{big}/g.vti", "--size", "320x240"],
        ["{big}/g.vti"],
    ),
    "topo-png": (["topo", "{in}/dem.asc", "-o", "{big}/map.png"], ["{big}/map.png"]),
    "topo-cog": (["topo", "{in}/dem.asc", "-o", "{big}/map.tif"], ["{big}/map.tif"]),
    "topo-geotiff": (
        ["topo", "{in}/dem.asc", "-o", "{ok}/map.png", "--geotiff", "{big}/geo.tif"],
        ["{ok}/map.png", "{big}/geo.tif"],
    ),
    "topo-cog-overview": (
        ["topo", "{in}/dem.asc", "-o", "{big}/map.tif", "--overview", "{ok}/ov.png"],
        ["{big}/map.tif", "{ok}/ov.png"],
    ),
    "topo-overview-png": (
        [
            *["topo", "{in}/dem.asc", "-o", "{ok}/map.tif"],
            *["--overview", "{big}/ov.png", "--overview-size", "400"],
        ],
        ["{ok}/map.tif", "{big}/ov.png"],
    ),
    "birdseye-save-gbuffer": (
        [
            *["birdseye", "{in}/dem.asc", "-o", "{ok}/bird.png", "--size", "320x240"],
            *["--supersample", "1", "--save-gbuffer", "{big}/bird.npz"],
        ],
        ["{ok}/bird.png", "{big}/bird.npz"],
    ),
}


def _fill(items, **where) -> list[str]:
    out = []
    for item in items:
        for key, folder in where.items():
            item = item.replace("{" + key + "}", str(folder))
        out.append(item)
    return out


@pytest.mark.parametrize("case", sorted(CLI_CASES))
def test_cli_file_size_limit(case, inputs, tmp_path):
    """Writes past ``RLIMIT_FSIZE`` fail with EFBIG: exit 2, one line naming the file, no
    output, no temporary. The same command without the limit succeeds (the control)."""
    args, outputs = CLI_CASES[case]
    ok = tmp_path / "control"
    ok.mkdir()
    control = run(_fill(args, **{"in": inputs, "big": ok, "ok": ok}))
    assert control.returncode == 0, control.stderr[-3000:]
    for out in _fill([o for o in outputs if o.startswith("{big}")], big=ok):
        assert os.path.getsize(out) > FSIZE_LIMIT, out  # the case really overflows

    before = checksums([inputs])
    out_dir = tmp_path / "limited"
    out_dir.mkdir()
    names = _fill(outputs, big=out_dir, ok=out_dir)
    proc = run(_fill(args, **{"in": inputs, "big": out_dir, "ok": out_dir}), limit=FSIZE_LIMIT)
    line = assert_clean_failure(proc, names=names, outputs=names, inputs=before)
    assert "write failed" in line and "File too large" in line, line
    assert _listing(out_dir) == []


@pytest.mark.parametrize("case", sorted(CLI_CASES))
def test_cli_full_disk(case, inputs, tmp_path, small_disk):
    """A real full disk (ENOSPC): the same, and the outputs that would have fit elsewhere
    are not left either."""
    args, outputs = CLI_CASES[case]
    ok = tmp_path / "fits"
    ok.mkdir()
    before = checksums([inputs])
    big = _fill([o for o in outputs if o.startswith("{big}")], big=small_disk)
    names = _fill(outputs, big=small_disk, ok=ok)
    proc = run(_fill(args, **{"in": inputs, "big": small_disk, "ok": ok}))
    line = assert_clean_failure(proc, names=big, outputs=names, inputs=before)
    assert "No space left on device" in line, line
    assert _listing(small_disk) == [] and _listing(ok) == []


def test_cli_output_is_a_folder(inputs, tmp_path):
    """An output name taken by a folder: the rename fails (an OS error too), nothing left."""
    (tmp_path / "g.npz").mkdir()
    out = tmp_path / "g.npz"
    proc = run(["capture", inputs / "ball.stl", "-o", out, "--size", "64x48"])
    line = assert_clean_failure(proc, names=str(out), inputs=checksums([inputs]))
    assert "write failed" in line and out.is_dir() and _listing(out) == []
    assert _listing(tmp_path) == ["g.npz"]


# ----------------------------------------------------------------------------- the API
def _image(shape=(600, 700, 4)) -> np.ndarray:
    return np.random.default_rng(0).random(shape)  # noise: does not compress


def _api_writers():
    """``(name, file, write(path))`` of every public writer, each output > 200 KiB."""
    import dask.array as da

    from sciviz_gbuf.compose import write_geotiff, write_png
    from sciviz_gbuf.writers.cog import write_cog

    image = _image()
    return [
        ("png", "x.png", lambda p: write_png(p, image)),
        # >= LARGE_IMAGE pixels: the multithreaded encoder
        ("png-large", "x.png", lambda p: write_png(p, _image((2000, 2000, 3)))),
        ("geotiff", "x.tif", lambda p: write_geotiff(p, image, transform=TRANSFORM)),
        ("cog", "x.tif", lambda p: write_cog(image, p, transform=TRANSFORM)),
        (
            "cog-dask",
            "x.tif",
            lambda p: write_cog(da.from_array(image, chunks=(256, 256, 4)), p, transform=TRANSFORM),
        ),
    ]


@pytest.fixture(scope="module")
def gbuffer():
    import pyvista as pv

    from sciviz_gbuf import capture

    return capture(pv.Sphere(theta_resolution=60, phi_resolution=60), window_size=(320, 240))


def _check_api_failure(exc: OutputError, target: Path) -> None:
    text = str(exc)
    assert "\n" not in text and str(target) in text and "write failed" in text, text
    assert _listing(target.parent) == [], _listing(target.parent)


@pytest.mark.parametrize("name", ["png", "png-large", "geotiff", "cog", "cog-dask"])
def test_api_writers_full_disk(name, small_disk):
    _, file, write = next(w for w in _api_writers() if w[0] == name)
    target = small_disk / file
    with pytest.raises(OutputError) as info:
        write(target)
    _check_api_failure(info.value, target)


@pytest.mark.parametrize("suffix", [".npz", ".vti"])
def test_api_gbuffer_save_full_disk(suffix, gbuffer, small_disk):
    target = small_disk / f"g{suffix}"
    with pytest.raises(OutputError) as info:
        gbuffer.save(target)
    _check_api_failure(info.value, target)


def test_api_cog_overview_full_disk(tmp_path, small_disk):
    """The preview does not fit: the COG (in a folder with room) is not left either."""
    from sciviz_gbuf.writers.cog import write_cog

    cog, png = tmp_path / "fits" / "m.tif", small_disk / "ov.png"
    cog.parent.mkdir()
    with pytest.raises(OutputError) as info:
        write_cog(_image(), cog, transform=TRANSFORM, overview_png=png, overview_size=700)
    _check_api_failure(info.value, png)
    assert _listing(cog.parent) == []


def test_api_failed_write_keeps_the_old_file(small_disk):
    """A write over an existing file that fails leaves the old file as it was (a writer
    that truncates in place would have destroyed it)."""
    from sciviz_gbuf.compose import write_png

    target = small_disk / "x.png"
    write_png(target, np.zeros((8, 8)))
    old = target.read_bytes()
    with pytest.raises(OutputError):
        write_png(target, _image())
    assert target.read_bytes() == old and _listing(small_disk) == ["x.png"]


API_SCRIPT = """
import sys
from pathlib import Path
import numpy as np
sys.path.insert(0, {root!r})
from tests.writers.test_atomic_writes import _api_writers
from sciviz_gbuf.errors import OutputError
import resource, pyvista as pv
from sciviz_gbuf import capture
gb = capture(pv.Sphere(theta_resolution=60, phi_resolution=60), window_size=(320, 240))
writers = _api_writers() + [
    ("npz", "g.npz", gb.save), ("vti", "g.vti", gb.save),
]
resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, resource.RLIM_INFINITY))
for name, file, write in writers:
    folder = Path({out!r}) / name
    folder.mkdir()
    try:
        write(folder / file)
        print(name, "no error")
    except OutputError as exc:
        print(name, "|", exc, "|", sorted(p.name for p in folder.iterdir()))
"""


def test_api_writers_file_size_limit(tmp_path):
    """Every writer of the Python API under ``RLIMIT_FSIZE``, in a child process."""
    root = str(Path(__file__).resolve().parents[2])
    script = API_SCRIPT.format(root=root, limit=FSIZE_LIMIT, out=str(tmp_path))
    proc = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    rows = [ln.split(" | ") for ln in proc.stdout.splitlines() if " | " in ln]
    assert {r[0] for r in rows} == {"png", "png-large", "geotiff", "cog", "cog-dask", "npz", "vti"}
    for name, message, left in rows:
        assert "write failed" in message and "File too large" in message, (name, message)
        assert left == "[]", (name, left)
    assert proc.stderr.strip() == "", proc.stderr  # GDAL's and VTK's prints were folded in


# ----------------------------------------------------------------------------- signals
@pytest.fixture(scope="module")
def big_dem(tmp_path_factory) -> Path:
    """A 3000 x 3000 DEM: its COG takes seconds to write."""
    n = 3000
    y, x = np.mgrid[0:n, 0:n].astype(np.float32)
    z = 300 + 80 * np.sin(x / 97.0) * np.cos(y / 153.0)
    z += np.random.default_rng(1).standard_normal((n, n)).astype(np.float32) * 3
    path = tmp_path_factory.mktemp("big") / "big.npy"
    np.save(path, z.astype(np.float32))
    return path


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_signal_during_tif_write(signum, big_dem, tmp_path):
    """A signal once the output's temporary exists: exit 2, one line naming the output, no
    file and no hidden temporary left."""
    out = tmp_path / "out.tif"
    before = checksums([big_dem])
    # no contours: the map is quick, the write (the part under test) still takes seconds
    cmd = [sys.executable, "-m", "sciviz_gbuf", "topo", str(big_dem), "-o", str(out)]
    proc = subprocess.Popen(
        [*cmd, "--contours", "none"],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 600
        while not any(p.name.startswith(".out.tif") for p in tmp_path.iterdir()):
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "no temporary appeared"
            time.sleep(0.005)
        proc.send_signal(signum)
        stdout, stderr = proc.communicate(timeout=600)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    done = subprocess.CompletedProcess(proc.args, proc.returncode, stdout, stderr)
    line = assert_clean_failure(done, names=str(out), outputs=[out], inputs=before)
    assert f"interrupted by {signal.Signals(signum).name}" in line, line
    assert _listing(tmp_path) == []


# ----------------------------------------------------------------------------- _atomic itself
def test_atomic_output_renames_only_a_whole_file(tmp_path):
    target = tmp_path / "a.bin"
    with atomic_output(target) as part:
        assert part.path.parent == tmp_path and part.path.name.startswith(".a.bin.")
        assert part.path.name.endswith(".part")
        part.path.write_bytes(b"abc")
        assert not target.exists()
    assert target.read_bytes() == b"abc" and _listing(tmp_path) == ["a.bin"]

    with pytest.raises(OutputError, match=r"a\.bin: write failed \(3 bytes on disk of 4"):
        with atomic_output(target) as part:
            part.path.write_bytes(b"xyz")
            part.expected_size = 4
    with pytest.raises(OutputError, match="produced no file"):
        with atomic_output(target):
            pass
    assert target.read_bytes() == b"abc" and _listing(tmp_path) == ["a.bin"]


def test_atomic_output_removes_the_temporary_on_any_exception(tmp_path):
    target = tmp_path / "b.bin"
    with pytest.raises(ValueError, match="boom"):  # not ours: passed on unchanged
        with atomic_output(target) as part:
            part.path.write_bytes(b"x")
            (tmp_path / f"{part.path.name}.aux.xml").write_text("x")  # a native side file
            raise ValueError("boom")
    with pytest.raises(OutputError, match=r"b\.bin: write failed \(No space left on device\)"):
        with atomic_output(target) as part:
            part.path.write_bytes(b"x")
            raise OSError(28, "No space left on device")
    with pytest.raises(Interrupted) as info:
        with atomic_output(target) as part:
            part.path.write_bytes(b"x")
            raise Interrupted(signal.SIGTERM)
    assert info.value.outputs == [str(target)]
    assert str(info.value) == f"interrupted by SIGTERM: {target} not written"
    assert _listing(tmp_path) == []


def test_native_output_folded_into_one_line(tmp_path):
    target = tmp_path / "c.bin"
    with pytest.raises(OutputError) as info:
        with atomic_output(target) as part:
            with part.native():
                os.write(2, b"\x1b[31mERROR 1: disk\nfull\x1b[0m\nERROR 1: disk\n")
            part.fail("the library said no")
    text = str(info.value)
    assert text == (
        f"{target}: write failed (the library said no; ERROR 1: disk full); "
        "the file was not written"
    )
    assert one_line("a\n  b\tc", limit=4) == "a..."


def test_native_output_of_a_good_write_reaches_stderr(tmp_path, capfd):
    with atomic_output(tmp_path / "d.bin") as part:
        with part.native():
            os.write(2, b"GDAL warning\n")
        part.path.write_bytes(b"d")
        assert "GDAL warning" not in capfd.readouterr().err  # held back until the end
    assert capfd.readouterr().err == "GDAL warning\n"


def test_output_group_all_or_none(tmp_path):
    first, second = tmp_path / "first.png", tmp_path / "second.tif"
    with pytest.raises(OutputError, match=r"second\.tif"):
        with output_group():
            with atomic_output(first) as part:
                part.path.write_bytes(b"1")
            assert not first.exists()  # renamed only when the group ends
            with atomic_output(second) as part:
                raise OSError(27, "File too large")
    assert _listing(tmp_path) == []
    with output_group():
        for target in (first, second):
            with atomic_output(target) as part:
                part.path.write_bytes(target.name.encode())
    assert first.read_bytes() == b"first.png" and _listing(tmp_path) == [first.name, second.name]


def test_raising_signals_turns_sigterm_into_interrupted():
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(Interrupted) as info:
        with raising_signals():
            os.kill(os.getpid(), signal.SIGTERM)
            for _ in range(1000):  # the handler runs between bytecodes
                time.sleep(0.001)
    assert info.value.signum == signal.SIGTERM
    assert signal.getsignal(signal.SIGTERM) == before


def test_temporary_names_are_unique(tmp_path):
    names = set()
    for _ in range(50):
        with atomic_output(tmp_path / "e.bin") as part:
            names.add(part.path.name)
            part.path.write_bytes(uuid.uuid4().bytes)
    assert len(names) == 50 and _listing(tmp_path) == ["e.bin"]


def test_a_signal_during_a_cog_write_stops_it_and_leaves_nothing(tmp_path):
    """SIGTERM while write_cog is encoding (tiles deflate on helper threads, the main thread
    stores them) raises at once in the main thread; the output, its scratch files and the
    preview are all gone."""
    import threading

    from sciviz_gbuf._atomic import Interrupted, raising_signals
    from sciviz_gbuf.writers.cog import write_cog

    noise = np.random.default_rng(0).integers(0, 256, (4000, 4000, 4), dtype=np.uint8)

    def signal_once_encoding() -> None:
        for _ in range(4000):
            if any(p.name.endswith(".tiles.part") for p in tmp_path.iterdir()):
                break
            time.sleep(0.002)
        os.kill(os.getpid(), signal.SIGTERM)

    threading.Thread(target=signal_once_encoding, daemon=True).start()
    with pytest.raises(Interrupted), raising_signals():
        write_cog(noise, tmp_path / "m.tif", transform=TRANSFORM, overview_png=tmp_path / "o.png")
    assert _listing(tmp_path) == []


@pytest.mark.parametrize("step", [1, 2], ids=["while-redirecting", "while-restoring"])
def test_signal_while_descriptor_2_is_swapped(step, monkeypatch):
    """A SIGINT that arrives between the steps that swap descriptor 2 and ``sys.stderr`` is
    raised once they are all done: descriptor 2 and ``sys.stderr`` are what they were, so the
    CLI's one error line reaches the terminal (it was lost in a CI run, stderr empty)."""
    import sciviz_gbuf._atomic as atomic

    before = os.fstat(2)
    stderr_before = sys.stderr
    calls = []
    flush = atomic._flush_stderr

    def flush_then_signal() -> None:
        flush()
        calls.append(1)
        if len(calls) == step:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.01)  # the handler would run here, between two bytecodes

    monkeypatch.setattr(atomic, "_flush_stderr", flush_then_signal)
    box: list[str] = []
    with pytest.raises(Interrupted) as info:
        with raising_signals():
            with native_stderr() as captured:
                box = captured
                os.write(2, b"captured text\n")
                time.sleep(0.01)
    after = os.fstat(2)
    assert info.value.signum == signal.SIGINT
    assert (after.st_dev, after.st_ino) == (before.st_dev, before.st_ino)
    assert sys.stderr is stderr_before
    # interrupted as the capture began: the block did not run; else its text was kept
    assert box == ([] if step == 1 else ["captured text\n"])
    assert not atomic._DEFER["depth"] and not atomic._DEFER["pending"]
