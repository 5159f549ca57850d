"""Benchmark: full G-buffer ``capture()`` versus one plain PyVista render + screenshot.

Run from the project root with the project's venv active::

    python benchmarks/bench_capture.py            # 512^2, 1024^2, 2048^2; 3 repeats (~70 s)
    python benchmarks/bench_capture.py --quick    # 512^2, 1024^2; 1 repeat (~20 s)
    python benchmarks/bench_capture.py --csv out.csv

What is compared, per mesh and window size (n x n):

* ``capture``: ``sciviz_gbuf.capture(mesh, window_size=(n, n))`` with all its channels, warm
  (the numba kernels were compiled by an untimed first call);
* ``valuepass``: the alternative design, six ``vtkValuePass`` float passes (world x/y/z, normal
  x/y/z) in one render, read back (fewer channels than ``capture``: no depth, sz, ids);
* ``plain``: ``pl = pv.Plotter(off_screen=True, window_size=(n, n)); pl.add_mesh(mesh);
  pl.screenshot(); pl.close()``, PyVista's default theme and default (iso) camera.

Both are timed from scratch in every repeat (window, geometry upload, render, readback) and
interleaved, so the ratio capture/plain compares runs under the same machine state. Each cell is
the median of the repeats, in seconds. Every cell first runs one untimed capture + plain pair:
on a freshly booted VM (e.g. Firecracker) the first touch of never-used guest memory costs
~2 ms/MB, which otherwise lands at random on either side of the ratio (``--no-warmup`` skips it).

The meshes are ``pv.ParametricRandomHills`` terrains (generated, no download) of ~100k and ~1M
triangles. Each is captured once without point normals (``capture`` computes them with
``vtkPolyDataNormals``) and once with normals precomputed by ``mesh.compute_normals()`` outside
the timing (``capture`` then skips that filter).

The stage breakdown comes from separate, instrumented ``capture()`` calls: the internal steps
capture.py calls (``collect_surfaces``/``_merge``, ``IdRenderer``, ``_kernels.resolve_hits``,
and the VTK filters inside ``sciviz_gbuf.core.scene``) are wrapped with timers for the duration of
those calls only. The headline ``capture`` column is always the un-instrumented public call.
A stage the package no longer has under the same name shows as ``-``.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import functools
import gc
import importlib
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import numba
import numpy as np
import pyvista as pv
import vtk
from vtkmodules.vtkCommonCore import vtkLogger

import sciviz_gbuf

GOAL_RATIO = 2.0
GOAL_SIZE = 1024
GOAL_LABEL = "1M"

# (label, u/v resolution): a res x res grid has 2 * (res - 1)^2 triangles.
MESHES: tuple[tuple[str, int], ...] = (("100k", 225), ("1M", 708))

# Stage keys of the instrumented capture, and what they wrap.
# key -> (module name, attribute path)
_PATCHES: dict[str, tuple[str, str]] = {
    "collect": ("sciviz_gbuf.core.capture", "collect_surfaces"),
    "merge": ("sciviz_gbuf.core.capture", "_merge"),
    "surface": ("sciviz_gbuf.core.scene", "_surface_polydata"),
    "triangulate": ("sciviz_gbuf.core.scene", "_triangulate"),
    "normals": ("sciviz_gbuf.core.scene", "_compute_normals"),
    "gl_setup": ("sciviz_gbuf.core._render", "IdRenderer.__init__"),
    "gl_render": ("sciviz_gbuf.core._render", "IdRenderer.render"),
    "gl_close": ("sciviz_gbuf.core._render", "IdRenderer.close"),
    "resolve": ("sciviz_gbuf.core._capture_kernels", "resolve_hits"),
}


@dataclass
class Row:
    """One benchmark row: a mesh at one window size."""

    mesh: str
    n_triangles: int
    normals: bool
    size: int
    capture: list[float] = field(default_factory=list)
    plain: list[float] = field(default_factory=list)
    valuepass: list[float] = field(default_factory=list)
    stages: list[dict[str, float]] = field(default_factory=list)

    def median_stage(self, key: str) -> float | None:
        vals = [s[key] for s in self.stages if key in s]
        return statistics.median(vals) if vals else None


# --------------------------------------------------------------------------- timed workloads


def run_capture(mesh: pv.PolyData, n: int) -> float:
    """Seconds for one public ``capture()`` call (result kept alive until timed)."""
    gc.collect()
    t0 = time.perf_counter()
    gbuf = sciviz_gbuf.capture(mesh, window_size=(n, n))
    dt = time.perf_counter() - t0
    del gbuf
    return dt


def run_valuepass(mesh: pv.PolyData, n: int) -> float:
    """Seconds for the alternative design: float buffers straight from VTK's ``vtkValuePass``.

    Six passes (world x/y/z and normal x/y/z as point arrays) in one ``vtkSequencePass``, one
    ``Render()``, then every float image read back: the channels ``capture`` gets from its single
    id render. Normals are computed first when the mesh lacks them, as ``capture`` does.
    """
    from vtkmodules.vtkRenderingCore import (
        VTK_SCALAR_MODE_USE_POINT_FIELD_DATA,
        vtkActor,
        vtkPolyDataMapper,
        vtkRenderer,
    )
    from vtkmodules.vtkRenderingOpenGL2 import (
        vtkCameraPass,
        vtkRenderPassCollection,
        vtkSequencePass,
        vtkValuePass,
    )

    from sciviz_gbuf.core._render import new_render_window

    gc.collect()
    t0 = time.perf_counter()
    surf = mesh if "Normals" in mesh.point_data else mesh.compute_normals(split_vertices=True)
    data = pv.PolyData(surf.points, faces=surf.faces)
    pts = np.asarray(surf.points, dtype=np.float32)
    nrm = np.asarray(surf.point_data["Normals"], dtype=np.float32)
    names = []
    for k, axis in enumerate("xyz"):
        data.point_data[f"w{axis}"] = pts[:, k]
        data.point_data[f"n{axis}"] = nrm[:, k]
        names += [f"w{axis}", f"n{axis}"]
    mapper = vtkPolyDataMapper()
    mapper.SetInputData(data)
    actor = vtkActor()
    actor.SetMapper(mapper)
    ren = vtkRenderer()
    ren.AddActor(actor)
    passes = vtkRenderPassCollection()
    value_passes = []
    for name in names:
        vp = vtkValuePass()
        vp.SetInputArrayToProcess(VTK_SCALAR_MODE_USE_POINT_FIELD_DATA, name)
        vp.SetInputComponentToProcess(0)
        passes.AddItem(vp)
        value_passes.append(vp)
    seq = vtkSequencePass()
    seq.SetPasses(passes)
    cam_pass = vtkCameraPass()
    cam_pass.SetDelegatePass(seq)
    ren.SetPass(cam_pass)
    win = new_render_window()
    win.AddRenderer(ren)
    win.SetSize(n, n)
    ren.GetActiveCamera().SetPosition(1, 1, 1)
    ren.ResetCamera()
    win.Render()
    images = [np.array(pv.convert_array(vp.GetFloatImageDataArray(ren))) for vp in value_passes]
    dt = time.perf_counter() - t0
    if not all(np.isfinite(im).any() for im in images):
        raise RuntimeError("vtkValuePass produced an empty float image")
    win.Finalize()
    del images
    return dt


def run_plain(mesh: pv.PolyData, n: int, report: list[str] | None = None) -> float:
    """Seconds for one plain PyVista off-screen render + screenshot of ``mesh``."""
    gc.collect()
    t0 = time.perf_counter()
    pl = pv.Plotter(off_screen=True, window_size=(n, n))
    pl.add_mesh(mesh)
    img = pl.screenshot()
    dt = time.perf_counter() - t0
    if report is not None:
        report.append(type(pl.ren_win).__name__)
        report.append(pl.ren_win.ReportCapabilities())
    pl.close()
    del img
    return dt


def _resolve_attr(module_name: str, path: str) -> tuple[object, str] | None:
    try:
        obj: object = importlib.import_module(module_name)
    except ImportError:
        return None
    *parents, name = path.split(".")
    for p in parents:
        obj = getattr(obj, p, None)
        if obj is None:
            return None
    if not callable(getattr(obj, name, None)):
        return None
    return obj, name


@contextlib.contextmanager
def instrumented(timings: dict[str, float]) -> Iterator[None]:
    """Wrap the internal capture steps with timers, accumulating seconds into ``timings``."""
    undo: list[tuple[object, str, object]] = []

    def timer(key: str, fn: Callable) -> Callable:
        @functools.wraps(fn)
        def timed(*args, **kwargs):
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                timings[key] = timings.get(key, 0.0) + time.perf_counter() - t0

        return timed

    try:
        for key, (module_name, path) in _PATCHES.items():
            found = _resolve_attr(module_name, path)
            if found is None:
                continue
            obj, name = found
            # class attributes: take the raw function from __dict__ (not a bound method)
            orig = vars(obj)[name] if isinstance(obj, type) else getattr(obj, name)
            undo.append((obj, name, orig))
            setattr(obj, name, timer(key, orig))
        yield
    finally:
        for obj, name, orig in reversed(undo):
            setattr(obj, name, orig)


def run_breakdown(mesh: pv.PolyData, n: int) -> dict[str, float]:
    """Stage seconds of one instrumented ``capture()`` call; ``total`` is its wall time."""
    timings: dict[str, float] = {}
    gc.collect()
    with instrumented(timings):
        t0 = time.perf_counter()
        gbuf = sciviz_gbuf.capture(mesh, window_size=(n, n))
        timings["total"] = time.perf_counter() - t0
    del gbuf
    return timings


# --------------------------------------------------------------------------- meshes


def make_meshes(labels: set[str]) -> list[tuple[str, bool, pv.PolyData]]:
    """``(label, has_normals, mesh)``: each terrain without and with precomputed normals."""
    out = []
    for label, res in MESHES:
        if label not in labels:
            continue
        hills = pv.ParametricRandomHills(u_res=res, v_res=res)
        bare = hills.copy(deep=True)
        bare.point_data.clear()  # the source generates normals: drop them
        bare.cell_data.clear()
        assert bare.GetPointData().GetNormals() is None
        with_normals = bare.compute_normals()  # outside any timing
        out.append((label, False, bare))
        out.append((label, True, with_normals))
    return out


# --------------------------------------------------------------------------- reporting


def machine_facts(caps: list[str]) -> list[str]:
    from sciviz_gbuf.core._render import new_render_window

    try:
        n_avail = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        n_avail = os.cpu_count()
    gl_lines = []
    if len(caps) >= 2:
        for line in caps[1].splitlines():
            if line.startswith(("OpenGL renderer", "OpenGL version", "OpenGL vendor")):
                gl_lines.append(" ".join(line.split()))
    capture_win = new_render_window()
    capture_cls = capture_win.GetClassName()
    capture_win.Finalize()
    theme = pv.global_theme
    return [
        f"machine: {platform.machine()} {platform.system()} {platform.release()}; "
        f"cpu_count={os.cpu_count()} (usable {n_avail}); {platform.processor() or '?'}",
        f"python {platform.python_version()}, numpy {np.__version__}, VTK "
        f"{vtk.vtkVersion.GetVTKVersion()}, pyvista {pv.__version__}, numba {numba.__version__} "
        f"(threads {numba.get_num_threads()}), sciviz_gbuf {sciviz_gbuf.__version__}",
        f"render windows: capture {capture_cls}, plain pv.Plotter "
        f"{caps[0] if caps else '?'}; DISPLAY={os.environ.get('DISPLAY', '')!r}",
        *(f"  {g}" for g in gl_lines),
        f"plain render theme: anti_aliasing={theme.anti_aliasing!r} "
        f"multi_samples={theme.multi_samples} lighting={theme.lighting} "
        f"smooth_shading={theme.smooth_shading}",
    ]


def _fmt(v: float | None, digits: int = 3) -> str:
    return "-" if v is None else f"{v:.{digits}f}"


COLUMNS = (
    "mesh",
    "triangles",
    "normals",
    "size",
    "capture_s",
    "plain_s",
    "ratio",
    "valuepass_s",
    "prep_s",
    "vtkNormals_s",
    "render_s",
    "resolve_s",
    "other_s",
)


def row_values(row: Row) -> dict[str, str]:
    cap = statistics.median(row.capture)
    plain = statistics.median(row.plain)
    st = {k: row.median_stage(k) for k in (*_PATCHES, "total")}
    prep = None
    if st["collect"] is not None:
        prep = st["collect"] + (st["merge"] or 0.0)
    render = None
    if st["gl_render"] is not None:
        render = st["gl_render"] + (st["gl_setup"] or 0.0) + (st["gl_close"] or 0.0)
    other = None
    if st["total"] is not None and None not in (prep, render, st["resolve"]):
        other = st["total"] - prep - render - st["resolve"]  # type: ignore[operator]
    return {
        "mesh": f"RandomHills {row.mesh}",
        "triangles": str(row.n_triangles),
        "normals": "precomputed" if row.normals else "none (capture computes)",
        "size": f"{row.size}^2",
        "capture_s": _fmt(cap),
        "plain_s": _fmt(plain),
        "ratio": f"{cap / plain:.2f}x",
        "valuepass_s": _fmt(statistics.median(row.valuepass)) if row.valuepass else "-",
        "prep_s": _fmt(prep),
        # None when capture skipped the filter (mesh already had normals)
        "vtkNormals_s": _fmt(st["normals"]) if not row.normals else "skipped",
        "render_s": _fmt(render),
        "resolve_s": _fmt(st["resolve"]),
        "other_s": _fmt(other),
    }


def format_table(rows: list[dict[str, str]]) -> str:
    widths = {c: max(len(c), *(len(r[c]) for r in rows)) for c in COLUMNS}
    left = {"mesh", "normals"}

    def line(vals: dict[str, str]) -> str:
        return "  ".join(
            vals[c].ljust(widths[c]) if c in left else vals[c].rjust(widths[c]) for c in COLUMNS
        )

    header = line({c: c for c in COLUMNS})
    return "\n".join([header, "-" * len(header), *(line(r) for r in rows)])


# --------------------------------------------------------------------------- main


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument(
        "--quick", action="store_true", help="only 512^2 and 1024^2, 1 repeat (under a minute)"
    )
    parser.add_argument("--repeats", "-r", type=int, default=None, help="repeats per cell (3)")
    parser.add_argument(
        "--sizes", type=int, nargs="+", default=None, help="window edges (512 1024 2048)"
    )
    parser.add_argument(
        "--meshes", nargs="+", choices=[m for m, _ in MESHES], default=[m for m, _ in MESHES]
    )
    parser.add_argument("--csv", metavar="PATH", help="also write the raw medians as CSV")
    parser.add_argument(
        "--no-breakdown", action="store_true", help="skip the instrumented stage runs"
    )
    parser.add_argument(
        "--no-warmup", action="store_true", help="skip the untimed warm-up pair of each cell"
    )
    args = parser.parse_args(argv)
    repeats = args.repeats if args.repeats is not None else (1 if args.quick else 3)
    sizes = args.sizes or ([512, 1024] if args.quick else [512, 1024, 2048])
    if repeats < 1:
        parser.error("--repeats must be >= 1")

    # pv.Plotter first tries an X window and warns when there is no display; keep the
    # output readable (it falls back to EGL, reported below).
    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)

    t_start = time.perf_counter()
    # Warm-up (untimed): numba compilation / cache load, first EGL context, PyVista imports.
    warm = pv.Sphere()
    t0 = time.perf_counter()
    sciviz_gbuf.capture(warm, window_size=(64, 64))
    t_first_capture = time.perf_counter() - t0
    caps: list[str] = []
    run_plain(warm, 64, report=caps)
    run_breakdown(warm, 64)

    print("sciviz_gbuf capture benchmark")
    for fact in machine_facts(caps):
        print(fact)
    print(f"first (cold) capture of a 64^2 sphere: {t_first_capture:.2f} s (numba compile/cache)")
    print(f"repeats per cell: {repeats} (median shown); sizes: {sizes}")
    print()

    t0 = time.perf_counter()
    meshes = make_meshes(set(args.meshes))
    print(f"meshes generated in {time.perf_counter() - t0:.1f} s (not part of any timing)")

    rows: list[Row] = []
    for label, has_normals, mesh in meshes:
        for n in sizes:
            row = Row(label, int(mesh.n_cells), has_normals, n)
            if not args.no_warmup:
                # untimed: first touch of this cell's buffers (see the module docstring)
                run_capture(mesh, n)
                run_plain(mesh, n)
            for _ in range(repeats):
                row.capture.append(run_capture(mesh, n))
                row.plain.append(run_plain(mesh, n))
                row.valuepass.append(run_valuepass(mesh, n))
                if not args.no_breakdown:
                    row.stages.append(run_breakdown(mesh, n))
            rows.append(row)
            print(
                f"  done {label:>4} normals={'yes' if has_normals else 'no ':3} {n:>4}^2: "
                f"capture {statistics.median(row.capture):.3f} s, "
                f"plain {statistics.median(row.plain):.3f} s",
                flush=True,
            )

    values = [row_values(r) for r in rows]
    print()
    print(format_table(values))
    print()
    print(
        "columns: capture_s = public sciviz_gbuf.capture() (all channels); plain_s = "
        "pv.Plotter + add_mesh + screenshot + close;\n"
        "  ratio = capture_s / plain_s; breakdown (instrumented runs, medians): prep_s = "
        "collect_surfaces + _merge\n"
        "  (surface extraction, triangulation, normals), of which vtkNormals_s = "
        "vtkPolyDataNormals; render_s = IdRenderer\n"
        "  setup + render/readback passes + close; resolve_s = _kernels.resolve_hits; "
        "other_s = rest of the instrumented call\n"
        "  (camera fit, id->object/cell maps, sz, GBuffer)."
    )

    goal = [r for r in rows if r.mesh == GOAL_LABEL and r.size == GOAL_SIZE]
    print()
    print(
        f"goal: full capture <= {GOAL_RATIO:g}x one plain render at {GOAL_SIZE}^2 "
        f"for {GOAL_LABEL} triangles"
    )
    if not goal:
        print(f"  (not measured in this run: needs --meshes {GOAL_LABEL} and size {GOAL_SIZE})")
    for r in goal:
        ratio = statistics.median(r.capture) / statistics.median(r.plain)
        verdict = "MET" if ratio <= GOAL_RATIO else "NOT MET"
        what = "normals precomputed" if r.normals else "no normals (capture computes them)"
        print(
            f"  {what:<36}: capture {statistics.median(r.capture):.3f} s / plain "
            f"{statistics.median(r.plain):.3f} s = {ratio:.2f}x -> {verdict}"
        )

    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            writer = csv.writer(fh)
            stage_keys = [*_PATCHES, "total"]
            writer.writerow(
                [
                    "mesh",
                    "triangles",
                    "normals_precomputed",
                    "size",
                    "repeats",
                    "capture_s",
                    "plain_s",
                    "ratio",
                    *(f"stage_{k}_s" for k in stage_keys),
                    "capture_runs_s",
                    "plain_runs_s",
                ]
            )
            for r in rows:
                cap = statistics.median(r.capture)
                plain = statistics.median(r.plain)
                stage_vals = [r.median_stage(k) for k in stage_keys]
                writer.writerow(
                    [
                        f"ParametricRandomHills {r.mesh}",
                        r.n_triangles,
                        r.normals,
                        r.size,
                        repeats,
                        f"{cap:.5f}",
                        f"{plain:.5f}",
                        f"{cap / plain:.4f}",
                        *("" if v is None else f"{v:.5f}" for v in stage_vals),
                        " ".join(f"{v:.5f}" for v in r.capture),
                        " ".join(f"{v:.5f}" for v in r.plain),
                    ]
                )
        print(f"\nCSV written to {args.csv}")
    print(f"\ntotal benchmark wall time: {time.perf_counter() - t_start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
