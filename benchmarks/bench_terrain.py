"""Whole-process benchmark of ``sciviz-gbuf topo`` against the three GDAL commands it replaces.

On a synthetic GeoTIFF DEM (fractal terrain, float32, 10 m UTM cells, a nodata lake), in the
same run:

- ours: ``sciviz-gbuf topo DEM -o map.png --contours 20,100`` - relief, colour bands and
  major/minor contour lines composited into one RGBA PNG; once more with ``--geotiff`` (the
  PNG and a COG from the same blocks) and as ``-o map.tif`` (a COG alone); the default map
  generalises its contour lines (a cartographic step GDAL has not), so each is also timed
  with ``--exact-contours``, the lines ``gdal_contour`` traces;
- ours at ``--scale S`` (default 4): the map at S output pixels per DEM cell (heights resampled
  by clamped cubic convolution first), for DEMs whose map side stays within ``--max-side``;
  MPix/s counts output pixels;
- GDAL: ``gdaldem hillshade`` + ``gdaldem color-relief`` + ``gdal_contour -i 20`` (three
  separate outputs, not yet one picture: the comparison flatters GDAL).

Each command is a fresh process, timed from start to exit (imports, numba cache loading, reading
and writing included); peak resident memory from ``getrusage``. Every command runs ``--repeat``
times and the best time is reported. The package's bytecode is compiled first, as ``pip
install`` does (an editable install with ``PYTHONDONTWRITEBYTECODE=1`` would otherwise compile
every module in every run).

Usage: ``python benchmarks/bench_terrain.py [--sizes 2048,4096,8192] [--hurst 0.8,0.6]
[--repeat 1] [--scales 4] [--max-side 8192]``
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

# Colour-relief table of gdaldem (heights in metres of the synthetic terrain: 0 - 2000).
RAMP = """\
0 87 158 97
400 148 194 120
800 217 224 148
1200 245 222 158
1600 184 143 117
2000 247 247 247
nv 0 0 0 0
"""


def make_dem(path: Path, n: int, seed: int = 1, hurst: float = 0.8) -> None:
    """Fractal terrain (power-law spectrum, amplitude ~ k^-(1 + hurst)) scaled to 0 - 2000 m,
    with a round nodata lake. Real topography has Hurst exponents of about 0.5 - 0.9 (fractal
    dimension 2.5 - 2.1): rougher terrain has more and longer contour lines."""
    import rasterio
    from rasterio.transform import from_origin

    rng = np.random.default_rng(seed)
    k = np.fft.fftfreq(n).astype(np.float32)[:, None]
    ell = np.fft.rfftfreq(n).astype(np.float32)[None, :]
    r = np.hypot(k, ell)
    r[0, 0] = 1.0
    spec = rng.standard_normal((n, n // 2 + 1), dtype=np.float32) + 1j * rng.standard_normal(
        (n, n // 2 + 1), dtype=np.float32
    )
    spec /= r ** (1.0 + hurst)
    z = np.fft.irfft2(spec, s=(n, n)).astype(np.float32)
    del spec, r
    z -= z.min()
    z *= 2000.0 / z.max()
    yy, xx = np.ogrid[:n, :n]
    z[(yy - n * 0.3) ** 2 + (xx - n * 0.6) ** 2 < (n * 0.08) ** 2] = -9999.0
    with rasterio.open(
        path,
        "w",
        driver="GTiff",
        width=n,
        height=n,
        count=1,
        dtype="float32",
        crs="EPSG:32613",
        transform=from_origin(400000.0, 4500000.0, 10.0, 10.0),
        nodata=-9999.0,
        tiled=True,
    ) as f:
        f.write(z, 1)


def run(cmd: list[str], repeat: int) -> tuple[float, float]:
    """Best wall time over ``repeat`` runs and the peak RSS (MB) of the command's process.

    The RSS comes from GNU ``time`` when present: the rusage of a child forked from this
    (large) Python process would count the parent's pages it held before ``exec``.
    """
    gnu_time = shutil.which("time") or ("/usr/bin/time" if Path("/usr/bin/time").exists() else "")
    best, rss = float("inf"), float("nan")
    for _ in range(repeat):
        full = [gnu_time, "-f", "RSS_KB %M", *cmd] if gnu_time else cmd
        t0 = time.perf_counter()
        proc = subprocess.run(full, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        dt = time.perf_counter() - t0
        if proc.returncode != 0:
            raise SystemExit(f"failed: {' '.join(cmd)}\n{proc.stderr}")
        best = min(best, dt)
        for line in proc.stderr.splitlines():
            if line.startswith("RSS_KB "):
                kb = float(line.split()[1])
                rss = kb / 1024.0 if rss != rss else max(rss, kb / 1024.0)
    return best, rss


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", default="2048,4096,8192", help="DEM sizes (pixels a side)")
    parser.add_argument("--repeat", type=int, default=1, help="runs per command (best kept)")
    parser.add_argument(
        "--hurst",
        default="0.8,0.6",
        help="Hurst exponents of the synthetic terrains (0.8 smooth hills, 0.6 rugged)",
    )
    parser.add_argument("--scales", default="4", help="map scales to time (pixels per cell)")
    parser.add_argument(
        "--max-side", type=int, default=8192, help="largest map side of a --scales row (memory)"
    )
    args = parser.parse_args()
    tools = ("gdaldem", "gdal_contour")
    missing = [t for t in tools if shutil.which(t) is None]
    if missing:
        raise SystemExit(f"needs {', '.join(missing)} (Debian: apt install gdal-bin)")
    ours = [str(Path(sys.executable).with_name("sciviz-gbuf"))]
    if not Path(ours[0]).exists():
        ours = [sys.executable, "-m", "sciviz_gbuf"]
    sizes = [int(s) for s in args.sizes.split(",")]
    print(f"# {os.cpu_count()} CPUs, {sys.platform}, GDAL {gdal_version()}")
    # pip compiles a package's bytecode when it installs it; an editable install under
    # PYTHONDONTWRITEBYTECODE=1 (as on the CI machine) would compile ~100 modules in every run
    import sciviz_gbuf

    package = str(Path(sciviz_gbuf.__file__).parent)
    subprocess.run([sys.executable, "-m", "compileall", "-q", package], check=True,
                   stdout=subprocess.DEVNULL)  # fmt: skip
    # Warm the numba cache once so that no row pays for compiling.
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        make_dem(t / "warm.tif", 256)
        run([*ours, "topo", str(t / "warm.tif"), "-o", str(t / "w.png"), "--no-progress"], 1)
    header = f"{'size':>6} {'step':<44} {'s':>7} {'MPix/s':>7} {'MB RSS':>7} {'vs GDAL':>8}"
    print(header)
    print("-" * len(header))
    cases = [(n, float(hu)) for hu in args.hurst.split(",") for n in sizes]
    for n, hurst in cases:
        print(f"# {n}x{n}, Hurst exponent {hurst:g}")
        with tempfile.TemporaryDirectory() as tmp:
            t = Path(tmp)
            dem = t / "dem.tif"
            make_dem(dem, n, hurst=hurst)
            (t / "ramp.txt").write_text(RAMP)
            gdal = [
                ("gdaldem hillshade", ["gdaldem", "hillshade", "-q", str(dem), str(t / "hs.tif")]),
                (
                    "gdaldem color-relief",
                    [
                        "gdaldem",
                        "color-relief",
                        "-q",
                        "-alpha",
                        str(dem),
                        str(t / "ramp.txt"),
                        str(t / "cr.tif"),
                    ],
                ),
                (
                    "gdal_contour -i 20",
                    ["gdal_contour", "-q", "-i", "20", "-a", "elev", str(dem), str(t / "c.gpkg")],
                ),
            ]
            png, cog = str(t / "map.png"), str(t / "map.tif")
            exact = "--exact-contours"  # gdal_contour's lines (no generalisation): like for like
            ours_cmds = [
                ("sciviz-gbuf topo --contours 20,100 (PNG)", png, [], 1.0),
                ("sciviz-gbuf topo ... --exact-contours (PNG)", png, [exact], 1.0),
                ("sciviz-gbuf topo ... --geotiff (PNG + COG)", png, ["--geotiff", cog], 1.0),
                ("sciviz-gbuf topo ... --exact ... --geotiff", png, [exact, "--geotiff", cog], 1.0),
                ("sciviz-gbuf topo ... -o map.tif (COG)", cog, [], 1.0),
                ("sciviz-gbuf topo ... --exact ... -o map.tif", cog, [exact], 1.0),
            ]
            for k in (float(v) for v in args.scales.split(",") if v):
                if n * k <= args.max_side:
                    ours_cmds.append((f"sciviz-gbuf topo ... --scale {k:g} (PNG)", png,
                                      ["--scale", f"{k:g}"], k))  # fmt: skip
            rows = []
            gdal_total = 0.0
            for name, cmd in gdal:
                s, rss = run(cmd, args.repeat)
                gdal_total += s
                rows.append((name, s, rss, 1.0))
            rows.append(("GDAL total (3 commands)", gdal_total, float("nan"), 1.0))
            for name, out, extra, k in ours_cmds:
                cmd = [*ours, "topo", str(dem), "-o", out, "--contours", "20,100"]
                s, rss = run([*cmd, *extra, "--no-progress"], args.repeat)
                rows.append((name, s, rss, k))
            for name, s, rss, k in rows:
                ratio = f"{gdal_total / s:7.1f}x" if name.startswith("sciviz") and k == 1 else ""
                mp = n * n * k * k / s / 1e6
                mem = f"{rss:7.0f}" if rss == rss else " " * 7
                print(f"{n:>6} {name:<44} {s:7.2f} {mp:7.1f} {mem} {ratio:>8}")
            print()


def gdal_version() -> str:
    out = subprocess.run(["gdalinfo", "--version"], capture_output=True, text=True).stdout
    return out.split(",")[0].replace("GDAL ", "").strip() or "?"


if __name__ == "__main__":
    main()
