"""Benchmark: vector line art (``vectorize``, ``edge_strokes``, SVG/PDF) and multi-layer
captures (``capture(layers=k)``).

Run from the project root with the project's venv active::

    python benchmarks/bench_vector.py                 # ~2-3 min on 2 cores
    python benchmarks/bench_vector.py --repeats 5
    python benchmarks/bench_vector.py --skip-layers   # tables (a) and (b) only

What is measured (warm: every timed call follows an untimed one; best of ``--repeats``):

(a) **Tracing.** The nut (``sciviz_gbuf.datasets.load_nut()``), the shared CAD STL
    (``../shared/data/meshes/vtkdata_42400-IDGH.stl``, skipped if absent) and ``pv.Cube()``,
    captured in the default iso view at 512^2 and 1024^2, ``supersample`` 1 and 2 (untimed).
    Per case:

    * ``raster``: ``profile_and_crease_edges(gb)``, the raster edge filter (the PNG's lines);
    * ``strokes``: ``edge_strokes(gb)``, the whole vector path (line finding + tracing);
    * ``trace``: ``vectorize`` alone, on the two line images ``edge_strokes`` traces (the
      one-pixel lines of the buffer, ``buffer_lines`` when supersampled), same parameters;
    * ``skel``: scikit-image's ``skeletonize`` alone on the same two line masks (ink >= 0.3),
      the first step of ``trace`` and a floor for any skeleton-based tracer (a peer in the
      same run, not a competitor: it gives pixels, no strokes).

    Ratios: ``strokes / raster`` (what vector output costs over the raster lines) and
    ``trace / skel`` (what the tracing adds to a bare skeleton). Counts: strokes, vertices,
    closed strokes.
(b) **Files.** For the 1024^2 supersample-2 case of each mesh: ``write_svg`` and
    ``write_pdf`` of the strokes against ``compose.write_png`` of the raster lines of the same
    G-buffer (black on white, 8-bit RGB), time and bytes, in a temporary folder.
(c) **Layers.** ``capture(scene, window_size=(1024, 768), layers=k)`` for k = 1, 2, 4 on two
    nested ``pv.Icosphere(nsub=6)`` spheres (radii 2 and 1; 81920 triangles each) and on the CAD
    STL. Each case runs in a fresh subprocess: one untimed 128 x 96 capture with the same ``k``
    (numba kernels loaded or compiled, VTK up), then ``--layer-repeats`` timed captures.
    ``peak`` is the subprocess's peak RSS over them (``VmHWM`` of ``/proc/self/status``,
    reset after the warm-up; not ``getrusage``'s ``ru_maxrss``, which Linux keeps across
    ``execve``: a child would report its parent's peak), ``+peak`` its growth over the RSS
    after the warm-up, ``traced`` tracemalloc's peak over one more capture (NumPy's and
    Python's allocations, not VTK's), ``kept`` the bytes of the returned G-buffer's arrays,
    ``model`` the estimate the memory check uses. The ratio is against k = 1 of the same
    scene in the same run.

No time is asserted; the tables are for comparing rows of one run on one machine.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

if not os.environ.get("DISPLAY"):
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
STL = ROOT.parent / "shared" / "data" / "meshes" / "vtkdata_42400-IDGH.stl"
LAYER_SIZE = (1024, 768)


def timed(fn: Callable[[], object], repeats: int) -> tuple[float, object]:
    """Best time of ``repeats`` calls after an untimed one, and the last result."""
    out = fn()
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def meshes() -> dict[str, object]:
    import pyvista as pv

    import sciviz_gbuf as sg

    out = {"nut": sg.datasets.load_nut()}
    if STL.is_file():
        out["cad_stl"] = pv.read(STL)
    out["cube"] = pv.Cube().triangulate()
    return out


def _line_images(gb):
    """The two line images edge_strokes traces (its own line finding, default parameters)."""
    from sciviz_gbuf.filters import profile_and_crease_edges
    from sciviz_gbuf.filters.edges import buffer_lines

    if gb.supersample == 1:
        return profile_and_crease_edges(gb, width=1.0, min_length=5.0, signed=False)
    return buffer_lines(gb, min_length=5.0)


# --------------------------------------------------------------------------- (a) and (b)
def bench_tracing(repeats: int) -> list[dict]:
    from skimage.morphology import skeletonize

    import sciviz_gbuf as sg
    from sciviz_gbuf.filters import profile_and_crease_edges, vectorize
    from sciviz_gbuf.filters.strokes import TOLERANCE

    rows = []
    for name, mesh in meshes().items():
        for n in (512, 1024):
            for ss in (1, 2):
                gb = sg.capture(mesh, window_size=(n, n), camera="iso", supersample=ss)
                t_raster, _ = timed(lambda gb=gb: profile_and_crease_edges(gb), repeats)
                t_strokes, strokes = timed(lambda gb=gb: sg.edge_strokes(gb), repeats)
                profile, crease = _line_images(gb)

                def trace(profile=profile, crease=crease, ss=ss):
                    for ink in (profile, crease):
                        vectorize(ink, width=1.0, tolerance=min(TOLERANCE * ss, 64.0),
                                  min_length=2.0 * ss)  # fmt: skip

                masks = [np.clip(np.abs(np.nan_to_num(i)), 0, 1) >= 0.3 for i in (profile, crease)]

                def skel(masks=masks):
                    for m in masks:
                        skeletonize(m)

                t_trace, _ = timed(trace, repeats)
                t_skel, _ = timed(skel, repeats)
                h, w = gb.shape
                rows.append({
                    "mesh": name, "n": n, "ss": ss, "buffer": f"{w}x{h}", "gb": gb,
                    "raster": t_raster, "strokes": t_strokes, "trace": t_trace,
                    "skel": t_skel, "n_strokes": len(strokes),
                    "vertices": sum(len(s.points) for s in strokes),
                    "closed": sum(s.closed for s in strokes), "stroke_list": strokes,
                })  # fmt: skip
    return rows


def print_tracing(rows: list[dict]) -> None:
    print("(a) tracing: edge_strokes / vectorize vs the raster edges and a bare skeleton; "
          "best of the repeats, ms")  # fmt: skip
    head = (f"{'mesh':<8} {'out':>5} {'ss':>2} {'buffer':>10} {'raster':>7} {'strokes':>8} "
            f"{'trace':>7} {'skel':>6} {'str/ras':>8} {'trc/skl':>8} {'strokes':>8} "
            f"{'verts':>6} {'closed':>6}")  # fmt: skip
    print(head)
    print("-" * len(head))
    for r in rows:
        print(
            f"{r['mesh']:<8} {r['n']:>5} {r['ss']:>2} {r['buffer']:>10} {1e3 * r['raster']:7.1f} "
            f"{1e3 * r['strokes']:8.1f} {1e3 * r['trace']:7.1f} {1e3 * r['skel']:6.1f} "
            f"{r['strokes'] / r['raster']:7.1f}x {r['trace'] / r['skel']:7.1f}x "
            f"{r['n_strokes']:8d} {r['vertices']:6d} {r['closed']:6d}"
        )
    print("raster = profile_and_crease_edges; strokes = edge_strokes (lines + tracing); "
          "trace = vectorize alone; skel = skimage skeletonize alone (same masks)")  # fmt: skip


def bench_files(rows: list[dict], repeats: int) -> None:
    import sciviz_gbuf as sg
    from sciviz_gbuf.compose import write_png
    from sciviz_gbuf.filters import profile_and_crease_edges

    print("\n(b) files of the same edges (1024^2 output, supersample 2): time ms (best), size")
    head = (f"{'mesh':<8} {'strokes':>7} {'verts':>6} {'SVG ms':>7} {'SVG kB':>7} {'PDF ms':>7} "
            f"{'PDF kB':>7} {'PNG ms':>7} {'PNG kB':>7} {'SVG/PNG size':>13}")  # fmt: skip
    print(head)
    print("-" * len(head))
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        for r in rows:
            if (r["n"], r["ss"]) != (1024, 2):
                continue
            gb, strokes = r["gb"], r["stroke_list"]
            h, w = gb.output_shape
            prof, crease = profile_and_crease_edges(gb)
            lines = 1.0 - np.maximum(prof, crease)
            rgb = (np.repeat(np.clip(lines, 0, 1)[..., None], 3, axis=2) * 255).astype(np.uint8)
            svg, pdf, png = d / "e.svg", d / "e.pdf", d / "e.png"
            size = (w, h)
            t_svg, _ = timed(lambda s=svg, k=strokes, z=size: sg.write_svg(s, k, size=z), repeats)
            t_pdf, _ = timed(lambda p=pdf, k=strokes, z=size: sg.write_pdf(p, k, size=z), repeats)
            t_png, _ = timed(lambda p=png, a=rgb: write_png(p, a), repeats)
            s_svg, s_pdf, s_png = (p.stat().st_size for p in (svg, pdf, png))
            print(
                f"{r['mesh']:<8} {len(strokes):7d} {r['vertices']:6d} {1e3 * t_svg:7.1f} "
                f"{s_svg / 1e3:7.1f} {1e3 * t_pdf:7.1f} {s_pdf / 1e3:7.1f} {1e3 * t_png:7.1f} "
                f"{s_png / 1e3:7.1f} {s_svg / s_png:12.2f}x"
            )
    print("PNG = compose.write_png of the raster lines (1 - max(profile, crease)), 8-bit RGB")


# --------------------------------------------------------------------------- (c) layers
def _scene(name: str):
    import pyvista as pv

    if name == "spheres":
        return [pv.Icosphere(radius=r, nsub=6) for r in (2.0, 1.0)]
    return pv.read(STL)


def _status_kb(field: str) -> int | None:
    """A ``/proc/self/status`` field in bytes (``VmRSS``, ``VmHWM``), None where absent."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith(field + ":"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return None


def _reset_peak() -> bool:
    """Reset the kernel's peak-RSS mark of this process (Linux >= 4.0: ``clear_refs`` 5)."""
    try:
        Path("/proc/self/clear_refs").write_text("5")
        return True
    except OSError:
        return False


def layer_case(scene_name: str, k: int, repeats: int) -> None:
    """One subprocess case: prints one JSON line.

    The peak is the process's own high-water mark (``VmHWM``, reset after the warm-up), not
    ``getrusage``'s ``ru_maxrss``: Linux keeps that across ``execve``, so a child would report
    the parent's peak. ``traced`` is tracemalloc's peak of one more capture (the NumPy and
    Python allocations; not VTK's or the driver's)."""
    import tracemalloc

    import sciviz_gbuf as sg

    scene = _scene(scene_name)
    sg.capture(scene, window_size=(128, 96), layers=k)  # kernels, VTK, first touch
    reset = _reset_peak()
    base = _status_kb("VmRSS")
    times = []
    g = None
    for _ in range(repeats):
        g = None
        t0 = time.perf_counter()
        g = sg.capture(scene, window_size=LAYER_SIZE, layers=k)
        times.append(time.perf_counter() - t0)
    peak = _status_kb("VmHWM") if reset else None
    if peak is None:  # no /proc: ru_maxrss (may include the parent's peak)
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    kept = sum(a.nbytes for a in g.channels().values())
    covered = [int(layer.mask.sum()) for layer in (g, *g.layers)]
    g = None
    tracemalloc.start()
    sg.capture(scene, window_size=LAYER_SIZE, layers=k)
    traced = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    print(json.dumps({"best": min(times), "median": statistics.median(times), "peak": peak,
                      "base": base or 0, "kept": kept, "traced": traced,
                      "covered": covered}))  # fmt: skip


def bench_layers(repeats: int) -> None:
    print(f"\n(c) capture(layers=k) at {LAYER_SIZE[0]}x{LAYER_SIZE[1]}, supersample 1; "
          f"one subprocess per case, best of {repeats}")  # fmt: skip
    head = (f"{'scene':<8} {'triangles':>9} {'k':>2} {'best s':>7} {'median s':>8} {'vs k=1':>7} "
            f"{'peak MB':>8} {'+peak MB':>8} {'traced MB':>9} {'kept MB':>8} {'model MB':>8}  "
            "covered px per layer")  # fmt: skip
    print(head)
    print("-" * len(head))
    from sciviz_gbuf.core.capture import BYTES_PER_LAYER, BYTES_PER_PIXEL

    scenes = ["spheres"] + (["cad_stl"] if STL.is_file() else [])
    for name in scenes:
        tri = sum(int(m.triangulate().n_cells) for m in np.atleast_1d(_scene(name)))
        ref = None
        for k in (1, 2, 4):
            cmd = [sys.executable, __file__, "--layer-case", name, str(k),
                   "--layer-repeats", str(repeats)]  # fmt: skip
            r = subprocess.run(cmd, capture_output=True, text=True, check=False, timeout=900)
            if r.returncode != 0:
                print(f"{name:<8} k={k}: failed: {r.stderr.strip().splitlines()[-1:]}")
                continue
            res = json.loads(r.stdout.strip().splitlines()[-1])
            ref = res["best"] if k == 1 else ref
            px = LAYER_SIZE[0] * LAYER_SIZE[1]
            model = px * (BYTES_PER_PIXEL + (k - 1) * BYTES_PER_LAYER + (k + 2) * 16 * (k > 1))
            ratio = f"{res['best'] / ref:6.1f}x" if ref else "      -"
            print(
                f"{name:<8} {tri:9d} {k:2d} {res['best']:7.2f} {res['median']:8.2f} {ratio} "
                f"{res['peak'] / 1e6:8.0f} {(res['peak'] - res['base']) / 1e6:8.0f} "
                f"{res['traced'] / 1e6:9.0f} {res['kept'] / 1e6:8.0f} {model / 1e6:8.0f}  "
                f"{res['covered']}"
            )
    print("peak = the subprocess's peak RSS (VmHWM, reset after the warm-up); +peak = its "
          "growth over the RSS after the warm-up;\ntraced = tracemalloc's peak of one capture; "
          "kept = the G-buffer's arrays; model = the memory check's estimate\n(BYTES_PER_PIXEL "
          "+ (k-1) BYTES_PER_LAYER + (k+2) x 16 per pixel)")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=3, help="timed calls per cell (best shown)")
    ap.add_argument("--layer-repeats", type=int, default=2)
    ap.add_argument("--skip-layers", action="store_true")
    ap.add_argument("--layer-case", nargs=2, metavar=("SCENE", "K"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.layer_case:
        layer_case(args.layer_case[0], int(args.layer_case[1]), args.layer_repeats)
        return 0
    import numba

    import sciviz_gbuf

    print(f"sciviz_gbuf {sciviz_gbuf.__version__}, numba threads {numba.get_num_threads()}, "
          f"{os.cpu_count()} CPUs")  # fmt: skip
    t0 = time.perf_counter()
    rows = bench_tracing(args.repeats)
    print_tracing(rows)
    bench_files(rows, args.repeats)
    rows.clear()  # the G-buffers (1-2 GB), before the layer subprocesses
    if not args.skip_layers:
        bench_layers(args.layer_repeats)
    print(f"\ntotal {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
