"""Benchmark: ``cast_shadows`` and ``sky_view`` of ``sciviz_gbuf.filters.terrain_light``, in MPix/s.

Run from the project root with the project's venv active::

    python benchmarks/bench_terrain_light.py                 # 1024^2, 2048^2, 4096^2 (~1.5 min)
    python benchmarks/bench_terrain_light.py --sizes 1024    # quick

What is measured, on synthetic fractal terrain (spectral synthesis, power ~ 1/f^2.2, 30 m cells,
~1500 m of relief, float32):

* ``cast_shadows`` at azimuth 315 and altitude 30: hard shadows by the sweep (also at azimuth
  300: its lines cross the columns, which it copies in strips) and by the per-cell march it
  keeps as ``method="march"``, with the share of cells where the two differ; and soft shadows
  (``sun_radius=0.5``, always the march);
  ``sky_view`` and ``openness`` with 16 directions and the default radius (50 cells, 1500 m);
  up to 2048^2 also the per-cell ray march ``sky_view`` ran before its row march (the same
  samples, kept as the reference the tests hold the row march to).
* The fused row march (four steps a pass, what ``sky_view`` and ``openness`` run) against
  the one-step row march it replaced (``K.sky_view_march_kernel``, the same values bit for
  bit), interleaved in this process: ``--rounds`` rounds of new, old, each the whole kernel
  on the same rays; the median and range of each one's MPix/s and of the per-round ratio
  (sizes in ``--compare-sizes``, default the largest of ``--sizes``).
* Peer, same grid, same run: ``hillshade`` (a 3x3 stencil: the floor of any per-cell terrain
  shading). The ``x hillshade`` column is the time relative to it.
* Numpy references on the smallest size: shadows for a west sun (azimuth 270) as the row-wise
  "any higher cell s columns west above the ray" loop over shifts s, vectorised over the grid
  (checked equal to ``cast_shadows``); the sky-view factor by the same ray march as the kernel,
  vectorised over the grid with numpy fancy indexing (on a 512^2 crop: it is slow).

Every call is warm (numba compiled or loaded from its cache on a small grid first); the best of
the repeats is reported (at least ``--min-repeats``, more while under ``--target`` seconds).
``cores`` is the process's CPU time over the wall time of that call: about 2 on two idle cores
for the parallel kernels; clearly less means another job shared the machine.
"""

from __future__ import annotations

import argparse
import math
import os
import time
from collections.abc import Callable
from functools import partial

import numpy as np

# Headless: VTK's default window class would try X first; must precede the sciviz_gbuf import.
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numba

from sciviz_gbuf.filters import _terrain_light_kernels as K
from sciviz_gbuf.filters import terrain_light as T
from sciviz_gbuf.filters.hillshade import hillshade
from sciviz_gbuf.filters.terrain_light import cast_shadows, openness, sky_view

CELL = 30.0  # metres
AZIMUTH, ALTITUDE = 315.0, 30.0


def fractal_terrain(n: int, seed: int = 0, beta: float = 2.2, relief: float = 1500.0):
    """n x n float32 heights with a 1/f^beta power spectrum, scaled to ``relief`` metres."""
    rng = np.random.default_rng(seed)
    fy = np.fft.fftfreq(n)[:, None]
    fx = np.fft.rfftfreq(n)[None, :]
    f = np.hypot(fx, fy)
    f[0, 0] = 1.0
    amp = f ** (-beta / 2.0)
    amp[0, 0] = 0.0
    phase = rng.uniform(0, 2 * np.pi, size=amp.shape)
    z = np.fft.irfft2(amp * np.exp(1j * phase), s=(n, n))
    z = (z - z.min()) / (z.max() - z.min()) * relief
    return z.astype(np.float32)


def numpy_west_shadows(z: np.ndarray, altitude: float, dx: float) -> np.ndarray:
    """1 = lit for a sun in the west: no cell s columns west rises above the ray at s * dx."""
    tan = math.tan(math.radians(altitude))
    z64 = z.astype(np.float64)
    blocked = np.zeros(z.shape, bool)
    relief = float(np.nanmax(z64) - np.nanmin(z64))
    s = 1
    while s < z.shape[1] and s * dx * tan < relief:  # beyond that no cell can block
        blocked[:, s:] |= z64[:, :-s] - z64[:, s:] > s * dx * tan
        s += 1
    return (~blocked).astype(np.float32)


def numpy_sky_view(z: np.ndarray, directions: int, radius: float, dx: float) -> np.ndarray:
    """The kernel's ray march (one pixel along the dominant axis, linear interpolation across),
    vectorised over all cells with numpy."""
    z64 = z.astype(np.float64)
    h, w = z.shape
    ii, jj = np.mgrid[0:h, 0:w]
    acc = np.zeros(z.shape)
    for d in range(directions):
        az = math.radians(360.0 * d / directions)
        e, nth = math.sin(az), math.cos(az)
        e, nth = (0.0 if abs(e) < 1e-12 else e), (0.0 if abs(nth) < 1e-12 else nth)
        m = max(abs(e), abs(nth))
        dr, dc, step = -nth / m, e / m, dx / m
        best = np.zeros(z.shape)
        for k in range(1, int(radius / step + 1e-9) + 1):
            r, c = ii + k * dr, jj + k * dc
            r0, c0 = np.floor(r).astype(np.int64), np.floor(c).astype(np.int64)
            fr, fc = r - r0, c - c0
            ok = (r0 >= 0) & (c0 >= 0) & (r0 + (fr > 0) < h) & (c0 + (fc > 0) < w)
            r0, c0 = np.clip(r0, 0, h - 1), np.clip(c0, 0, w - 1)
            a = z64[r0, c0]
            b = z64[np.clip(r0 + (fr > 0), 0, h - 1), np.clip(c0 + (fc > 0), 0, w - 1)]
            v = a + (fr + fc) * (b - a)  # one of fr, fc is 0
            best = np.where(ok, np.maximum(best, (v - z64) / (k * step)), best)
        acc += best / np.sqrt(1.0 + best * best)
    return (1.0 - acc / directions).astype(np.float32)


def best_time(fn: Callable[[], object], min_reps: int, target: float) -> tuple[float, float]:
    """(best wall seconds, CPU seconds / wall seconds of that call: ~2 = both cores busy)."""
    times: list[tuple[float, float]] = []
    while len(times) < min_reps or (sum(t for t, _ in times) < target and len(times) < 50):
        c0, t0 = time.process_time(), time.perf_counter()
        fn()
        wall = time.perf_counter() - t0
        times.append((wall, (time.process_time() - c0) / wall))
    return min(times)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1024, 2048, 4096])
    parser.add_argument("--min-repeats", type=int, default=1)
    parser.add_argument("--target", type=float, default=1.5, help="seconds per cell at least")
    parser.add_argument("--compare-sizes", type=int, nargs="*", default=None)
    parser.add_argument("--rounds", type=int, default=3, help="rounds of the interleaved runs")
    parser.add_argument("--only-compare", action="store_true", help="skip the main table")
    args = parser.parse_args(argv)
    if args.compare_sizes is None:
        args.compare_sizes = [max(args.sizes)]

    print(f"numba {numba.__version__}, {numba.get_num_threads()} threads, numpy {np.__version__}")
    print(f"terrain: fractal, {CELL:g} m cells; sun azimuth {AZIMUTH:g}, altitude {ALTITUDE:g}")
    warm = fractal_terrain(64)
    hillshade(warm, dx=CELL, dy=CELL)
    cast_shadows(warm, dx=CELL, dy=CELL)
    cast_shadows(warm, dx=CELL, dy=CELL, sun_radius=0.5)
    sky_view(warm, dx=CELL, dy=CELL)

    if args.only_compare:
        fused_vs_march(args.compare_sizes, args.rounds)
        return 0
    header = (
        f"{'function':<34} {'size':>6} {'best s':>8} {'MPix/s':>8} {'x hillshade':>12} {'cores':>6}"
    )
    print(header)
    print("-" * len(header))
    kw = {"dx": CELL, "dy": CELL}
    for n in args.sizes:
        z = fractal_terrain(n)
        mpix = n * n / 1e6
        sun = {"azimuth": AZIMUTH, "altitude": ALTITUDE, "dx": CELL, "dy": CELL}
        cells: list[tuple[str, Callable[[], object]]] = [
            ("hillshade (peer)", partial(hillshade, z, **sun)),
            ("cast_shadows (sweep)", partial(cast_shadows, z, **sun)),
            (
                "cast_shadows azimuth 300 (sweep)",
                partial(cast_shadows, z, **{**sun, "azimuth": 300.0}),
            ),
            ("cast_shadows method=march", partial(cast_shadows, z, method="march", **sun)),
            ("cast_shadows sun_radius=0.5", partial(cast_shadows, z, sun_radius=0.5, **sun)),
            ("sky_view 16 dirs r=50 px", partial(sky_view, z, dx=CELL, dy=CELL)),
            ("sky_view 16 dirs r=10 px (RVT's)", partial(sky_view, z, radius=10 * CELL, **kw)),
            ("openness 16 dirs r=50 px", partial(openness, z, dx=CELL, dy=CELL)),
        ]
        zz = T._prepare(z, CELL, CELL, 1.0, None)
        march_rays = T._sky_rays(zz, CELL, CELL, 16, T.default_sky_radius(CELL, CELL), local=False)
        cells.append(("sky_view one-step march (before)",
                      partial(K.sky_view_march_kernel, zz, *march_rays)))  # fmt: skip
        cells.append(("openness one-step march (before)",
                      partial(K.openness_march_kernel, zz, *march_rays)))  # fmt: skip
        if n <= 2048:  # the per-cell march sky_view ran before the row march: slow
            zz = T._prepare(z, CELL, CELL, 1.0, None)
            rays = T._sky_rays(zz, CELL, CELL, 16, T.default_sky_radius(CELL, CELL))
            cells.append(("sky_view per-cell (before)",
                          partial(K.sky_view_reference_kernel, zz, *rays)))  # fmt: skip
        base = None
        for name, fn in cells:
            t, cores = best_time(fn, args.min_repeats, args.target)
            base = base or t
            print(f"{name:<34} {n:>6} {t:>8.3f} {mpix / t:>8.1f} {t / base:>12.1f} {cores:>6.2f}")
        sweep, march = cast_shadows(z, **sun), cast_shadows(z, method="march", **sun)
        print(f"{'  (lit share)':<34} {n:>6} {float(np.mean(sweep)):>8.3f}")
        print(f"{'  (sweep != march share)':<34} {n:>6} {float(np.mean(sweep != march)):>8.4f}")

    n = min(args.sizes)
    z = fractal_terrain(n)
    kw = {"dx": CELL, "dy": CELL}
    print()
    print(f"numpy references on {n}^2 (sky view on a 512^2 crop):")
    want = numpy_west_shadows(z, ALTITUDE, CELL)
    t_np, _ = best_time(partial(numpy_west_shadows, z, ALTITUDE, CELL), 1, 0.0)
    west = partial(cast_shadows, z, azimuth=270.0, altitude=ALTITUDE, **kw)
    t_nb, _ = best_time(west, 3, 1.0)
    same = np.array_equal(want, west())
    print(
        f"  shadows azimuth 270: numpy {t_np:.3f} s, cast_shadows {t_nb:.3f} s, "
        f"speed-up {t_np / t_nb:.1f}x, identical: {same}"
    )
    crop = z[:512, :512]
    t0 = time.perf_counter()
    want = numpy_sky_view(crop, 16, 50 * CELL, CELL)
    t_np = time.perf_counter() - t0
    t_nb, _ = best_time(partial(sky_view, crop, **kw), 3, 1.0)
    diff = float(np.abs(want - sky_view(crop, **kw)).max())
    print(
        f"  sky_view 16 dirs:    numpy {t_np:.3f} s, sky_view {t_nb:.3f} s, "
        f"speed-up {t_np / t_nb:.1f}x, max |diff| {diff:.1e}"
    )
    rvt_peer(z)
    if args.compare_sizes:
        print()
        fused_vs_march(args.compare_sizes, args.rounds)
    return 0


def fused_vs_march(sizes: list[int], rounds: int) -> None:
    """The fused row march (``sky_view_kernel``, ``openness_kernel``: what the public
    functions run) against the one-step march (``*_march_kernel``), interleaved: each round
    times new then old on the same rays; median [range] of MPix/s and of new/old per round;
    ``cores`` the least CPU time over wall time of the calls (about 2 on two idle cores)."""
    print(f"fused row march vs one-step march, 16 dirs, r=50 px, {rounds} interleaved rounds:")
    head = (
        f"{'kernel':<12} {'size':>6} {'new MPix/s':>22} {'old MPix/s':>22} {'new/old':>20} "
        f"{'cores':>6}"
    )
    print(head)
    print("-" * len(head))
    for n in sizes:
        z = T._prepare(fractal_terrain(n), CELL, CELL, 1.0, None)
        rays = T._sky_rays(z, CELL, CELL, 16, T.default_sky_radius(CELL, CELL), local=False)
        for name, new, old in (
            ("sky_view", K.sky_view_kernel, K.sky_view_march_kernel),
            ("openness", K.openness_kernel, K.openness_march_kernel),
        ):
            rates: list[tuple[float, float]] = []
            cores: list[float] = []
            for _ in range(rounds):
                pair = []
                for fn in (new, old):
                    c0, t0 = time.process_time(), time.perf_counter()
                    fn(z, *rays)
                    wall = time.perf_counter() - t0
                    pair.append(n * n / wall / 1e6)
                    cores.append((time.process_time() - c0) / wall)
                rates.append((pair[0], pair[1]))
            a = np.array(rates)
            ratio = a[:, 0] / a[:, 1]

            def fmt(v: np.ndarray) -> str:
                return f"{np.median(v):.1f} [{v.min():.1f}-{v.max():.1f}]"

            print(
                f"{name:<12} {n:>6} {fmt(a[:, 0]):>22} {fmt(a[:, 1]):>22} {fmt(ratio):>20} "
                f"{min(cores):>6.2f}"
            )


def rvt_peer(z: np.ndarray) -> None:
    """RVT's ``sky_view_factor`` (numpy, its defaults: 16 directions, 10 px) against
    ``sky_view`` at the same radius, same grid, same run; skipped without RVT (``pip install
    --no-deps rvt-py``: its visualisations need only numpy and scipy)."""
    try:
        import rvt.vis
    except ImportError:
        print("  RVT sky_view_factor: not installed (pip install --no-deps rvt-py)")
        return
    n = z.shape[0]
    t0 = time.perf_counter()
    theirs = rvt.vis.sky_view_factor(z, CELL, svf_n_dir=16, svf_r_max=10)["svf"]
    t_rvt = time.perf_counter() - t0
    ours = partial(sky_view, z, dx=CELL, dy=CELL, radius=10 * CELL)
    t_nb, _ = best_time(ours, 3, 1.0)
    both = np.isfinite(theirs) & np.isfinite(ours())
    diff = np.abs(theirs - ours())[both]
    print(
        f"  sky view 16 dirs, 10 px on {n}^2: RVT {t_rvt:.2f} s ({n * n / t_rvt / 1e6:.1f} "
        f"MPix/s), sky_view {t_nb:.3f} s ({n * n / t_nb / 1e6:.1f} MPix/s), "
        f"speed-up {t_rvt / t_nb:.0f}x; |RVT - ours| median {np.median(diff):.3f}, "
        f"p99 {np.percentile(diff, 99):.3f} (RVT rounds its samples to cells, mirrors the edges)"
    )


if __name__ == "__main__":
    raise SystemExit(main())
