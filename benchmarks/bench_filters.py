"""Benchmark: throughput of the image-space operators of ``sciviz_gbuf.filters``, in MPix/s.

Run from the project root with the project's venv active::

    python benchmarks/bench_filters.py            # 1024^2, 4096^2, 8192^2 + nut (~3.5 min)
    python benchmarks/bench_filters.py --quick    # 1024^2, 2048^2 + 1024^2 nut (~30 s)
    python benchmarks/bench_filters.py --sizes 2048 4096 --capture-sizes 1024
    python benchmarks/bench_filters.py --csv out.csv --wait-idle 60   # shared machine

What is measured:

* ``synthetic``: every public 3x3 operator of ``sciviz_gbuf.filters`` (``sobel_gradient``,
  ``second_order``, ``normalize_gradient``, ``suppress_zeroth_order``, ``c1_discontinuity``,
  ``diagonal_depth_discontinuity``, ``diagonal_normal_discontinuity``) on an n x n float32
  image, once without a mask and once with a coverage mask (a centred disc, 70 % of the
  pixels). The image is depth-like: a tilted ground plane in pixel units with NaN "sky" above
  its horizon (12 % of the rows) and four spheres in front of it; the operators treat the NaN
  pixels as masked. ``normalize_gradient`` and ``suppress_zeroth_order`` get the gradient (and
  second-order) images of that depth; ``diagonal_depth_discontinuity`` gets the depth scaled
  to z-buffer-like values in [0, 1]; ``diagonal_normal_discontinuity`` gets the unit normals of
  the depth surface, (n, n, 3) float32 (NaN on the sky and its border).
* Peers, same image, same run: ``skimage.filters.sobel`` (without and with the same mask),
  ``scipy.ndimage.sobel`` along both axes + ``np.hypot``, and ``numpy copy`` (allocate a new
  image and write it: the memory-bandwidth ceiling of any operator that returns a new image).
* ``nut gbuf``: the G-buffer level functions ``profile_edges``, ``internal_edges``,
  ``crease_edges``, ``edge_map(operator="diagonal")`` and ``edge_map(operator="c1")`` on
  ``capture(datasets.load_nut(), window_size=(S, S))``, next to ``skimage.filters.sobel`` of
  that capture's ``sz``. The capture time is reported for context.

Every cell is warm: one untimed call first (numba compiles or loads its cache, and on a freshly
booted VM the first touch of never-used guest memory costs ~2 ms/MB). Then the call is repeated
for about ``--target`` seconds (N times, at least ``--min-repeats``). MPix/s is n^2 / best time
(every pixel counts, covered or not); the median is shown too. Each call allocates its result
like a user's call would; the results are freed at once, so every call faults in fresh pages
for its result (64 MB at 4096^2). On a VM with free page reporting (virtio_balloon, e.g.
Firecracker) memory that stayed free for a few seconds is handed back to the host and costs
~1-2 ms/MB again on the next touch: a call whose result lands there is slower (+~80 ms at
4096^2). The best time excludes such calls, the median may not.

The ``core`` column separates that cost. For the operators it is the same public call with
the ``np.empty`` of ``sciviz_gbuf.filters.operators`` / ``._stencil`` handing out a reused
buffer (checked to give the same result): no allocation, no page faults, so public vs core is
what allocating the result costs. For the G-buffer functions it is the private numba kernel
(``_edge_kernels.edge_pass``, in its pair or edge-map mode) alone on preallocated output, without
the dilation, downsample, clip and stack that follow it. ``-`` where that does not apply to the
code as it is (private internals, not part of the package's interface).

The ``other load`` column is the share of the machine's CPU that other processes took during
the cell (from ``/proc/stat``): on a 2-core machine a concurrent job directly slows the
parallel kernels, so cells with a high value are not representative.
"""

from __future__ import annotations

import argparse
import csv
import gc
import hashlib
import math
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

# Headless: VTK's default window class would try X first. Must precede the pyvista import
# (``sciviz_gbuf`` imports it).
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numba
import scipy
import skimage
from scipy import ndimage
from skimage import filters as skfilters

import sciviz_gbuf
import sciviz_gbuf.datasets
from sciviz_gbuf import filters

GOAL_MPIX = 1000.0
GOAL_RATIO = 25.0
GOAL_SIZE = 4096
MASK_COVERAGE = 0.70
SKY_FRACTION = 0.12

# (centre x, centre y, radius) as fractions of the image edge
SPHERES = ((0.30, 0.55, 0.18), (0.68, 0.40, 0.14), (0.55, 0.80, 0.12), (0.20, 0.15, 0.09))

OPERATORS = (
    "sobel_gradient",
    "second_order",
    "normalize_gradient",
    "suppress_zeroth_order",
    "c1_discontinuity",
    "diagonal_depth_discontinuity",
    "diagonal_normal_discontinuity",
)
SKIMAGE = "skimage.filters.sobel"


@dataclass
class Row:
    """One benchmark cell: an operator at one size, with or without a mask."""

    section: str
    operator: str
    size: int
    mask: str
    times: list[float] = field(default_factory=list)
    core_times: list[float] = field(default_factory=list)
    peer: bool = False
    other_load: float | None = None

    @property
    def mpix(self) -> float:
        return self.size * self.size / 1e6

    def best(self) -> float:
        return self.mpix / min(self.times)

    def median(self) -> float:
        return self.mpix / statistics.median(self.times)

    def core(self) -> float | None:
        return self.mpix / min(self.core_times) if self.core_times else None


# --------------------------------------------------------------------------- timing


def measure(fn: Callable[[], object], target: float, min_reps: int, max_reps: int) -> list[float]:
    """Seconds of warm calls of ``fn``, repeated for ``target`` s (``min_reps``..``max_reps``
    calls); the first (warm-up) call is not returned."""
    gc.collect()
    out = fn()  # warm-up: compile / cache load, first touch of the result's memory
    del out
    times: list[float] = []
    gc.disable()
    try:
        while len(times) < max_reps and (len(times) < min_reps or sum(times) < target):
            t0 = time.perf_counter()
            out = fn()
            times.append(time.perf_counter() - t0)
            del out
    finally:
        gc.enable()
    return times


def _cpu_snapshot() -> tuple[float, float, float, float] | None:
    """(wall s, busy CPU s of the whole guest, CPU s of this process, steal s); Linux only."""
    try:
        with open("/proc/stat") as fh:
            v = [int(x) for x in fh.readline().split()[1:]]
        tick = os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError):
        return None
    # user nice system idle iowait irq softirq steal ...
    busy = (v[0] + v[1] + v[2] + v[5] + v[6]) / tick
    steal = v[7] / tick if len(v) > 7 else 0.0
    t = os.times()
    return time.perf_counter(), busy, t.user + t.system, steal


class LoadMeter:
    """CPU share that *other* processes (and the hypervisor, as steal) took while in the block:
    on a 2-core VM a concurrent job directly slows the parallel kernels."""

    def start(self) -> LoadMeter:
        self.a = _cpu_snapshot()
        self.b = None
        return self

    def stop(self) -> None:
        self.b = _cpu_snapshot()

    def __enter__(self) -> LoadMeter:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    def _share(self, k: int) -> float | None:
        if self.a is None or self.b is None:
            return None
        wall = (self.b[0] - self.a[0]) * (os.cpu_count() or 1)
        if k == 1:  # busy minus own
            used = (self.b[1] - self.a[1]) - (self.b[2] - self.a[2])
        else:
            used = self.b[3] - self.a[3]
        return max(0.0, used / wall) if wall > 0 else None

    def other(self) -> float | None:
        return self._share(1)

    def steal(self) -> float | None:
        return self._share(3)


IDLE_THRESHOLD = 0.05
_waited = [0.0]  # seconds spent in wait_idle, for the report


def wait_idle(max_wait: float, window: float = 0.25) -> None:
    """Wait up to ``max_wait`` s until other processes use < IDLE_THRESHOLD of the CPU."""
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < max_wait:
        with LoadMeter() as meter:
            time.sleep(window)
        other = meter.other()
        if other is None or other < IDLE_THRESHOLD:
            break
    _waited[0] += time.perf_counter() - t0


# --------------------------------------------------------------------------- inputs


def make_depth(n: int) -> np.ndarray:
    """(n, n) float32 depth in pixel units: tilted plane, NaN sky, four spheres in front."""
    y = np.arange(n, dtype=np.float32)[:, None]
    x = np.arange(n, dtype=np.float32)[None, :]

    def plane(yy, xx):
        return np.float32(0.5 * n) + np.float32(0.35) * (n - yy) + np.float32(0.05) * xx

    depth = plane(y, x)  # broadcasts to (n, n) float32
    depth[: int(SKY_FRACTION * n)] = np.nan
    for fx, fy, fr in SPHERES:
        cx, cy, r = fx * n, fy * n, fr * n
        r0, r1 = max(0, int(cy - r)), min(n, int(cy + r) + 2)
        c0, c1 = max(0, int(cx - r)), min(n, int(cx + r) + 2)
        yy = y[r0:r1] - np.float32(cy)
        xx = x[:, c0:c1] - np.float32(cx)
        d2 = np.float32(r * r) - yy * yy - xx * xx
        zs = plane(np.float32(cy), np.float32(cx)) - np.float32(1.2 * r)
        zs = zs - np.sqrt(np.maximum(d2, np.float32(0)))
        sub = depth[r0:r1, c0:c1]
        # in front of the plane, and over the sky (NaN <= z is False)
        np.copyto(sub, zs, where=(d2 > 0) & ~(sub <= zs))
    return depth


def make_mask(n: int) -> np.ndarray:
    """Centred disc covering MASK_COVERAGE of the (n, n) image."""
    c = (n - 1) / 2.0
    r2 = MASK_COVERAGE * n * n / math.pi
    y = (np.arange(n, dtype=np.float64)[:, None] - c) ** 2
    x = (np.arange(n, dtype=np.float64)[None, :] - c) ** 2
    return (y + x) <= r2


def make_normals(depth: np.ndarray) -> np.ndarray:
    """Unit normals (n, n, 3) float32 of the depth surface; NaN where the depth is NaN."""
    gy, gx = np.gradient(depth)
    nrm = np.empty((*depth.shape, 3), dtype=np.float32)
    nrm[..., 0] = -gx
    nrm[..., 1] = gy
    nrm[..., 2] = 1.0
    del gx, gy
    nrm /= np.sqrt((nrm * nrm).sum(axis=-1, keepdims=True))
    return nrm


# --------------------------------------------------------------------------- callables


def scipy_sobel(img: np.ndarray) -> np.ndarray:
    gx = ndimage.sobel(img, axis=1)
    gy = ndimage.sobel(img, axis=0)
    return np.hypot(gx, gy, out=gx)


def _probe(call: Callable[[], object]) -> Callable[[], object] | None:
    """``call`` if it runs (the private API may have changed under this script), else None."""
    try:
        call()
    except Exception:  # a diagnostic column: any incompatibility just shows "-"
        return None
    return call


# Modules of the public operators whose ``np.empty`` calls allocate the results.
_ALLOC_MODULES = ("sciviz_gbuf.filters.operators", "sciviz_gbuf.filters._stencil_kernels")


class _ReusedEmpty:
    """Stands in for ``numpy`` in the operator modules: the i-th ``np.empty`` of a call gets the
    same buffer in every call (so no allocation and no page faults); all else is numpy."""

    def __init__(self) -> None:
        self.buffers: list[np.ndarray] = []
        self.index = 0
        self.calls = 0

    def __getattr__(self, name: str):
        return getattr(np, name)

    def empty(self, shape, dtype=float, order="C", **kwargs):
        shape = tuple(shape) if isinstance(shape, (tuple, list)) else (int(shape),)
        dt = np.dtype(dtype)
        self.calls += 1
        i, self.index = self.index, self.index + 1
        if i < len(self.buffers):
            buf = self.buffers[i]
            if buf.shape == shape and buf.dtype == dt and not kwargs:
                return buf
            self.buffers[i] = buf = np.empty(shape, dt, order, **kwargs)
            return buf
        buf = np.empty(shape, dt, order, **kwargs)
        self.buffers.append(buf)
        return buf


def no_alloc(fn: Callable[[], np.ndarray]) -> Callable[[], np.ndarray] | None:
    """``fn`` (a public operator call) with its result buffers reused between calls.

    Times the operator without the cost of allocating and first-touching a new result: the
    difference to the plain call is what the allocation costs. None when the operator modules
    do not allocate through ``np.empty`` (the trick does not apply) or the result differs.
    """
    mods = [sys.modules.get(name) for name in _ALLOC_MODULES]
    mods = [m for m in mods if m is not None and getattr(m, "np", None) is np]
    if not mods:
        return None
    shim = _ReusedEmpty()

    def call() -> np.ndarray:
        shim.index = 0
        for m in mods:
            m.np = shim
        try:
            return fn()
        finally:
            for m in mods:
                m.np = np

    try:
        same = np.array_equal(fn(), call(), equal_nan=True)
    except Exception:  # e.g. numba could not compile with the stand-in: just show "-"
        return None
    return call if same and shim.calls > 0 else None


def _gbuf_kernel(gb, which: str):
    """The private numba kernel of an edge function (no dilation / downsample / copies)."""
    try:
        from sciviz_gbuf.filters import _edge_kernels as k
        from sciviz_gbuf.filters import edges

        parallel, inv_d, inv_w = edges._camera_terms(gb)
        args = (*edges._kernel_inputs(gb), parallel, inv_d)
        h, w = gb.shape
        jump, crease = edges.DEFAULT_DEPTH_JUMP, edges.DEFAULT_CREASE_ANGLE
        a = np.empty((h, w), dtype=np.float32)
        b = np.empty((h, w), dtype=np.float32)
        mode = {"pair": k.MODE_PAIRS, "c1": k.MODE_C1}.get(which, k.MODE_DIAGONAL)
        kern = k.edge_pass
        return _probe(lambda: kern(*args, inv_w, jump, crease, 0.5 * crease, True, mode, a, b))
    except (ImportError, AttributeError):
        return None


# --------------------------------------------------------------------------- sections


def bench_synthetic(
    n: int, target: float, min_reps: int, max_reps: int, core: bool, idle: float
) -> tuple[list[Row], str]:
    t0 = time.perf_counter()
    depth = make_depth(n)
    disc = make_mask(n)
    info = (
        f"{n}^2 inputs: depth finite {np.isfinite(depth).mean():.0%}, mask covers "
        f"{disc.mean():.0%} (generated in {time.perf_counter() - t0:.1f} s, untimed)"
    )
    rows: list[Row] = []

    def cell(section, name, mask_label, fn, peer=False):
        row = Row(section, name, n, mask_label, peer=peer)
        wait_idle(idle)
        with LoadMeter() as load:
            row.times = measure(fn, target, min_reps, max_reps)
            kern = no_alloc(fn) if core and not peer else None
            if kern is not None:
                row.core_times = measure(kern, target, min_reps, max_reps)
        row.other_load = load.other()
        rows.append(row)

    # peers first: the reference of the ratio column
    cell("synthetic", SKIMAGE, "no", lambda: skfilters.sobel(depth), peer=True)
    cell("synthetic", SKIMAGE, "yes", lambda: skfilters.sobel(depth, mask=disc), peer=True)
    cell("synthetic", "scipy.ndimage.sobel (hypot)", "no", lambda: scipy_sobel(depth), peer=True)
    cell("synthetic", "numpy copy (alloc + write)", "no", depth.copy, peer=True)

    masks = (("no", None), ("yes", disc))

    def both(name, call):
        """One cell without and one with the mask; ``call(mask)`` runs the operator."""
        for label, m in masks:
            cell("synthetic", name, label, lambda m=m: call(m))

    both("sobel_gradient", lambda m: filters.sobel_gradient(depth, mask=m))
    both("second_order", lambda m: filters.second_order(depth, mask=m))
    grad = filters.sobel_gradient(depth)
    both("normalize_gradient", lambda m: filters.normalize_gradient(grad, mask=m))
    lap = filters.second_order(depth)
    both("suppress_zeroth_order", lambda m: filters.suppress_zeroth_order(lap, grad, mask=m))
    grad = lap = None  # free (the closures above are done)
    both("c1_discontinuity", lambda m: filters.c1_discontinuity(depth, mask=m))
    zbuf = depth / np.float32(2 * n)  # z-buffer-like values in [0, 1]
    both(
        "diagonal_depth_discontinuity", lambda m: filters.diagonal_depth_discontinuity(zbuf, mask=m)
    )
    zbuf = None
    normal = make_normals(depth)
    both(
        "diagonal_normal_discontinuity",
        lambda m: filters.diagonal_normal_discontinuity(normal, mask=m),
    )
    normal = depth = disc = None
    gc.collect()
    return rows, info


def bench_gbuffer(
    s: int, target: float, min_reps: int, max_reps: int, core: bool, idle: float
) -> tuple[list[Row], str]:
    mesh = sciviz_gbuf.datasets.load_nut()
    gc.collect()
    gb = sciviz_gbuf.capture(mesh, window_size=(s, s))  # untimed warm-up (first touch)
    del gb
    cap_times = []
    for _ in range(2):
        gc.collect()
        t0 = time.perf_counter()
        gb = sciviz_gbuf.capture(mesh, window_size=(s, s))
        cap_times.append(time.perf_counter() - t0)
    info = (
        f"nut capture {s}x{s}: best {min(cap_times):.3f} s of {len(cap_times)} "
        f"(= {s * s / 1e6 / min(cap_times):.0f} MPix/s), coverage {gb.mask.mean():.0%}, "
        f"triangles {mesh.n_cells}"
    )
    rows: list[Row] = []
    cases = (
        (SKIMAGE + " (on sz)", lambda: skfilters.sobel(gb.sz), None, True),
        ("profile_edges", lambda: filters.profile_edges(gb), "pair", False),
        ("internal_edges", lambda: filters.internal_edges(gb), "pair", False),
        ("crease_edges", lambda: filters.crease_edges(gb), "pair", False),
        ('edge_map(operator="diagonal")', lambda: filters.edge_map(gb), "diagonal", False),
        ('edge_map(operator="c1")', lambda: filters.edge_map(gb, operator="c1"), "c1", False),
    )
    pair_kernel: list[float] = []
    for name, fn, which, peer in cases:
        row = Row("nut gbuf", name, s, "gb.mask", peer=peer)
        wait_idle(idle)
        with LoadMeter() as load:
            row.times = measure(fn, target, min_reps, max_reps)
            if core and which is not None:
                if which == "pair" and pair_kernel:
                    row.core_times = pair_kernel  # the same kernel for all three
                else:
                    kern = _gbuf_kernel(gb, which)
                    if kern is not None:
                        row.core_times = measure(kern, target, min_reps, max_reps)
                    if which == "pair":
                        pair_kernel = row.core_times
        row.other_load = load.other()
        rows.append(row)
    gb = None
    gc.collect()
    return rows, info


# --------------------------------------------------------------------------- reporting


def machine_facts() -> list[str]:
    try:
        n_avail = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        n_avail = os.cpu_count()
    cpu = platform.processor() or "?"
    mem = "?"
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next(
                (ln.split(":", 1)[1].strip() for ln in fh if ln.startswith("model name")), cpu
            )
        with open("/proc/meminfo") as fh:
            kb = int(next(ln for ln in fh if ln.startswith("MemTotal")).split()[1])
            mem = f"{kb / 1024**2:.1f} GiB"
    except (OSError, StopIteration, ValueError):
        pass
    try:
        layer = numba.threading_layer()
    except ValueError:  # no parallel function has run yet
        layer = f"not yet initialised (config {numba.config.THREADING_LAYER})"
    src = sorted(Path(filters.__file__).parent.glob("*.py"))
    digest = hashlib.sha1(b"".join(p.read_bytes() for p in src)).hexdigest()[:12]
    newest = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(max(p.stat().st_mtime for p in src)))
    return [
        f"machine: {platform.machine()} {platform.system()} {platform.release()}; "
        f"cpu_count={os.cpu_count()} (usable {n_avail}); {cpu}; RAM {mem}",
        f"numba {numba.__version__}: threads {numba.get_num_threads()}, threading layer {layer}",
        f"python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
        f"scikit-image {skimage.__version__}, sciviz_gbuf {sciviz_gbuf.__version__}",
        f"sciviz_gbuf/filters/*.py: sha1 {digest} (newest file {newest}); "
        f"load average at start {', '.join(f'{x:.2f}' for x in os.getloadavg())}",
    ]


def warm_up() -> float:
    """Seconds for the first call of every operator on a tiny image (numba compile / cache)."""
    depth = make_depth(64)
    disc = make_mask(64)
    normal = make_normals(depth)
    t0 = time.perf_counter()
    for m in (None, disc):
        g = filters.sobel_gradient(depth, mask=m)
        lap = filters.second_order(depth, mask=m)
        filters.normalize_gradient(g, mask=m)
        filters.suppress_zeroth_order(lap, g, mask=m)
        filters.c1_discontinuity(depth, mask=m)
        filters.diagonal_depth_discontinuity(depth / 128, mask=m)
        filters.diagonal_normal_discontinuity(normal, mask=m)
    return time.perf_counter() - t0


COLUMNS = (
    "section",
    "operator",
    "size",
    "mask",
    "N",
    "best ms",
    "MPix/s",
    "median MPix/s",
    "vs skimage",
    "core MPix/s",
    "other load",
)
LEFT = {"section", "operator", "mask"}


def row_values(row: Row, ref: dict[tuple[str, int], float]) -> dict[str, str]:
    r = ref.get((row.section, row.size))
    k = row.core()
    return {
        "section": row.section,
        "operator": row.operator,
        "size": f"{row.size}^2",
        "mask": row.mask,
        "N": str(len(row.times)),
        "best ms": f"{1e3 * min(row.times):.2f}",
        "MPix/s": f"{row.best():.0f}",
        "median MPix/s": f"{row.median():.0f}",
        "vs skimage": "-" if r is None else f"{row.best() / r:.1f}x",
        "core MPix/s": "-" if k is None else f"{k:.0f}",
        "other load": "-" if row.other_load is None else f"{row.other_load:.0%}",
    }


def format_table(values: list[dict[str, str]]) -> str:
    widths = {c: max(len(c), *(len(v[c]) for v in values)) for c in COLUMNS}

    def line(vals: dict[str, str]) -> str:
        cells = (
            vals[c].ljust(widths[c]) if c in LEFT else vals[c].rjust(widths[c]) for c in COLUMNS
        )
        return "| " + " | ".join(cells) + " |"

    rule = "|" + "|".join(
        (":" + "-" * (widths[c] + 1)) if c in LEFT else ("-" * (widths[c] + 1) + ":")
        for c in COLUMNS
    )
    return "\n".join([line({c: c for c in COLUMNS}), rule + "|", *(line(v) for v in values)])


def reference(rows: list[Row]) -> dict[tuple[str, int], float]:
    """(section, size) -> best MPix/s of skimage.filters.sobel without a mask."""
    return {
        (r.section, r.size): r.best()
        for r in rows
        if r.operator.startswith(SKIMAGE) and r.mask in ("no", "gb.mask")
    }


# --------------------------------------------------------------------------- main


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument(
        "--quick",
        action="store_true",
        help="sizes 1024 2048, capture 1024, ~0.3 s per cell (~30 s)",
    )
    parser.add_argument(
        "--sizes", type=int, nargs="+", default=None, help="image edges (1024 4096 8192)"
    )
    parser.add_argument(
        "--capture-sizes",
        type=int,
        nargs="*",
        default=None,
        help="nut capture edges (1024 2048; --quick: 1024); none to skip the section",
    )
    parser.add_argument(
        "--target", type=float, default=None, help="seconds per cell (0.75; --quick: 0.3)"
    )
    parser.add_argument("--min-repeats", type=int, default=3, help="repeats per cell at least")
    parser.add_argument("--max-repeats", type=int, default=1000, help="repeats per cell at most")
    parser.add_argument(
        "--no-core", action="store_true", help="skip the core column (about halves the run)"
    )
    parser.add_argument(
        "--wait-idle",
        type=float,
        default=0.0,
        metavar="S",
        help=f"before each cell wait up to S s until other processes use < "
        f"{IDLE_THRESHOLD:.0%}% of the CPU (shared machines; default 0: no waiting)",
    )
    parser.add_argument("--csv", metavar="PATH", help="also write the raw results as CSV")
    args = parser.parse_args(argv)
    sizes = args.sizes or ([1024, 2048] if args.quick else [1024, 4096, 8192])
    if args.capture_sizes is not None:
        capture_sizes = args.capture_sizes
    else:
        capture_sizes = [1024] if args.quick else [1024, 2048]
    target = args.target if args.target is not None else (0.3 if args.quick else 0.75)
    if args.min_repeats < 1 or args.max_repeats < args.min_repeats or target <= 0:
        parser.error("need 1 <= --min-repeats <= --max-repeats and --target > 0")
    if min(sizes) < 8:
        parser.error("--sizes must be >= 8")
    core = not args.no_core

    t_start = time.perf_counter()
    run_load = LoadMeter().start()
    t_first = warm_up()
    print("sciviz_gbuf filters benchmark")
    for fact in machine_facts():
        print(fact)
    print(f"first call of all operators at 64^2: {t_first:.2f} s (numba compile / cache load)")
    missing = sorted(set(getattr(filters.operators, "__all__", ())) - set(OPERATORS))
    if missing:
        print(f"note: public operators not covered by this benchmark: {', '.join(missing)}")
    print(
        f"sizes {sizes}, nut captures {capture_sizes}; each cell: 1 untimed warm-up call, then "
        f"N timed calls for ~{target:g} s (N >= {args.min_repeats}); MPix/s = n^2 / best"
    )
    print(flush=True)

    rows: list[Row] = []
    for n in sizes:
        t0 = time.perf_counter()
        new, info = bench_synthetic(
            n, target, args.min_repeats, args.max_repeats, core, args.wait_idle
        )
        rows += new
        print(f"  {info}; cells {time.perf_counter() - t0:.0f} s", flush=True)
    for s in capture_sizes:
        t0 = time.perf_counter()
        new, info = bench_gbuffer(
            s, target, args.min_repeats, args.max_repeats, core, args.wait_idle
        )
        rows += new
        print(f"  {info}; cells {time.perf_counter() - t0:.0f} s", flush=True)

    ref = reference(rows)
    print()
    print(format_table([row_values(r, ref) for r in rows]))
    print()
    print(
        "columns: MPix/s = image pixels (covered or not) / best time of N warm calls; vs skimage "
        f"= MPix/s / that of {SKIMAGE}\n"
        "  without a mask on the same image in the same run (nut gbuf: on the capture's sz); "
        "core MPix/s = operators: the same call\n"
        "  with its result buffer reused (no allocation / page faults); gbuf: the numba kernel "
        "alone (edge_pass, pair /\n"
        "  edge-map mode, without dilation, downsample, clip, stack); other load = CPU share "
        "taken by other processes."
    )

    print()
    print(
        f"goal: >= {GOAL_MPIX:g} MPix/s and >= {GOAL_RATIO:g}x {SKIMAGE} at {GOAL_SIZE}^2 on "
        f"{numba.get_num_threads()} numba threads"
    )
    goal_rows = [r for r in rows if r.size == GOAL_SIZE and r.section == "synthetic" and not r.peer]
    if not goal_rows:
        print(f"  (not measured in this run: needs size {GOAL_SIZE})")
    else:
        r_ref = ref[("synthetic", GOAL_SIZE)]
        print(
            f"  ({SKIMAGE} runs at {r_ref:.0f} MPix/s here, so {GOAL_MPIX:g} MPix/s is "
            f"{GOAL_MPIX / r_ref:.1f}x it, and {GOAL_RATIO:g}x it is "
            f"{GOAL_RATIO * r_ref:.0f} MPix/s)"
        )

        def label(r: Row) -> str:
            return f"{r.operator} (mask {r.mask})"

        fast = [label(r) for r in goal_rows if r.best() >= GOAL_MPIX]
        ratio = [label(r) for r in goal_rows if r.best() / r_ref >= GOAL_RATIO]
        both = [x for x in fast if x in ratio]
        total = len(goal_rows)
        print(f"  >= {GOAL_MPIX:g} MPix/s: {len(fast)}/{total}: " + ("; ".join(fast) or "none"))
        print(
            f"  >= {GOAL_RATIO:g}x skimage: {len(ratio)}/{total}: " + ("; ".join(ratio) or "none")
        )
        print(f"  goal met (both) by {len(both)}/{total}: " + ("; ".join(both) or "none"))
        slow = [
            f"{label(r)} {r.best():.0f} MPix/s ({r.best() / r_ref:.1f}x)"
            for r in goal_rows
            if label(r) not in both
        ]
        if slow:
            print("  short of it: " + "; ".join(slow))

    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            writer = csv.writer(fh)
            writer.writerow(
                [
                    "section",
                    "operator",
                    "size",
                    "mask",
                    "repeats",
                    "best_s",
                    "median_s",
                    "mpix_per_s_best",
                    "mpix_per_s_median",
                    "ratio_vs_skimage",
                    "core_best_s",
                    "core_mpix_per_s",
                    "other_load",
                    "runs_s",
                ]
            )
            for r in rows:
                rr = ref.get((r.section, r.size))
                k = r.core()
                writer.writerow(
                    [
                        r.section,
                        r.operator,
                        r.size,
                        r.mask,
                        len(r.times),
                        f"{min(r.times):.6f}",
                        f"{statistics.median(r.times):.6f}",
                        f"{r.best():.1f}",
                        f"{r.median():.1f}",
                        "" if rr is None else f"{r.best() / rr:.3f}",
                        f"{min(r.core_times):.6f}" if r.core_times else "",
                        "" if k is None else f"{k:.1f}",
                        "" if r.other_load is None else f"{r.other_load:.3f}",
                        " ".join(f"{t:.6f}" for t in r.times),
                    ]
                )
        print(f"\nCSV written to {args.csv}")
    run_load.stop()
    other, steal = run_load.other(), run_load.steal()
    if other is not None:
        print(
            f"\nother processes used {other:.0%} of the machine's CPU during the run "
            f"(hypervisor steal {steal or 0.0:.0%})"
            + ("; figures are affected by that load" if other > 0.05 else "")
        )
    if args.wait_idle > 0:
        print(f"waited {_waited[0]:.0f} s in total for the machine to be idle (--wait-idle)")
    print(f"\ntotal benchmark wall time: {time.perf_counter() - t_start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
