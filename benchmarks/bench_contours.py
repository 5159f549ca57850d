"""Benchmark: contour lines and hatching of ``sciviz_gbuf.filters`` on a DEM, in MPix/s.

Run from the project root with the project's venv active::

    python benchmarks/bench_contours.py            # 4096^2 and 8192^2 (~8 min)
    python benchmarks/bench_contours.py --quick    # 1024^2, fewer repeats (~20 s)
    python benchmarks/bench_contours.py --sizes 2048 4096 --peer-budget 20
    python benchmarks/bench_contours.py --csv out.csv --wait-idle 60   # shared machine

The grid is a synthetic DEM in metres, 0..2000 m, the same terrain at every size: a fractal
(1/f^1.9 amplitude) relief by spectral synthesis with a regional tilt and eight gaussian
massifs, made on a 1024^2 grid, spline-upsampled to n x n, plus 0.3 m of per-pixel sensor
noise (deterministic seed). That noise is per pixel, so a finer grid has more tiny closed
contours in flat areas (as a real DEM's noise gives): the peers' line counts grow faster than
the lines' length. The ``NaN 5 %`` variant sets irregular nodata voids (a thresholded
smooth random field, 5 % of the pixels) to NaN. Cases, each on that same grid:

* ``regular``: ``contour_lines(dem, interval=25)``: 79 levels (25..1975 m), a topographic map;
  without and with the voids (as NaN in the field, and as ``mask=`` on the finite DEM);
* ``major/minor``: ``contour_lines(dem, interval=5, major_interval=25)``: 399 minor lines, every
  fifth a major one (Fig. 11 of the paper), minor lines thinning out where they crowd;
* ``levels``: ``contour_lines(dem, levels=LEVELS)``: an explicit irregular list of 50 levels,
  dense low down (10 m steps) and sparse high up (100 m);
* ``hatching``: ``hatching(dem, spacing=8, interval=1)``: no peer (the interval is chosen per
  pixel).

Peers, same grid, same levels, same run:

* ``skimage.measure.find_contours`` called once per level (marching squares, vector polylines;
  the NaN voids are passed as they are, like to ours). One loop over all the levels may take
  ``--peer-budget`` seconds (60): where it would take longer, an evenly spread subset of the
  levels is timed and the time scaled by (all levels / timed levels); the ``levels`` column
  then says e.g. ``399 (133 timed)``. The estimate comes from one untimed call at the middle
  level.
* ``gdal_contour`` (GDAL's command-line tool, if on PATH), run with ``subprocess``: ``-i``
  for regular levels, ``-fl`` for the explicit list. The grid is written once per size, untimed,
  as a raw float32 ``.bil`` with an ESRI ``.hdr`` and converted by ``gdal_translate`` to a
  GeoTIFF (NaN as nodata for the voids); without ``gdal_translate`` the ``.bil`` is read
  directly. The output goes to ``--gdal-format`` (FlatGeobuf; deleted between runs, untimed);
  the regular case also runs the ``Memory`` driver (nothing written) to show what writing costs.
  The time includes starting the process and reading the raster, as a user would see it; the
  start-up alone is reported.

Our rows: one untimed call first, then repeated for about ``--target`` seconds (N times, at
least ``--min-repeats``); MPix/s is n^2 / best time, the median is shown too. Peers: best of N
runs (N >= ``--min-repeats`` while within ``--peer-budget``). ``core MPix/s`` is our call with
its result buffer reused (``no_alloc`` of ``bench_filters.py``: no allocation, no page faults).
``vs skimage`` / ``vs gdal`` = our MPix/s / the peer's on the same case, size and voids. The
first call of each numba kernel compiles it (or loads the cache): that is timed separately on a
64^2 grid before everything else. ``other load`` is the CPU share other processes took during
the cell; on a 2-core machine anything above a few % slows the parallel kernels.
"""

from __future__ import annotations

import argparse
import csv
import gc
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

# bench_filters sets up headless VTK before sciviz_gbuf is imported: import it first.
import bench_filters as bf
from bench_filters import LoadMeter, machine_facts, measure, no_alloc, wait_idle
from scipy import ndimage
from skimage import measure as skmeasure

from sciviz_gbuf.filters import contour_lines, hatching

TOP = 2000.0  # m: the DEM spans 0..TOP
INTERVAL = 25.0  # m: regular contours
MINOR = 5.0  # m: minor contours under the 25 m majors
HOLE_FRACTION = 0.05
BASE_RES = 1024  # the terrain is made at this resolution, then upsampled
SEED = 1990
LEVELS = (
    *range(10, 100, 10),
    *range(100, 500, 25),
    *range(500, 1500, 50),
    *range(1500, 2000, 100),
)
HATCH = {"spacing": 8.0, "interval": 1.0}
SKIMAGE = "skimage find_contours"
GDAL = "gdal_contour"


@dataclass
class Row(bf.Row):
    """One cell. ``section`` is the case, ``operator`` the method, ``mask`` the voids; for a
    peer timed on a subset of the levels, ``times`` are already scaled to all of them."""

    levels: str = ""
    method: str = "ours"  # "ours", "skimage" or "gdal"
    output: str = ""


class Meter(LoadMeter):
    """``LoadMeter`` that counts the CPU time of this process's finished children
    (gdal_contour, run by this script) as its own, not as other load."""

    @staticmethod
    def _children() -> float:
        t = os.times()
        return t.children_user + t.children_system

    def start(self) -> Meter:
        self.kids = self._children()
        super().start()
        return self

    def stop(self) -> None:
        super().stop()
        self.kids = self._children() - self.kids

    def other(self) -> float | None:
        share = super().other()
        if share is None:
            return None
        wall = (self.b[0] - self.a[0]) * (os.cpu_count() or 1)
        return max(0.0, share - self.kids / wall) if wall > 0 else share


# --------------------------------------------------------------------------- inputs


def _upsample(z: np.ndarray, n: int, order: int) -> np.ndarray:
    if z.shape[0] == n:
        return z
    return ndimage.zoom(z, n / z.shape[0], order=order, grid_mode=True, mode="reflect")


def make_dem(n: int, seed: int = SEED) -> np.ndarray:
    """(n, n) float32 terrain in metres spanning 0..TOP (see the module docstring)."""
    rng = np.random.default_rng(seed)
    m = min(n, BASE_RES)
    fy = np.fft.fftfreq(m)[:, None]
    fx = np.fft.rfftfreq(m)[None, :]
    f = np.hypot(fx, fy)
    f[0, 0] = 1.0
    amp = np.where(f > 0.25, 0.0, f**-1.9)  # no detail finer than 4 base cells
    amp[0, 0] = 0.0  # the mean
    spec = amp * (rng.standard_normal(amp.shape) + 1j * rng.standard_normal(amp.shape))
    z = np.fft.irfft2(spec, s=(m, m))
    z *= 350.0 / z.std()
    t = (np.arange(m) + 0.5) / m
    z += 500.0 * t[None, :] + 250.0 * t[:, None]
    for _ in range(8):
        cx, cy = rng.uniform(0.1, 0.9, 2)
        s, h = rng.uniform(0.05, 0.18), rng.uniform(250.0, 900.0)
        z += h * np.exp(-((t[:, None] - cy) ** 2 + (t[None, :] - cx) ** 2) / s**2)
    dem = _upsample(z.astype(np.float32), n, 3)
    noise = rng.standard_normal((n, n), dtype=np.float32)
    noise *= np.float32(0.3)
    dem += noise
    del noise
    lo, hi = float(dem.min()), float(dem.max())
    dem -= np.float32(lo)
    dem *= np.float32(TOP / (hi - lo))
    return dem


def make_holes(n: int, seed: int = SEED + 1) -> np.ndarray:
    """(n, n) bool: irregular voids covering ~HOLE_FRACTION of the grid."""
    m = min(n, 256)
    rng = np.random.default_rng(seed)
    field = ndimage.gaussian_filter(rng.standard_normal((m, m)), m / 40, mode="wrap")
    thr = np.quantile(field, 1.0 - HOLE_FRACTION)
    return _upsample(field.astype(np.float32), n, 1) > thr


def regular_levels(step: float) -> np.ndarray:
    """The multiples of ``step`` strictly inside (0, TOP): the levels a line can lie on."""
    return np.arange(step, TOP - step / 2, step)


# --------------------------------------------------------------------------- peers


def run_capped(
    fn: Callable[[], object], reps: int, budget: float, prepare=None
) -> tuple[list[float], object]:
    """Times of up to ``reps`` calls of ``fn``, stopping early once ``budget`` s are spent
    (always one); ``prepare`` runs untimed before each call. Returns the last result too."""
    times: list[float] = []
    out = None
    while len(times) < reps and (not times or sum(times) + times[-1] <= budget):
        if prepare is not None:
            prepare()
        gc.collect()
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return times, out


def skimage_row(row: Row, grid: np.ndarray, levels: np.ndarray, reps: int, budget: float) -> Row:
    """``find_contours`` over ``levels`` (or a spread subset of them, scaled up)."""
    k_all = len(levels)
    t0 = time.perf_counter()
    skmeasure.find_contours(grid, float(levels[k_all // 2]))  # warm-up and estimate
    per_level = time.perf_counter() - t0
    k = k_all if per_level * k_all <= budget else max(1, int(budget / per_level))
    subset = levels[np.unique(np.linspace(0, k_all - 1, k).round().astype(int))]
    scale = k_all / len(subset)
    if scale > 1:
        reps = 1

    def loop() -> tuple[int, int]:
        lines = verts = 0
        for lv in subset:
            cs = skmeasure.find_contours(grid, float(lv))
            lines += len(cs)
            verts += sum(len(c) for c in cs)
        return lines, verts

    times, (lines, verts) = run_capped(loop, reps, budget)
    row.times = [t * scale for t in times]
    row.levels = f"{k_all}" + (f" ({len(subset)} timed)" if scale > 1 else "")
    approx = "~" if scale > 1 else ""
    row.output = f"{approx}{lines * scale:,.0f} lines, {approx}{verts * scale / 1e6:.1f} M pts"
    return row


class Gdal:
    """``gdal_contour`` on GeoTIFF copies of the grids, in a temporary folder."""

    def __init__(self, fmt: str, ext: str) -> None:
        self.exe = shutil.which("gdal_contour")
        self.translate = shutil.which("gdal_translate")
        self.ogrinfo = shutil.which("ogrinfo")
        self.fmt, self.ext = fmt, ext
        self.dir = Path(tempfile.mkdtemp(prefix="bench_contours_"))

    def close(self) -> None:
        shutil.rmtree(self.dir, ignore_errors=True)

    def write(self, grid: np.ndarray, name: str) -> tuple[Path, str]:
        """The grid as a file gdal_contour reads (untimed); the format's name."""
        h, w = grid.shape
        bil = self.dir / f"{name}.bil"
        grid.astype("<f4", copy=False).tofile(bil)
        header = {
            "BYTEORDER": "I",
            "LAYOUT": "BIL",
            "NROWS": h,
            "NCOLS": w,
            "NBANDS": 1,
            "NBITS": 32,
            "PIXELTYPE": "FLOAT",
            "ULXMAP": 0.5,  # pixel centres at x + 0.5, y + 0.5, like find_contours' (row, col)
            "ULYMAP": h - 0.5,
            "XDIM": 1,
            "YDIM": 1,
        }
        bil.with_suffix(".hdr").write_text("".join(f"{k} {v}\n" for k, v in header.items()))
        if self.translate is None:
            return bil, "EHdr .bil (no gdal_translate)"
        tif = self.dir / f"{name}.tif"
        nodata = ["-a_nodata", "nan"] if np.isnan(grid).any() else []
        subprocess.run([self.translate, "-q", "-of", "GTiff", *nodata, bil, tif], check=True)
        for p in (bil, bil.with_suffix(".hdr")):
            p.unlink()
        return tif, "GeoTIFF" + (" (nodata NaN)" if nodata else "")

    def command(self, src: Path, levels_args: list[str], fmt: str) -> tuple[list, Path]:
        out = self.dir / "out" / ("out" + (self.ext if fmt == self.fmt else ""))
        cmd = [self.exe, "-q", *levels_args, "-a", "elev", "-f", fmt, src, out]
        return cmd, out

    def startup(self) -> float:
        """Seconds for a gdal_contour run on a 4 x 4 grid: process start + library load."""
        src, _ = self.write(np.arange(16, dtype=np.float32).reshape(4, 4), "tiny")
        cmd, _ = self.command(src, ["-i", "5"], "Memory")
        times, _ = run_capped(lambda: subprocess.run(cmd, check=True), 5, 10.0)
        return min(times)

    def row(self, row: Row, src: Path, levels_args: list[str], fmt: str, reps, budget) -> Row:
        cmd, out = self.command(src, levels_args, fmt)

        def clean() -> None:
            shutil.rmtree(out.parent, ignore_errors=True)
            out.parent.mkdir()

        row.times, _ = run_capped(lambda: subprocess.run(cmd, check=True), reps, budget, clean)
        row.output = "nothing written" if fmt == "Memory" else self._features(out)
        clean()
        return row

    def _features(self, out: Path) -> str:
        size = sum(p.stat().st_size for p in out.parent.iterdir()) / 1e6
        text = ""
        if self.ogrinfo is not None:
            info = subprocess.run(
                [self.ogrinfo, "-so", "-al", out], capture_output=True, text=True, check=False
            )
            text = next(
                (
                    ln.split(":")[1].strip()
                    for ln in info.stdout.splitlines()
                    if "Feature Count" in ln
                ),
                "",
            )
        return (f"{int(text):,} lines, " if text.isdigit() else "") + f"{size:.0f} MB {self.fmt}"


# --------------------------------------------------------------------------- cells


@dataclass
class Settings:
    target: float
    min_reps: int
    max_reps: int
    peer_budget: float
    core: bool
    idle: float


@dataclass
class Case:
    """One contouring job: our calls on it, and the same levels for the peers."""

    name: str
    voids: str
    grid: np.ndarray  # what the peers get (NaN voids as they are)
    levels: np.ndarray  # the levels a line can lie on, for find_contours
    ours: list[tuple[str, Callable[[], np.ndarray]]]
    gdal_args: list[str]


def ours_row(row: Row, fn: Callable[[], np.ndarray], st: Settings) -> Row:
    row.times = measure(fn, st.target, st.min_reps, st.max_reps)
    kern = no_alloc(fn) if st.core else None
    if kern is not None:
        row.core_times = measure(kern, st.target, st.min_reps, st.max_reps)
    ink = fn()
    row.output = f"raster, {ink.mean():.1%} ink"
    return row


def make_cases(dem: np.ndarray, dem_nan: np.ndarray, covered: np.ndarray) -> list[Case]:
    reg, minor = regular_levels(INTERVAL), regular_levels(MINOR)
    lv = np.asarray(LEVELS, dtype=np.float64)
    q, mq = INTERVAL, MINOR
    regular_args = ["-i", f"{q:g}"]
    return [
        Case(
            "regular",
            "no",
            dem,
            reg,
            [(f"contour_lines(interval={q:g})", lambda: contour_lines(dem, interval=q))],
            regular_args,
        ),
        Case(
            "regular",
            "NaN 5%",
            dem_nan,
            reg,
            [
                (f"contour_lines(interval={q:g})", lambda: contour_lines(dem_nan, interval=q)),
                (
                    f"contour_lines(interval={q:g}, mask=)",
                    lambda: contour_lines(dem, interval=q, mask=covered),
                ),
            ],
            regular_args,
        ),
        Case(
            "major/minor",
            "no",
            dem,
            minor,
            [
                (
                    f"contour_lines(interval={mq:g}, major_interval={q:g})",
                    lambda: contour_lines(dem, interval=mq, major_interval=q),
                )
            ],
            ["-i", f"{mq:g}"],
        ),
        Case(
            "levels",
            "no",
            dem,
            lv,
            [(f"contour_lines(levels=[{len(lv)} values])", lambda: contour_lines(dem, levels=lv))],
            ["-fl", *(f"{x:g}" for x in lv)],
        ),
    ]


def bench_size(n: int, st: Settings, gdal: Gdal | None) -> list[Row]:
    t0 = time.perf_counter()
    dem = make_dem(n)
    holes = make_holes(n)
    dem_nan = dem.copy()
    dem_nan[holes] = np.nan
    covered = ~holes
    print(
        f"  {n}^2 DEM {float(dem.min()):.0f}..{float(dem.max()):.0f} m, voids {holes.mean():.1%}"
        f" (generated in {time.perf_counter() - t0:.1f} s, untimed)",
        flush=True,
    )
    del holes
    files: dict[str, Path] = {}
    if gdal is not None and gdal.exe is not None:
        t0 = time.perf_counter()
        files["no"], kind = gdal.write(dem, f"dem{n}")
        files["NaN 5%"], kind_nan = gdal.write(dem_nan, f"dem{n}_nan")
        print(
            f"  {n}^2 rasters for gdal_contour: {kind} / {kind_nan}, written in "
            f"{time.perf_counter() - t0:.1f} s (untimed)"
        )
    rows: list[Row] = []

    def cell(case: Case, method: str, label: str, voids: str, run: Callable[[Row], object]):
        row = Row(case.name, label, n, voids, method=method, peer=method != "ours")
        row.levels = str(len(case.levels))
        wait_idle(st.idle)
        with Meter() as load:
            run(row)
        row.other_load = load.other()
        rows.append(row)
        mpix = f"{row.best():9.1f} MPix/s" if row.times else ""
        print(f"    {n}^2 {case.name:<11} {voids:<7} {label:<50} {mpix}", flush=True)
        return row

    budget, reps = st.peer_budget, st.min_reps
    for case in make_cases(dem, dem_nan, covered):
        for label, fn in case.ours:
            voids = "mask 5%" if "mask=" in label else case.voids
            cell(case, "ours", label, voids, lambda r, fn=fn: ours_row(r, fn, st))
        cell(
            case,
            "skimage",
            SKIMAGE,
            case.voids,
            lambda r, c=case: skimage_row(r, c.grid, c.levels, reps, budget),
        )
        if gdal is None:
            continue
        if gdal.exe is None:
            cell(case, "gdal", GDAL, case.voids, lambda r: setattr(r, "output", "not on PATH"))
            continue
        src = files[case.voids]
        fmts = [gdal.fmt] + (["Memory"] if (case.name, case.voids) == ("regular", "no") else [])
        for fmt in fmts:
            label = f"{GDAL} -f {fmt}" + (" (no file)" if fmt == "Memory" else "")
            cell(
                case,
                "gdal",
                label,
                case.voids,
                lambda r, c=case, f=fmt, s=src: gdal.row(r, s, c.gdal_args, f, reps, budget),
            )
    hatch = Case("hatching", "no", dem, np.empty(0), [], [])
    label = f"hatching(spacing={HATCH['spacing']:g}, interval={HATCH['interval']:g})"
    row = cell(
        hatch, "ours", label, "no", lambda r: ours_row(r, lambda: hatching(dem, **HATCH), st)
    )
    row.levels = "per pixel"
    for p in files.values():
        p.unlink(missing_ok=True)
    return rows


def warm_up() -> list[tuple[str, float]]:
    """Seconds of the first call of each numba kernel on a 64^2 grid (compile / cache load)."""
    dem = make_dem(64)
    calls = (
        ("contour", lambda: contour_lines(dem, interval=INTERVAL)),
        ("levels", lambda: contour_lines(dem, levels=LEVELS)),
        ("hatch", lambda: hatching(dem, **HATCH)),
    )
    out = []
    for name, fn in calls:
        t0 = time.perf_counter()
        fn()
        out.append((name, time.perf_counter() - t0))
    return out


# --------------------------------------------------------------------------- reporting

COLUMNS = (
    "case",
    "voids",
    "method",
    "size",
    "levels",
    "N",
    "best ms",
    "MPix/s",
    "median MPix/s",
    "core MPix/s",
    "vs skimage",
    "vs gdal",
    "output",
    "other load",
)
LEFT = ("case", "voids", "method", "output")


def references(rows: list[Row]) -> dict[tuple[str, int, bool, str], float]:
    """(case, size, has voids, "skimage" / "gdal") -> the peer's best MPix/s (gdal: written
    to a file, not the Memory driver)."""
    return {
        (r.section, r.size, r.mask != "no", r.method): r.best()
        for r in rows
        if r.peer and r.times and "(no file)" not in r.operator
    }


def row_values(r: Row, ref: dict) -> dict[str, str]:
    def ratio(peer: str) -> str:
        base = ref.get((r.section, r.size, r.mask != "no", peer))
        return "-" if r.peer or base is None or not r.times else f"{r.best() / base:.1f}x"

    core = r.core()
    timed = bool(r.times)
    return {
        "case": r.section,
        "voids": r.mask,
        "method": r.operator,
        "size": f"{r.size}^2",
        "levels": r.levels,
        "N": str(len(r.times)) if timed else "-",
        "best ms": f"{1e3 * min(r.times):.1f}" if timed else "-",
        "MPix/s": f"{r.best():.1f}" if timed else "-",
        "median MPix/s": f"{r.median():.1f}" if timed else "-",
        "core MPix/s": "-" if core is None else f"{core:.1f}",
        "vs skimage": ratio("skimage"),
        "vs gdal": ratio("gdal"),
        "output": r.output,
        "other load": "-" if r.other_load is None else f"{r.other_load:.0%}",
    }


def format_table(values: list[dict[str, str]]) -> str:
    """A Markdown table; text columns left-aligned, numbers right-aligned."""
    width = {c: max(len(c), *(len(v[c]) for v in values)) for c in COLUMNS}
    just = {c: (str.ljust if c in LEFT else str.rjust) for c in COLUMNS}
    rule = {
        c: (":" + "-" * width[c] + "-") if c in LEFT else ("-" + "-" * width[c] + ":")
        for c in COLUMNS
    }
    head = " | ".join(just[c](c, width[c]) for c in COLUMNS)
    body = ["| " + " | ".join(just[c](v[c], width[c]) for c in COLUMNS) + " |" for v in values]
    return "\n".join([f"| {head} |", "|" + "|".join(rule.values()) + "|", *body])


def write_csv(path: str, rows: list[Row], ref: dict) -> None:
    fields = [
        "case",
        "voids",
        "method",
        "size",
        "levels",
        "repeats",
        "best_s",
        "median_s",
        "mpix_per_s",
        "mpix_per_s_median",
        "core_mpix_per_s",
        "vs_skimage",
        "vs_gdal",
        "output",
        "other_load",
        "runs_s",
    ]
    with open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(fields)
        for r in rows:
            v = row_values(r, ref)
            writer.writerow(
                [
                    r.section,
                    r.mask,
                    r.operator,
                    r.size,
                    r.levels,
                    len(r.times),
                    f"{min(r.times):.6f}" if r.times else "",
                    f"{statistics.median(r.times):.6f}" if r.times else "",
                    f"{r.best():.2f}" if r.times else "",
                    f"{r.median():.2f}" if r.times else "",
                    "" if r.core() is None else f"{r.core():.2f}",
                    v["vs skimage"].rstrip("x").replace("-", ""),
                    v["vs gdal"].rstrip("x").replace("-", ""),
                    r.output,
                    "" if r.other_load is None else f"{r.other_load:.3f}",
                    " ".join(f"{t:.6f}" for t in r.times),
                ]
            )


NOTES = """\
notes:
  * ours draws a raster: an (n, n) float32 image of antialiased ink, ready to composite; the peers
    trace vector polylines (skimage: a list of (k, 2) float64 arrays per level; gdal_contour: a
    vector file of LineStrings with an 'elev' attribute). Same grid, same levels, different output.
  * MPix/s = grid pixels / best time. ours: best of N warm calls; peers: best of N runs.
    vs skimage / vs gdal = ours MPix/s / the peer's on the same case, size and voids (ours with
    mask= against the peers on the NaN grid). gdal's reference is the row that writes a file,
    not "-f Memory".
  * "levels" = levels a line can lie on inside 0..2000 m. skimage rows marked "(k timed)" ran an
    evenly spread subset of k levels once and were scaled by levels / k (the loop over all of
    them would exceed --peer-budget); their line / point counts are scaled the same way (~).
  * major/minor: ours draws the 399 minor (5 m) lines with the 79 major (25 m) lines on top, in
    one pass; the peers trace all 399 levels (-i 5), the majors being among them.
  * hatching has no peer: its interval is chosen per pixel (2^k x 1 m) to keep 8 px spacing.
  * gdal_contour is single-threaded; its time includes process start-up and reading the raster
    from the page cache; ours and skimage run in this process on the in-memory grid.
  * core MPix/s = our call with its result buffer reused (no allocation, no page faults)."""


def load_summary(meter: Meter, waited: bool) -> str:
    """How busy the machine was with other work during the run."""
    share = meter.other()
    if share is None:
        return "other load: unknown (no /proc/stat)"
    parts = [
        f"other processes used {share:.0%} of the machine's CPU during the run "
        f"(hypervisor steal {meter.steal() or 0.0:.0%})"
    ]
    if share > bf.IDLE_THRESHOLD:
        parts.append("figures are affected by that load")
    if waited:
        parts.append(f"waited {bf._waited[0]:.0f} s in all for an idle machine (--wait-idle)")
    return "; ".join(parts)


# --------------------------------------------------------------------------- main


OPTIONS: tuple[tuple[str, dict], ...] = (
    ("--quick", {"action": "store_true", "help": "size 1024, fewer repeats (~20 s)"}),
    ("--sizes", {"type": int, "nargs": "+", "help": "grid edges (4096 8192)"}),
    ("--target", {"type": float, "help": "seconds per cell of ours (1; --quick: 0.3)"}),
    ("--min-repeats", {"type": int, "help": "repeats at least (3; --quick: 2)"}),
    ("--max-repeats", {"type": int, "default": 200, "help": "repeats of ours at most (200)"}),
    (
        "--peer-budget",
        {
            "type": float,
            "metavar": "S",
            "help": "seconds one peer cell may take (60; --quick: 10); beyond that skimage "
            "times a subset of the levels",
        },
    ),
    (
        "--gdal-format",
        {
            "default": "FlatGeobuf",
            "help": "OGR driver of gdal_contour's output (FlatGeobuf; or 'ESRI Shapefile', GPKG)",
        },
    ),
    ("--no-gdal", {"action": "store_true", "help": "skip gdal_contour"}),
    ("--no-core", {"action": "store_true", "help": "skip the core column"}),
    (
        "--wait-idle",
        {
            "type": float,
            "default": 0.0,
            "metavar": "S",
            "help": "shared machine: before each cell wait up to S s for the other processes to "
            "go quiet, as in bench_filters.py (0: do not wait)",
        },
    ),
    ("--csv", {"metavar": "PATH", "help": "also write the rows as CSV"}),
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    for flag, kwargs in OPTIONS:
        parser.add_argument(flag, **kwargs)
    args = parser.parse_args(argv)
    sizes = args.sizes or ([1024] if args.quick else [4096, 8192])
    st = Settings(
        target=args.target if args.target is not None else (0.3 if args.quick else 1.0),
        min_reps=args.min_repeats or (2 if args.quick else 3),
        max_reps=args.max_repeats,
        peer_budget=args.peer_budget or (10.0 if args.quick else 60.0),
        core=not args.no_core,
        idle=args.wait_idle,
    )
    if st.max_reps < st.min_reps or st.target <= 0 or st.peer_budget <= 0 or min(sizes) < 16:
        parser.error(
            "need --min-repeats <= --max-repeats, --target > 0, --peer-budget > 0, --sizes >= 16"
        )
    ext = {"ESRI Shapefile": ".shp", "GPKG": ".gpkg", "GeoJSON": ".geojson", "FlatGeobuf": ".fgb"}

    t_start = time.perf_counter()
    run_load = Meter().start()
    first = warm_up()
    compile_line = "first call of each numba kernel at 64^2 (compile / cache load): " + ", ".join(
        f"{k} {t:.2f} s" for k, t in first
    )
    print("\n".join(["sciviz_gbuf contour-line benchmark", *machine_facts(), compile_line]))
    gdal = None if args.no_gdal else Gdal(args.gdal_format, ext.get(args.gdal_format, ""))
    try:
        if gdal is not None and gdal.exe is not None:
            version = subprocess.run(
                [gdal.exe, "--version"], capture_output=True, text=True, check=False
            ).stdout.strip()
            version = version.splitlines()[0] if version else "?"
            print(
                f"{gdal.exe}: {version}; output driver {gdal.fmt}; start-up on a 4x4 grid "
                f"{1e3 * gdal.startup():.0f} ms"
            )
        elif gdal is not None:
            print("gdal_contour: not found on PATH (its rows say so)")
        print(
            f"sizes {sizes}; ours: 1 untimed call + N timed for ~{st.target:g} s (N >= "
            f"{st.min_reps}); peers: N <= {st.min_reps} runs within {st.peer_budget:g} s",
            flush=True,
        )
        rows: list[Row] = []
        for n in sizes:
            t0 = time.perf_counter()
            rows += bench_size(n, st, gdal)
            print(f"  {n}^2 cells took {time.perf_counter() - t0:.0f} s", flush=True)
            gc.collect()
    finally:
        if gdal is not None:
            gdal.close()

    ref = references(rows)
    print()
    print(format_table([row_values(r, ref) for r in rows]))
    print()
    print(NOTES)
    if args.csv:
        write_csv(args.csv, rows, ref)
        print(f"\nCSV written to {args.csv}")
    run_load.stop()
    print()
    print(load_summary(run_load, args.wait_idle > 0))
    print(f"\ntotal benchmark wall time: {time.perf_counter() - t_start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
