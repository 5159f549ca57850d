"""Benchmark: ``hillshade`` against the memory roofline, matplotlib and ``gdaldem``, in MPix/s.

Run from the project root with the project's venv active::

    python benchmarks/bench_hillshade.py                  # 4096^2 and 8192^2 (~1 min)
    python benchmarks/bench_hillshade.py --sizes 2048     # quick

On synthetic fractal terrain (float32, 10 m cells, 0-2000 m, power ~ 1/f^2.2), in one run:

* ours, every variant, into a preallocated ``out=`` (the kernel) and into a new array (what a
  plain call costs: on this VM the first touch of fresh memory costs ~1-2 ms/MB, more than the
  shading);
* the per-cell float64 statement of GDAL's formulas (``hillshade_reference_kernel``, what
  ``hillshade`` ran before its vectorised loop; the fast kernel is tested against it);
* the roofline: ``np.add(z, z, out=o)`` (read 8 bytes and write 4 per cell, one thread;
  hillshade reads 4 and writes 4);
* matplotlib's ``LightSource.hillshade`` (numpy) and ``gdaldem hillshade -compute_edges``
  (a process reading and writing raw ENVI files on the same disk; its I/O is included, so the
  ratio flatters us by that much: the file read alone is listed);
* the map's other per-pixel passes: its fused composite (band colours x relief, then contour
  ink, into a preallocated uint8 RGBA), against the per-pixel loop it ran before (kept as the
  reference), and ``color_bands`` into a new float32 RGBA (16 bytes a cell);
* the grey levels: our Byte output, ``round(1 + 254 shade)``, against gdaldem's on the same
  grid (max and share of cells that differ).

Best of the repeats (at least ``--min-repeats``, more while under ``--target`` seconds); every
call warm. ``cores`` = process CPU time / wall time of the best call.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

if not os.environ.get("DISPLAY"):
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

from sciviz_gbuf.filters import _band_kernels as BK
from sciviz_gbuf.filters import _hillshade_kernels as K
from sciviz_gbuf.filters import color_bands, hillshade
from sciviz_gbuf.filters.bands import _check_tables, band_tables

CELL = 10.0
VARIANTS = ("regular", "combined", "multidirectional", "igor")


def fractal_terrain(n: int, seed: int = 0, beta: float = 2.2) -> np.ndarray:
    """n x n float32 heights, 1/f^beta spectrum, scaled to 0-2000 m."""
    rng = np.random.default_rng(seed)
    f = np.hypot(np.fft.fftfreq(n)[:, None], np.fft.rfftfreq(n)[None, :]).astype(np.float32)
    f[0, 0] = 1.0
    amp = f ** np.float32(-beta / 2.0)
    amp[0, 0] = 0.0
    phase = rng.uniform(0, 2 * np.pi, size=amp.shape).astype(np.float32)
    z = np.fft.irfft2(amp * np.exp(1j * phase), s=(n, n)).astype(np.float32)
    z -= z.min()
    z *= np.float32(2000.0 / z.max())
    return z


def best(fn, target: float, min_reps: int) -> tuple[float, float]:
    """(best wall time, cores during it) over repeated calls."""
    times: list[tuple[float, float]] = []
    t_end = time.perf_counter() + target
    while len(times) < min_reps or (time.perf_counter() < t_end and len(times) < 50):
        c0, t0 = time.process_time(), time.perf_counter()
        fn()
        t1, c1 = time.perf_counter(), time.process_time()
        times.append((t1 - t0, (c1 - c0) / max(t1 - t0, 1e-9)))
    return min(times)


def gdaldem(z: np.ndarray, tmp: Path, variant: str) -> tuple[float, float, np.ndarray]:
    """(gdaldem's wall time, the time to read its input file once, its Byte output)."""
    src, out = tmp / "z.raw", tmp / "o.raw"
    z.tofile(src)
    n_rows, n_cols = z.shape
    (tmp / "z.hdr").write_text(
        f"ENVI\nsamples = {n_cols}\nlines = {n_rows}\nbands = 1\nheader offset = 0\n"
        f"file type = ENVI Standard\ndata type = 4\ninterleave = bsq\nbyte order = 0\n"
        f"map info = {{Arbitrary, 1, 1, 0, 0, {CELL}, {CELL}, 0}}\n"
    )
    cmd = ["gdaldem", "hillshade", "-q", "-compute_edges", "-of", "ENVI"]
    cmd += [] if variant == "regular" else [f"-{variant}"]
    t0 = time.perf_counter()
    subprocess.run([*cmd, str(src), str(out)], check=True, capture_output=True)
    t = time.perf_counter() - t0
    t0 = time.perf_counter()
    np.fromfile(src, dtype=np.float32)
    t_read = time.perf_counter() - t0
    return t, t_read, np.fromfile(out, dtype=np.uint8).reshape(z.shape)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="4096,8192")
    ap.add_argument("--target", type=float, default=1.5)
    ap.add_argument("--min-repeats", type=int, default=3)
    args = ap.parse_args()
    hillshade(np.zeros((8, 8), np.float32))  # compiled or loaded first
    for variant in VARIANTS:
        hillshade(np.zeros((8, 8), np.float32), variant=variant)
        K.hillshade_reference_kernel(np.zeros((8, 8), np.float32), 1, -1, 1, 315, 45, 0, 0)
    from matplotlib.colors import LightSource

    have_gdal = shutil.which("gdaldem") is not None
    for n in (int(s) for s in args.sizes.split(",")):
        z = fractal_terrain(n)
        out = np.empty_like(z)
        mp = n * n / 1e6
        rows: list[tuple[str, float, float]] = []

        def row(name, fn, reps=args.min_repeats, rows=rows):
            t, cores = best(fn, args.target, reps)
            rows.append((name, t, cores))
            return t

        roof = row("roofline: np.add(z, z, out=o), 1 thread",
                   lambda z=z, out=out: np.add(z, z, out=out))  # fmt: skip
        ref = None
        for variant in VARIANTS:
            row(f"ours {variant}, out=",
                lambda v=variant, z=z, out=out: hillshade(z, dx=CELL, dy=CELL, variant=v,
                                                          out=out))  # fmt: skip
            if variant == "regular":
                row("ours regular, new array", lambda z=z: hillshade(z, dx=CELL, dy=CELL))
                ref = row("per-cell float64 statement (before)",
                          lambda z=z: K.hillshade_reference_kernel(
                              z, 1 / CELL, -1 / CELL, 1.0, 315.0, 45.0, 0, 0), reps=1)  # fmt: skip
        # the map's other per-pixel passes: its composite (bands x relief, then contour ink,
        # uint8 RGBA) and the float colour bands
        tables = _check_tables(band_tables(
            np.array([z.min(), z.max()]), interval=100.0, levels=None, base=0.0, cmap=None,
            vmin=None, vmax=None, sea_level=None, sea_cmap=None))  # fmt: skip
        relief = hillshade(z, dx=CELL, dy=CELL)
        ink = np.where(relief > 0.95, np.float32(1.0), np.float32(0.0))
        none = np.zeros((0, 0), np.float32)
        rgba = np.empty((n, n, 4), np.uint8)
        layers = (z, True, *tables, True, relief, np.float32(0.7), none, none, ink,
                  np.zeros(3, np.float32))  # fmt: skip
        row("map composite, out= (vectorised loops)",
            lambda a=layers, o=rgba: BK.map_image_fast(*a, o))  # fmt: skip
        row("map composite, out=, per-pixel loop (before)",
            lambda a=layers, o=rgba: BK.map_image(*a, o), reps=1)  # fmt: skip
        bands_out = np.empty((n, n, 4), np.float32)
        row("color_bands, out= (float32 RGBA, 16 bytes a cell)",
            lambda z=z, o=bands_out: color_bands(z, interval=100.0, out=o))  # fmt: skip
        row("color_bands, new float32 RGBA", lambda z=z: color_bands(z, interval=100.0), reps=1)
        del bands_out
        del rgba, relief, ink
        ls = LightSource(azdeg=315, altdeg=45)
        row("matplotlib LightSource.hillshade",
            lambda z=z, ls=ls: ls.hillshade(z, dx=CELL, dy=CELL), reps=1)  # fmt: skip
        diffs = []
        if have_gdal:
            with tempfile.TemporaryDirectory() as tmp:
                for variant in ("regular", "multidirectional"):
                    t, t_read, gd = gdaldem(z, Path(tmp), variant)
                    name = f"gdaldem hillshade -{variant} (process, raw I/O)"
                    rows.append((name, t, float("nan")))
                    ours = hillshade(z, dx=CELL, dy=CELL, variant=variant)
                    b = np.rint(ours * 254.0 + 1.0).astype(np.int16)
                    d = np.abs(b - gd.astype(np.int16))
                    diffs.append((variant, int(d.max()), float((d > 0).mean())))
                rows.append(("  of which: reading its input once", t_read, float("nan")))
        ours_t = min(t for name, t, _ in rows if name == "ours regular, out=")
        print(f"\n## hillshade, {n}^2 float32 ({mp:.0f} MPix), 2 cores\n")
        print("| run | ms | MPix/s | cores | ours regular out= is x faster |")
        print("|---|---|---|---|---|")
        for name, t, cores in rows:
            c = "" if cores != cores else f"{cores:.1f}"
            print(f"| {name} | {t * 1e3:.1f} | {mp / t:.0f} | {c} | {t / ours_t:.2f} |")
        print(f"\nroofline / ours: {roof / ours_t:.2f}; "
              f"per-cell statement / ours: {ref / ours_t:.1f}")  # fmt: skip
        if diffs:
            print("\n| variant | max grey-level difference to gdaldem | cells that differ |")
            print("|---|---|---|")
            for v, m, share in diffs:
                print(f"| {v} | {m} | {share:.2e} |")


if __name__ == "__main__":
    main()
