"""Benchmark: the contour generalisation's steps, the numba kernels against the statements they
replaced (kept as the tested references), in MPix/s, same run.

Run from the project root with the project's venv active::

    python benchmarks/bench_generalize.py                  # 2048^2 and 4096^2 (~3 min)
    python benchmarks/bench_generalize.py --sizes 1024     # quick

On synthetic fractal terrain (float32, 0-2000 m, 20 m minor interval, a nodata lake), warm:

* the height-aware smoothing of one strip of ``STRIP_ROWS`` rows plus its halo
  (``smooth_strip``: the fits, then the blend, the tolerance band and the flat test in one
  pass) against ``smooth_strip_reference`` (the same fits, then numpy's expressions);
* the whole field (``smooth_field``: tiles on every core; the tiles of full windows by the
  fused route, ``fused_rows``) against the same tiles all by the separate kernels (the route
  before it: the same bits);
* the band heights (``band_heights``: run-length labelling of the band islands and a ring
  search for the nearest cell, strips on every core) against ``band_heights_reference`` (a
  ``scipy.ndimage.label`` of the whole grid per band and a Euclidean distance transform);
* the ring opening (``drop_small_rings``, strips on every core) of the minor/major ink.

Every pair is checked to agree (bit for bit for the smoothing; the same islands for the band
heights) before it is timed.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from sciviz_gbuf.filters import _contour_generalize as G
from sciviz_gbuf.filters import contour_lines


def terrain(n: int, seed: int = 1, hurst: float = 0.8) -> np.ndarray:
    """Fractal heights (power-law spectrum) scaled to 0 - 2000 m, with a round nodata lake."""
    rng = np.random.default_rng(seed)
    k = np.fft.fftfreq(n).astype(np.float32)[:, None]
    ell = np.fft.rfftfreq(n).astype(np.float32)[None, :]
    r = np.hypot(k, ell)
    r[0, 0] = 1.0
    spec = rng.standard_normal((n, n // 2 + 1)) + 1j * rng.standard_normal((n, n // 2 + 1))
    z = np.fft.irfft2(spec / r ** (1.0 + hurst), s=(n, n)).astype(np.float32)
    z -= z.min()
    z *= 2000.0 / z.max()
    yy, xx = np.ogrid[:n, :n]
    z[(yy - n * 0.3) ** 2 + (xx - n * 0.6) ** 2 < (n * 0.08) ** 2] = np.nan
    return z


def best(func, repeats: int) -> float:
    func()  # warm (numba's cache, first touch)
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        func()
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="2048,4096")
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    interval = 20.0
    ring = 6.0  # the default maps' min_ring (3 widths of the 2 px majors)
    print(f"{'size':>6} {'step':<52} {'s':>8} {'MPix/s':>8} {'vs ours':>8}")
    print("-" * 80)
    for n in (int(v) for v in args.sizes.split(",") if v):
        z = terrain(n)
        valid = np.isfinite(z)
        rows = G.STRIP_ROWS + 2 * G.SMOOTH_RADIUS
        zs, vs = z[:rows], valid[:rows]
        pairs = zip(
            G.smooth_strip(zs, vs, interval),
            G.smooth_strip_reference(zs, vs, interval),
            strict=True,
        )
        for a, b in pairs:
            assert np.array_equal(a, b, equal_nan=True)
        strip_mpix = zs.size / 1e6
        t_fast = best(lambda zs=zs, vs=vs: G.smooth_strip(zs, vs, interval), args.repeats)
        t_ref = best(lambda zs=zs, vs=vs: G.smooth_strip_reference(zs, vs, interval), args.repeats)
        name = f"smooth_strip ({rows} rows)"
        print(f"{n:>6} {name:<52} {t_fast:8.3f} {strip_mpix / t_fast:8.1f} {1.0:8.1f}")
        name = "smooth_strip_reference (numpy blend)"
        print(f"{n:>6} {name:<52} {t_ref:8.3f} {strip_mpix / t_ref:8.1f} {t_ref / t_fast:8.1f}")
        mpix = z.size / 1e6
        t = best(lambda z=z, valid=valid: G.smooth_field(z, valid, interval), args.repeats)
        print(f"{n:>6} {'smooth_field (whole grid)':<52} {t:8.3f} {mpix / t:8.1f} {1.0:8.1f}")
        G.FUSED_ROUTE = False  # every tile by the separate kernels: the same bits, slower
        try:
            t_sep = best(lambda z=z, valid=valid: G.smooth_field(z, valid, interval), args.repeats)
        finally:
            G.FUSED_ROUTE = True
        name = "smooth_field, separate kernels (no fused route)"
        print(f"{n:>6} {name:<52} {t_sep:8.3f} {mpix / t_sep:8.1f} {t_sep / t:8.1f}")
        fast = G.band_heights(z, valid, ring, step=100.0)
        t_fast = best(
            lambda z=z, valid=valid, ring=ring: G.band_heights(z, valid, ring, step=100.0), 1
        )
        print(f"{n:>6} {'band_heights':<52} {t_fast:8.3f} {mpix / t_fast:8.1f} {1.0:8.1f}")
        if n <= 4096:

            def index(h):
                return np.floor(h / np.float32(100.0)).astype(np.int64)

            ref = G.band_heights_reference(z, valid, index, ring)
            s = np.where(valid, z, np.nan)
            same = np.array_equal(valid & (fast != s), valid & (ref != s))
            t_ref = best(
                lambda z=z, valid=valid: G.band_heights_reference(z, valid, index, ring), 1
            )
            name = f"band_heights_reference (scipy; same cells: {same})"
            print(f"{n:>6} {name:<52} {t_ref:8.3f} {mpix / t_ref:8.1f} {t_ref / t_fast:8.1f}")
        ink = contour_lines(z, interval=interval, major_interval=100.0, width=1.0, major_width=2.0)
        t = best(
            lambda ink=ink, valid=valid, ring=ring: G.drop_small_rings(ink, ring, valid, 2.0), 1
        )
        print(f"{n:>6} {'drop_small_rings':<52} {t:8.3f} {mpix / t:8.1f}")
        print()


if __name__ == "__main__":
    main()
