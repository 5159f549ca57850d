"""Bad DEM and G-buffer files through the command line, as a careless user or an attacker would
pass them: every case exits 2 with one line naming the file, no traceback, no output left, the
input unchanged (issue 20: lying headers, truncation, damaged archives, out-of-range values)."""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path

import numpy as np
import pytest

from sciviz_gbuf.core.gbuffer import META_KEY
from tests.helpers.cli import assert_clean_failure, checksums, run_cli
from tests.helpers.paths import SHARED_DATA

rasterio = pytest.importorskip("rasterio")


def _npy_header(shape, descr="<f4") -> bytes:
    text = f"{{'descr': '{descr}', 'fortran_order': False, 'shape': {tuple(shape)}, }}"
    text += " " * (118 - len(text)) + "\n"
    return b"\x93NUMPY\x01\x00" + len(text).to_bytes(2, "little") + text.encode()


def _asc(ncols, nrows, cellsize=10.0, values=None, nodata=None) -> str:
    head = f"ncols {ncols}\nnrows {nrows}\nxllcorner 0\nyllcorner 0\ncellsize {cellsize}\n"
    if nodata is not None:
        head += f"nodata_value {nodata}\n"
    vals = values if values is not None else "1 " * max(ncols * nrows, 0)
    return head + vals + "\n"


def _tif(path: Path, values: np.ndarray, **profile) -> None:
    kw = {"driver": "GTiff", "width": values.shape[-1], "height": values.shape[-2]}
    kw.update(count=1 if values.ndim == 2 else values.shape[0], dtype=values.dtype.name)
    kw.update(profile)
    with rasterio.open(path, "w", **kw) as dst:
        dst.write(values if values.ndim == 3 else values[None])


def _make_dems(d: Path) -> dict[str, Path]:
    """name -> a bad DEM file in ``d``."""
    files: dict[str, bytes | str] = {}
    good = d / "_good.npy"
    np.save(good, np.arange(2500, dtype=np.float32).reshape(50, 50))
    g = good.read_bytes()
    good.unlink()
    files["truncated.npy"] = g[:500]
    files["header_only.npy"] = g[:60]
    files["garbage.npy"] = b"hello world" * 20
    files["empty.npy"] = b""
    files["huge_header.npy"] = _npy_header((1_000_000, 1_000_000)) + b"\0" * 64
    files["three_d.npy"] = _npy_header((4, 4, 4)) + b"\0" * 256
    files["complex.npy"] = _npy_header((4, 4), "<c8") + b"\0" * 128
    files["object.npy"] = _npy_header((4, 4), "|O") + b"\0" * 128
    files["zero_rows.npy"] = _npy_header((0, 5))
    files["not_a_zip.npz"] = b"PK\x03\x04" + b"garbage" * 40
    files["asc_negative_ncols.asc"] = _asc(-5, 3, values="1 2 3")
    files["asc_zero_rows.asc"] = _asc(4, 0, values="")
    files["asc_negative_cellsize.asc"] = _asc(2, 2, cellsize=-10)
    files["asc_nan_cellsize.asc"] = _asc(2, 2, cellsize="nan")
    files["asc_huge.asc"] = _asc(1_000_000, 1_000_000, values="1 2")
    files["asc_truncated.asc"] = _asc(10, 10, values="1 " * 37)
    files["asc_text.asc"] = _asc(2, 2, values="1 2 three 4")
    files["asc_no_header.asc"] = "1 2 3\n4 5 6\n"
    files["asc_all_nodata.asc"] = _asc(3, 3, values="-9999 " * 9, nodata=-9999)
    hgt = np.zeros((1201, 1201), ">i2").tobytes()
    files["N91E007.hgt"] = hgt
    files["S89W999.hgt"] = hgt
    files["N10W110_short.hgt"] = hgt[:-2]
    files["empty.tif"] = b""
    files["garbage.tif"] = b"II*\x00" + b"\xff" * 300
    for name, data in files.items():
        (d / name).write_bytes(data if isinstance(data, bytes) else data.encode())
    # archives with a damaged member, lying members and bad georeference scalars
    np.savez_compressed(d / "deflate.npz", heights=np.random.default_rng(0).random((200, 200)))
    raw = bytearray((d / "deflate.npz").read_bytes())
    raw[200:260] = b"\0" * 60
    (d / "deflate.npz").write_bytes(bytes(raw))
    with zipfile.ZipFile(d / "huge_member.npz", "w") as zf:
        zf.writestr("heights.npy", _npy_header((100_000, 100_000)) + b"\0" * 64)
    geo = {"elevation": np.ones((20, 20)), "dy": 1.0, "xmin": 0.0, "xmax": 1.0}
    geo |= {"ymin": 0.0, "ymax": 1.0}
    np.savez(d / "dx_array.npz", dx=np.array([1.0, 2.0]), **geo)
    np.savez(d / "dx_text.npz", dx=np.array("abc"), **geo)
    np.savez(d / "two_grids.npz", a=np.ones((3, 3)), b=np.ones((4, 4)))
    np.save(d / "all_nan.npy", np.full((8, 8), np.nan, np.float32))
    np.save(d / "beyond_float32.npy", np.full((8, 8), 1e300))
    _tif(d / "complex.tif", np.ones((8, 8), np.complex64))
    _tif(d / "rgb.tif", np.zeros((3, 8, 8), np.uint8))
    _tif(d / "_cut.tif", np.random.default_rng(1).random((300, 300)).astype(np.float32))
    cut = (d / "_cut.tif").read_bytes()
    (d / "_cut.tif").unlink()
    (d / "truncated.tif").write_bytes(cut[: len(cut) // 3])
    return {p.name: p for p in sorted(d.iterdir())}


@pytest.fixture(scope="module")
def dems(tmp_path_factory) -> dict[str, Path]:
    return _make_dems(tmp_path_factory.mktemp("bad_dems"))


DEM_CASES = [
    "truncated.npy",
    "header_only.npy",
    "garbage.npy",
    "empty.npy",
    "huge_header.npy",
    "three_d.npy",
    "complex.npy",
    "object.npy",
    "zero_rows.npy",
    "not_a_zip.npz",
    "deflate.npz",
    "huge_member.npz",
    "dx_array.npz",
    "dx_text.npz",
    "two_grids.npz",
    "asc_negative_ncols.asc",
    "asc_zero_rows.asc",
    "asc_negative_cellsize.asc",
    "asc_nan_cellsize.asc",
    "asc_huge.asc",
    "asc_truncated.asc",
    "asc_text.asc",
    "asc_no_header.asc",
    "asc_all_nodata.asc",
    "N91E007.hgt",
    "S89W999.hgt",
    "N10W110_short.hgt",
    "empty.tif",
    "garbage.tif",
    "truncated.tif",
    "complex.tif",
    "rgb.tif",
    "all_nan.npy",
    "beyond_float32.npy",
]


# Each bad file goes through topo or birdseye in turn; SCIVIZ_GBUF_FULL_CORPUS=1: both.
DEM_PAIRS = [
    (name, command)
    for k, name in enumerate(DEM_CASES)
    for j, command in enumerate(("topo", "birdseye"))
    if os.environ.get("SCIVIZ_GBUF_FULL_CORPUS") or j == k % 2
]


@pytest.mark.parametrize(("name", "command"), DEM_PAIRS)
def test_bad_dem_file_is_one_clean_line(dems, tmp_path, name, command):
    src = dems[name]
    before = checksums([src])
    out = tmp_path / "out.png"
    args = [command, src, "-o", out]
    if command == "birdseye":
        args += ["--size", "64x48", "--supersample", "1"]
    proc = run_cli(args, cwd=tmp_path)
    assert_clean_failure(proc, names=[src.name], outputs=[out], inputs=before)


LAZY_CASES = ["complex.tif", "rgb.tif", "garbage.tif", "empty.tif", "truncated.tif", "N91E007.hgt"]


@pytest.mark.parametrize("name", LAZY_CASES)
def test_bad_dem_file_out_of_core_is_one_clean_line(dems, tmp_path, name):
    src = dems[name]
    before = checksums([src])
    out = tmp_path / "out.tif"
    proc = run_cli(["topo", src, "-o", out, "--chunks", "64"], cwd=tmp_path)
    assert_clean_failure(proc, names=[src.name], outputs=[out], inputs=before)


def test_non_utf8_file_name(tmp_path):
    name = os.fsdecode(b"dem\xff.tif")
    try:
        _tif(tmp_path / "plain.tif", np.ones((8, 8), np.float32))
        os.rename(tmp_path / "plain.tif", tmp_path / name)
    except (OSError, UnicodeError):
        pytest.skip("this file system refuses non-UTF-8 names")
    for extra in ([], ["--chunks", "4"]):
        out = tmp_path / ("out.tif" if extra else "out.png")
        proc = run_cli(["topo", tmp_path / name, "-o", out, *extra], cwd=tmp_path)
        assert_clean_failure(proc, names=["dem", "not UTF-8"], outputs=[out])


# --------------------------------------------------------------------------- G-buffers
@pytest.fixture(scope="module")
def good_gbuffer(tmp_path_factory) -> Path:
    import pyvista as pv

    import sciviz_gbuf as sg

    path = tmp_path_factory.mktemp("gbuf") / "good.npz"
    sg.capture(pv.Sphere(), window_size=(32, 24), supersample=2).save(path)
    return path


def _tampered(src: Path, dst: Path, edit) -> Path:
    with np.load(src, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays[META_KEY]))
    edit(meta, arrays)
    arrays[META_KEY] = np.array(json.dumps(meta))
    np.savez(dst, **arrays)
    return dst


def _set(path: list, value):
    def edit(meta, arrays):
        d = meta
        for k in path[:-1]:
            d = d[k]
        d[path[-1]] = value

    return edit


GBUFFER_CASES = {
    "supersample_zero": _set(["supersample"], 0),
    "supersample_text": _set(["supersample"], "2"),
    "supersample_huge": _set(["supersample"], 10**6),
    "nan_camera": _set(["camera", "position"], [float("nan"), 0.0, 1.0]),
    "inf_matrix": _set(["camera", "view_matrix"], [float("inf")] * 16),
    "bad_clipping": _set(["camera", "clipping_range"], [5.0, 1.0]),
    "window_mismatch": _set(["camera", "window_size"], [1000, 10]),
    "zero_view_angle": _set(["camera", "view_angle"], 0.0),
    "short_vector": _set(["camera", "view_up"], [0.0, 1.0]),
    "newer_format": _set(["version"], 999),
    "missing_camera": lambda meta, arrays: meta.pop("camera"),
    "missing_channel": lambda meta, arrays: arrays.pop("normal"),
}


@pytest.mark.parametrize("case", sorted(GBUFFER_CASES))
def test_tampered_gbuffer_is_one_clean_line(good_gbuffer, tmp_path, case):
    src = _tampered(good_gbuffer, tmp_path / f"{case}.npz", GBUFFER_CASES[case])
    before = checksums([src])
    proc = run_cli(["info", src], cwd=tmp_path)
    assert_clean_failure(proc, names=[src.name], inputs=before)


@pytest.mark.parametrize(
    ("name", "data"),
    [
        ("garbage.npz", b"PK\x03\x04" + b"x" * 100),
        ("empty.npz", b""),
        ("text.vti", b"<VTKFile>not really</VTKFile>"),
        ("empty.vti", b""),
    ],
)
def test_damaged_gbuffer_file_is_one_clean_line(tmp_path, name, data):
    src = tmp_path / name
    src.write_bytes(data)
    proc = run_cli(["info", src], cwd=tmp_path)
    assert_clean_failure(proc, names=[src.name], inputs=checksums([src]))


def test_truncated_gbuffer_is_one_clean_line(good_gbuffer, tmp_path):
    raw = good_gbuffer.read_bytes()
    for k, cut in enumerate((len(raw) // 2, len(raw) - 30, 100)):
        src = tmp_path / f"cut{k}.npz"
        src.write_bytes(raw[:cut])
        proc = run_cli(["info", src], cwd=tmp_path)
        assert_clean_failure(proc, names=[src.name], inputs=checksums([src]))


def test_good_files_still_work(tmp_path, good_gbuffer):
    """The checks refuse only what is wrong: the real DEMs and a real G-buffer still go."""
    assert run_cli(["info", good_gbuffer], cwd=tmp_path).returncode == 0
    dem = SHARED_DATA / "dem" / "hugo_site.asc"
    if not dem.is_file():
        pytest.skip("../shared/data is not beside the project")
    out = tmp_path / "hugo.png"
    proc = run_cli(["topo", dem, "-o", out], cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert out.is_file()
