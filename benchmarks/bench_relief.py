"""Benchmark: ``texture_shade`` and ``local_relief`` of ``sciviz_gbuf.filters.relief``, and the
relief styles of ``topographic_map``, in MPix/s.

Run from the project root with the project's venv active::

    python benchmarks/bench_relief.py                  # 1024^2, 2048^2, 4096^2 (~1 min)
    python benchmarks/bench_relief.py --sizes 1024     # quick

Peers, same grid, same run:

* ``hillshade`` (a 3x3 stencil, the floor of any per-cell relief);
* texture shading by the reference implementation's formula (Fasih's ``texshade``: zero padding
  to a power of two, ``rfft2``, ``|f|^alpha``, ``irfft2``, numpy FFT, float64);
* the simple local relief model as RVT's older code computes it
  (``z - scipy.ndimage.uniform_filter(z, 2 r + 1)``; no nodata handling);
* ``topographic_map`` of a 1024^2 grid with each ``relief=`` style (bands, contours, relief).

The ``x peer`` column is our time over the peer's: below 1 is faster. The best of the repeats is
reported (at least ``--min-repeats``, more while under ``--target`` seconds).
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable

import numpy as np

if not os.environ.get("DISPLAY"):
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

from scipy import ndimage

from sciviz_gbuf.filters import hillshade, local_relief, texture_shade
from sciviz_gbuf.recipes.terrain import RELIEFS, topographic_map

CELL = 30.0


def fractal_terrain(n: int, seed: int = 0, beta: float = 2.2, relief: float = 1500.0):
    """n x n float32 heights with a 1/f^beta power spectrum, ``relief`` metres of range."""
    rng = np.random.default_rng(seed)
    fy = np.fft.fftfreq(n)[:, None]
    fx = np.fft.rfftfreq(n)[None, :]
    f = np.hypot(fx, fy)
    f[0, 0] = 1.0
    amp = f ** (-beta / 2.0)
    amp[0, 0] = 0.0
    z = np.fft.irfft2(amp * np.exp(1j * rng.uniform(0, 2 * np.pi, amp.shape)), s=(n, n))
    z = (z - z.min()) / (z.max() - z.min()) * relief
    return z.astype(np.float32)


def texshade_reference(x: np.ndarray, alpha: float) -> np.ndarray:
    n = [2 ** int(np.ceil(np.log2(v))) for v in x.shape]
    fy = np.fft.fftfreq(n[0])[:, None]
    fx = np.fft.rfftfreq(n[1])[None, :]
    return np.fft.irfft2(np.fft.rfft2(x, n) * np.hypot(fx, fy) ** alpha, n)[
        : x.shape[0], : x.shape[1]
    ]


def _rows(z: np.ndarray) -> list[tuple[str, Callable[[], object], int | None]]:
    """(name, call, index of its peer row or None) on the heights ``z``."""
    return [
        ("hillshade", lambda: hillshade(z, dx=CELL, dy=CELL), None),
        ("texshade formula (numpy FFT)", lambda: texshade_reference(z, 0.5), None),
        ("texture_shade alpha 0.5", lambda: texture_shade(z, dx=CELL, dy=CELL), 1),
        ("SLRM z - uniform_filter (scipy)",
         lambda: z - ndimage.uniform_filter(z, 41, mode="nearest"), None),
        ("local_relief r 20", lambda: local_relief(z, dx=CELL, dy=CELL), 3),
    ]  # fmt: skip


def best(call: Callable[[], object], min_repeats: int, target: float) -> float:
    times: list[float] = []
    start = time.perf_counter()
    while len(times) < min_repeats or time.perf_counter() - start < target:
        t0 = time.perf_counter()
        call()
        times.append(time.perf_counter() - t0)
        if len(times) >= 50:
            break
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1024, 2048, 4096])
    ap.add_argument("--min-repeats", type=int, default=3)
    ap.add_argument("--target", type=float, default=2.0)
    args = ap.parse_args()
    hillshade(np.zeros((8, 8), np.float32))  # numba compiled or loaded first
    print(f"{'operator':<34} {'size':>6} {'seconds':>9} {'MPix/s':>8} {'x peer':>8}")
    for n in args.sizes:
        mp = n * n / 1e6
        rows = _rows(fractal_terrain(n))
        secs = []
        for name, call, peer in rows:
            t = best(call, args.min_repeats, args.target)
            secs.append(t)
            ratio = f"{t / secs[peer]:.2f}" if peer is not None else "-"
            print(f"{name:<34} {n:>6} {t:>9.3f} {mp / t:>8.1f} {ratio:>8}")
    z = fractal_terrain(1024)
    from sciviz_gbuf.readers import read_dem

    dem = read_dem(z)
    base = None
    for style in RELIEFS:
        t = best(lambda s=style: topographic_map(dem, relief=s), args.min_repeats, args.target)
        base = base or t
        print(f"{'topographic_map relief=' + style:<34} {1024:>6} {t:>9.3f} "
              f"{1.048576 / t:>8.1f} {t / base:>8.2f}")  # fmt: skip


if __name__ == "__main__":
    main()
