"""Bad mesh files and degenerate scenes: a clean one-line refusal, never a crash or a blank.

The corpus (:mod:`tests.readers._bad_mesh_corpus`) goes through the command line in processes
of their own (``edges``, ``capture`` and ``mesh`` on every file): exit 2, one stderr line
naming the file, no traceback, no signal death, no output or temporary left, the input
unchanged. The first file of each command runs in a fresh interpreter, the others in children
forked from a warm one (:mod:`tests.helpers.fork_cli`: the same CLI, its own process, without
the 1.3 s of imports each).
The in-process tests give ``capture`` bad in-memory datasets and tiny or far-off meshes.
"""

from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest
import pyvista as pv

import sciviz_gbuf as sg
from sciviz_gbuf.readers import read_mesh
from tests.helpers.cli import assert_clean_failure, checksums, run_cli
from tests.helpers.fork_cli import ForkCli

from ._bad_mesh_corpus import CASES, valid_files

COMMANDS = {"edges": "out.png", "capture": "g.npz", "mesh": "m.png"}
# Each bad file goes through one of the commands in turn (every format and fault still meets
# every command across the corpus); SCIVIZ_GBUF_FULL_CORPUS=1 runs every file through every
# command (405 runs, a quarter of an hour on 2 cores: too long for every CI run).
FULL_CORPUS = bool(os.environ.get("SCIVIZ_GBUF_FULL_CORPUS"))
PAIRS = [
    (cid, cmd)
    for k, (cid, _, _) in enumerate(CASES)
    for j, cmd in enumerate(COMMANDS)
    if FULL_CORPUS or j == k % len(COMMANDS)
]
# Bytes inverted inside the numbers of a binary body, or a cut that only loses trailing
# metadata, can leave a file that is still a whole mesh: drawing it is then right too.
MAY_STILL_BE_A_MESH = ("flip", "cut97")

SPHERE = pv.Sphere(theta_resolution=16, phi_resolution=16)
SPHERE64 = SPHERE.copy()
SPHERE64.points = SPHERE.points.astype(np.float64)


@pytest.fixture(scope="module")
def corpus_runs(tmp_path_factory):
    """Every case through every command, two processes at a time (each takes seconds)."""
    root = tmp_path_factory.mktemp("bad_meshes")
    jobs = []
    wanted = set(PAIRS)
    for cid, name, content in CASES:
        for cmd, out in COMMANDS.items():
            if (cid, cmd) not in wanted:
                continue
            d = root / cid / cmd
            d.mkdir(parents=True)
            (d / name).write_bytes(content)
            jobs.append((cid, cmd, d, d / name, d / out))

    fresh = {
        next(j for j in jobs if j[1] == cmd) for cmd in COMMANDS if any(j[1] == cmd for j in jobs)
    }
    servers = threading.local()
    started = []

    def run(job):
        cid, cmd, d, src, out = job
        before = checksums([src])
        args = [cmd, src.name, "-o", out.name, "--size", "64x48"]
        if job in fresh:
            proc = run_cli(args, cwd=d, timeout=240)
        else:
            if not hasattr(servers, "cli"):
                servers.cli = ForkCli()
                started.append(servers.cli)
            proc = servers.cli.run(args, cwd=d, timeout=240)
        return (cid, cmd), (proc, src, out, before)

    try:
        with ThreadPoolExecutor(2) as pool:
            return dict(pool.map(run, jobs))
    finally:
        for server in started:
            server.close()


@pytest.mark.parametrize(("case", "cmd"), PAIRS)
def test_bad_mesh_file_through_the_cli(corpus_runs, case, cmd):
    proc, src, out, before = corpus_runs[case, cmd]
    assert proc.returncode not in (-11, -6, 139, 134), f"killed by a signal: {proc.stderr[-2000:]}"
    if proc.returncode == 0 and any(tag in case for tag in MAY_STILL_BE_A_MESH):
        assert out.exists() and checksums([src]) == before
        assert proc.stderr.strip() == "", proc.stderr
        if out.suffix == ".npz":
            assert sg.GBuffer.load(out).mask.any(), "a blank capture reported as success"
        return
    line = assert_clean_failure(proc, names=src.name, outputs=[out], inputs=before)
    assert "\x1b[" not in line and "vtk" not in line.split(":")[0].lower()


def test_corpus_covers_every_format_and_fault():
    ids = [c[0] for c in CASES]
    assert len(ids) == len(set(ids)) >= 120
    for fmt in ("stl_bin", "stl_ascii", "ply_bin", "ply_ascii", "obj", "vtp", "vtu", "vtk"):
        assert any(i.startswith(fmt) and "cut" in i for i in ids), fmt
    for fault in ("past", "negative", "nan", "inf", "zeroarea", "lines-only", "1e9", "empty"):
        assert any(fault in i for i in ids), fault


@pytest.mark.parametrize("name", list(valid_files()))
def test_the_good_files_of_the_corpus_read(tmp_path, name):
    p = tmp_path / name
    p.write_bytes(valid_files()[name])
    mesh = read_mesh(p)
    assert mesh.n_cells == 36 and mesh.n_points >= 20
    assert sg.capture(mesh, window_size=(32, 24)).mask.any()


def test_shared_cad_part_still_reads(shared_data):
    stl = shared_data / "meshes" / "vtkdata_42400-IDGH.stl"
    assert read_mesh(stl).n_cells == 11036


def test_vtk_reports_are_folded_not_printed(tmp_path, capfd):
    bad = tmp_path / "cut.vtp"
    bad.write_bytes(valid_files()["vtp_bin.vtp"][:500])
    with pytest.raises(sg.InputError) as err:
        read_mesh(bad)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(str(bad)) and "XML" in msg
    captured = capfd.readouterr()
    assert captured.err == "" and captured.out == ""


def test_file_name_reaches_capture_errors(tmp_path):
    """A file that reads but has nothing to draw: the capture names the file."""
    p = tmp_path / "lines.vtp"
    pv.Line(resolution=3).save(p)
    mesh = read_mesh(p)
    with pytest.raises(sg.InputError, match=rf"^{p}: the dataset has no surface"):
        sg.capture(mesh, window_size=(16, 16))


# ---------------------------------------------------------------------- in-memory datasets


def _poly(points, faces) -> pv.PolyData:
    """PolyData with exactly these faces (no checks, as a careless caller would build it)."""
    poly = pv.PolyData()
    poly.points = np.asarray(points, dtype=np.float64)
    cells = pv.CellArray()
    faces = np.asarray(faces, dtype=np.int64)
    cells.SetData(
        pv.numpy_to_idarr(np.arange(0, faces.size + 1, faces.shape[1])),
        pv.numpy_to_idarr(faces.ravel()),
    )
    poly.SetPolys(cells)
    return poly


def _ugrid(points, conn, offsets, types) -> pv.UnstructuredGrid:
    grid = pv.UnstructuredGrid()
    grid.points = np.asarray(points, dtype=np.float64)
    cells = pv.CellArray()
    cells.SetData(pv.numpy_to_idarr(offsets), pv.numpy_to_idarr(conn))
    grid.SetCells(pv.convert_array(np.asarray(types, dtype=np.uint8)), cells)
    return grid


TRI = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5]], dtype=float)


@pytest.mark.parametrize(
    ("scene", "match"),
    [
        (_poly(TRI, [[0, 1, 2], [1, 2, 7]]), r"dataset 0 \(PolyData\): polygon connectivity "
         r"refers to point 7 but the mesh has 4 points"),
        (_poly(TRI, [[0, 1, 2], [1, -3, 2]]), r"dataset 0 \(PolyData\): .*negative point index"),
        ([SPHERE, _poly(TRI, [[0, 1, 9]])], r"dataset 1 \(PolyData\): polygon connectivity"),
        (_ugrid(TRI, [0, 1, 2, 3], [0, 4], [5]), r"cell 0 is a TRIANGLE with 4 points"),
        (_ugrid(TRI, [0, 1, 2], [0, 3], [200]), "type 200, which VTK does not know"),
        (_ugrid(TRI, [0, 1, 2, 3], [0, 4], [12]), r"HEXAHEDRON with 4 points \(expected 8\)"),
        (_ugrid(TRI, [0, 1, 5, 3], [0, 4], [10]), "refers to point 5"),
        (_poly(np.zeros((4, 3)), [[0, 1, 2], [1, 2, 3]]), "all 2 triangles have zero area"),
        (_poly(np.outer(np.arange(4), [1, 2, 3]), [[0, 1, 2], [1, 2, 3]]), "zero area"),
        ([pv.Line(), pv.PolyData(TRI)], "no dataset has surface"),
        (pv.PolyData(TRI), "no surface"),
        (SPHERE.scale(1e31), "beyond"),
    ],
)  # fmt: skip
def test_bad_in_memory_datasets_are_refused(scene, match):
    with pytest.raises(sg.InputError, match=match) as err:
        sg.capture(scene, window_size=(16, 16))
    assert "\n" not in str(err.value)


def test_offsets_that_lie_are_refused():
    poly = _poly(TRI, [[0, 1, 2]])
    cells = pv.CellArray()
    cells.SetData(pv.numpy_to_idarr([0, 3, 9]), pv.numpy_to_idarr([0, 1, 2, 1, 2, 3]))
    poly.SetPolys(cells)
    with pytest.raises(sg.InputError, match="offsets do not describe"):
        sg.capture(poly, window_size=(16, 16))


def test_lines_and_vertices_are_left_out():
    g = sg.capture([pv.Line(), SPHERE, pv.PolyData(TRI)], window_size=(48, 36))
    assert g.mask.any()
    assert set(np.unique(g.object_id[g.mask])) == {1}  # object ids stay the scene's indices
    assert len(g.object_names) == 3
    alone = sg.capture(SPHERE, window_size=(48, 36))
    assert np.array_equal(alone.mask, g.mask)


def _drawn_or_refused(mesh: pv.DataSet, **kwargs) -> str:
    """'drawn' if the capture covers a fair share of the picture, 'refused' if InputError."""
    try:
        g = sg.capture(mesh, window_size=(64, 48), **kwargs)
    except sg.InputError as exc:
        assert "\n" not in str(exc)
        return "refused"
    assert g.mask.mean() > 0.05, f"a blank picture ({g.mask.mean():.3f} covered)"
    return "drawn"


@pytest.mark.parametrize("camera", ["iso", "xy", "xz"])
@pytest.mark.parametrize("parallel", [None, True])
@pytest.mark.parametrize(
    ("label", "mesh", "expected"),
    [
        ("tiny 1e-9 at the origin", SPHERE.scale(1e-9), "drawn"),
        ("float32 tiny 1e-9 at 1", SPHERE.scale(1e-9).translate((1, 1, 1)), "refused"),
        ("float32 unit at 1e7", SPHERE.translate((1e7, -3e7, 2e7)), "refused"),
        ("float32 unit at 1e12", SPHERE.translate((1e12, 0, 0)), "refused"),
        ("float32 1e4 across at 1e7", SPHERE.scale(1e4).translate((1e7, 0, 0)), "drawn"),
        ("float64 tiny 1e-9 at 1", SPHERE64.scale(1e-9).translate((1, 1, 1)), "drawn"),
        ("float64 unit at 1e7", SPHERE64.translate((1e7, -3e7, 2e7)), "drawn"),
        ("float64 unit at 1e12", SPHERE64.translate((1e12, 0, 0)), "drawn"),
        ("huge 1e20", SPHERE.scale(1e20), "drawn"),
    ],
)
def test_tiny_and_far_meshes_are_drawn_or_refused(label, mesh, expected, camera, parallel):
    got = _drawn_or_refused(mesh, camera=camera, parallel_projection=parallel)
    if expected != "either":
        assert got == expected, label


@pytest.mark.parametrize("camera", ["iso", "xy"])
def test_a_flat_plane_is_drawn(camera):
    assert _drawn_or_refused(pv.Plane(), camera=camera) == "drawn"


def test_read_mesh_names_the_path_as_given(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("bad.ply").write_bytes(b"ply\nformat ascii 1.0\nelement vertex 1000000000\nend_header\n")
    with pytest.raises(sg.InputError, match=r"^bad\.ply: the PLY header declares"):
        read_mesh("bad.ply")


def test_unchecked_formats_are_read_in_a_child(tmp_path):
    """Formats without a header check (here a .vtm) parse in a child process: the result
    comes back whole, a child over its time limit is an InputError naming the file."""
    from sciviz_gbuf.readers._mesh_check import read_isolated

    p = tmp_path / "blocks.vtm"
    pv.MultiBlock([SPHERE]).save(p)
    assert read_mesh(p).n_cells == SPHERE.n_cells
    with pytest.raises(sg.InputError, match=r"blocks\.vtm: reading took more than 0 s"):
        read_isolated(p, "blocks.vtm", timeout=0)
    junk = tmp_path / "junk.glb"
    junk.write_bytes(b"garbage")
    with pytest.raises(sg.InputError, match=r"junk\.glb: cannot read as a mesh \(.*parse error"):
        read_mesh(junk)


@pytest.mark.parametrize("cmd", list(COMMANDS))
def test_a_mesh_seen_edge_on_is_not_a_blank_success(tmp_path, cmd):
    """A flat mesh seen exactly edge-on covers no pixel: refused, not an empty picture."""
    src = tmp_path / "flat.vtp"
    pv.Plane(direction=(0, 0, 1), i_size=2, j_size=2).triangulate().save(src)
    out = tmp_path / COMMANDS[cmd]
    args = [cmd, src.name, "-o", out.name, "--size", "64x48", "--view", "xz", "--parallel"]
    proc = run_cli(args, cwd=tmp_path)
    line = assert_clean_failure(proc, names=src.name, outputs=[out], inputs=checksums([src]))
    assert "covers a pixel" in line
    seen = run_cli([*args[:-3], "--view", "xy", "--parallel"], cwd=tmp_path)
    assert seen.returncode == 0, seen.stderr  # from above it is drawn
