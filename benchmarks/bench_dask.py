"""Out-of-core topographic maps on dask: throughput vs chunk size and workers, peak memory.

Part 1 (this process, dask's threaded scheduler): a synthetic DEM (generated chunk by chunk,
never held whole) mapped with :func:`sciviz_gbuf.topographic_map` for several chunk sizes, the
map's blocks computed and dropped; against the in-memory map of the same grid and, as the
streaming peer, ``gdaldem hillshade`` (one operation of the map) on the grid as a GeoTIFF.

Part 2 (``dask.distributed.LocalCluster``, 1 then 2 worker processes with a 3 GB memory
limit each): the full pipeline to a Cloud-Optimised GeoTIFF with a PNG overview, with the peak
resident memory of every worker and of this (writing) process.

    python benchmarks/bench_dask.py                    # 20000 x 20000 in part 2 (minutes)
    python benchmarks/bench_dask.py --size 6000 --part1-size 4096   # quicker
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _drop(image) -> float:
    """Compute every block of a dask image and drop it (threads); seconds."""
    import dask

    t0 = time.perf_counter()
    blocks = image.to_delayed().ravel()
    batch = 2 * (os.cpu_count() or 1)
    for i in range(0, len(blocks), batch):
        dask.compute(*[b.sum() for b in blocks[i : i + batch]], scheduler="threads")
    return time.perf_counter() - t0


def part1(size: int, chunk_sizes: list[int]) -> list[tuple[str, float, float]]:
    import sciviz_gbuf as sg
    from sciviz_gbuf.datasets import synthetic_dem

    rows: list[tuple[str, float, float]] = []
    mpix = size * size / 1e6
    dem = synthetic_dem((size, size), chunks=4096)
    z = dem.heights.compute()
    mem = dataclasses.replace(dem, heights=z, mask=np.isfinite(z))
    small = z[:256, :256]
    sg.topographic_map(dataclasses.replace(dem, heights=small, mask=np.isfinite(small)))  # warm
    t0 = time.perf_counter()
    sg.topographic_map(mem)
    t_mem = time.perf_counter() - t0
    rows.append((f"in memory, {size}^2", t_mem, mpix / t_mem))
    for c in chunk_sizes:
        lazy = synthetic_dem((size, size), chunks=c)
        t0 = time.perf_counter()
        image = sg.topographic_map(lazy)  # includes the reduction pass (range, slope)
        t = time.perf_counter() - t0 + _drop(image)
        rows.append((f"dask threads, chunks {c}", t, mpix / t))
    gdaldem = shutil.which("gdaldem")
    if gdaldem:
        import rasterio
        from rasterio.transform import Affine

        with tempfile.TemporaryDirectory() as tmp:
            src = Path(tmp) / "dem.tif"
            with rasterio.open(
                src, "w", driver="GTiff", width=size, height=size, count=1, dtype="float32",
                transform=Affine(30, 0, 0, 0, -30, 30 * size), tiled=True,
            ) as dst:  # fmt: skip
                dst.write(z, 1)
            t0 = time.perf_counter()
            subprocess.run(
                [gdaldem, "hillshade", "-q", "-compute_edges", str(src), str(Path(tmp) / "h.tif")],
                check=True,
            )
            t = time.perf_counter() - t0
            rows.append(("peer: gdaldem hillshade (one layer)", t, mpix / t))
    return rows


def part2(size: int, workers: list[int], chunks: int, memory_limit: str) -> list[tuple]:
    import sciviz_gbuf as sg
    from sciviz_gbuf.cog import local_client, write_cog
    from sciviz_gbuf.datasets import synthetic_dem

    rows = []
    mpix = size * size / 1e6
    for n in workers:
        client = local_client(n, memory_limit=memory_limit)
        try:
            client.run(lambda: None)  # workers up before the clock starts
            with tempfile.TemporaryDirectory(dir=".") as tmp:
                out = Path(tmp) / "map.tif"
                dem = synthetic_dem((size, size), chunks=chunks)
                t0 = time.perf_counter()
                write_cog(
                    sg.topographic_map(dem),
                    out,
                    dem=dem,
                    overview_png=Path(tmp) / "map.png",
                    client=client,
                )
                t = time.perf_counter() - t0
                size_mb = out.stat().st_size / 1e6
            peaks = client.run(lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0)
            rows.append((n, t, mpix / t, max(peaks.values()), _peak_rss_mb(), size_mb))
        finally:
            cluster = client.cluster
            client.close()
            cluster.close()
    return rows


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", type=int, default=20000, help="part 2 grid edge (default 20000)")
    p.add_argument("--part1-size", type=int, default=8192, help="part 1 grid edge")
    p.add_argument("--chunks", default="512,1024,2048,4096", help="part 1 chunk sizes")
    p.add_argument("--workers", default="1,2", help="part 2 worker counts")
    p.add_argument("--cluster-chunks", type=int, default=2048, help="part 2 chunk size")
    p.add_argument("--memory-limit", default="3GB", help="per worker (default 3GB)")
    p.add_argument("--skip-part1", action="store_true")
    args = p.parse_args(argv)
    print(f"python {sys.version.split()[0]}, {os.cpu_count()} cores")
    if not args.skip_part1:
        rows = part1(args.part1_size, [int(c) for c in args.chunks.split(",")])
        base = rows[0][2]
        print(f"\nPart 1: {args.part1_size}^2 synthetic DEM -> topographic map (this process)")
        print(f"{'run':<40} {'s':>8} {'MPix/s':>8} {'vs memory':>10}")
        for name, t, rate in rows:
            print(f"{name:<40} {t:8.2f} {rate:8.1f} {rate / base:9.2f}x")
    rows = part2(
        args.size, [int(w) for w in args.workers.split(",")], args.cluster_chunks,
        args.memory_limit,
    )  # fmt: skip
    print(
        f"\nPart 2: {args.size}^2 synthetic DEM -> map -> COG + PNG overview, LocalCluster, "
        f"chunks {args.cluster_chunks}, memory limit {args.memory_limit} per worker"
    )
    print(
        f"{'workers':>7} {'s':>8} {'MPix/s':>8} {'speed-up':>9} {'worker peak MB':>15} "
        f"{'client peak MB':>15} {'COG MB':>8}"
    )
    first = rows[0][1]
    for n, t, rate, wpeak, cpeak, mb in rows:
        print(
            f"{n:>7} {t:8.1f} {rate:8.1f} {first / t:8.2f}x {wpeak:15.0f} {cpeak:15.0f} {mb:8.1f}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
