"""Out-of-core topographic maps on dask: throughput vs chunk size and workers, peak memory.

Part 1 (this process, dask's threaded scheduler): a DEM GeoTIFF (synthetic, written once)
mapped with :func:`sciviz_gbuf.topographic_map` read lazily with several chunk sizes (the
reduction pass included, the map's blocks computed and dropped), against reading it whole and
mapping it in memory, and ``gdaldem hillshade`` (one layer of the map) on the same file.

Part 2 (``dask.distributed.LocalCluster``, 1 then 2 worker processes with a 3 GB memory
limit each): a synthetic DEM generated chunk by chunk on the workers (never held whole; its
generation, done twice, once for the reduction pass, is part of the time), mapped and written
to a Cloud-Optimised GeoTIFF with a PNG overview, with the peak resident memory of every
worker and of this (writing) process.

    python benchmarks/bench_dask.py                    # 20000 x 20000 in part 2 (minutes)
    python benchmarks/bench_dask.py --size 6000 --part1-size 4096   # quicker
    python benchmarks/bench_dask.py --skip-part1 --size 4096,16384,30000 --workers 2
        # memory per worker against the raster's size, same chunks (about 8 minutes)
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
    """Map a GeoTIFF DEM in memory and lazily (each chunk size), both from the file."""
    import rasterio
    from rasterio.transform import Affine

    import sciviz_gbuf as sg
    from sciviz_gbuf.datasets import synthetic_dem
    from sciviz_gbuf.readers import read_dem

    rows: list[tuple[str, float, float]] = []
    mpix = size * size / 1e6
    with tempfile.TemporaryDirectory(dir=".") as tmp:
        src = Path(tmp) / "dem.tif"
        t0 = time.perf_counter()
        z = synthetic_dem((size, size), chunks=2048).heights.compute()
        t_gen = time.perf_counter() - t0
        with rasterio.open(
            src, "w", driver="GTiff", width=size, height=size, count=1, dtype="float32",
            transform=Affine(30, 0, 0, 0, -30, 30 * size), tiled=True, blockxsize=512,
            blockysize=512, crs="EPSG:32633",
        ) as dst:  # fmt: skip
            dst.write(z, 1)
        del z
        sg.topographic_map(read_dem(src, chunks=256).heights[:256, :256].compute())  # warm
        t0 = time.perf_counter()
        sg.topographic_map(read_dem(src))
        t_mem = time.perf_counter() - t0
        rows.append((f"in memory (read + map), {size}^2", t_mem, mpix / t_mem))
        for c in chunk_sizes:
            t0 = time.perf_counter()
            image = sg.topographic_map(read_dem(src, chunks=c))  # + the reduction pass
            t = time.perf_counter() - t0 + _drop(image)
            rows.append((f"dask threads, chunks {c}", t, mpix / t))
        gdaldem = shutil.which("gdaldem")
        if gdaldem:
            t0 = time.perf_counter()
            subprocess.run(
                [gdaldem, "hillshade", "-q", "-compute_edges", str(src), str(Path(tmp) / "h.tif")],
                check=True,
            )
            t = time.perf_counter() - t0
            rows.append(("peer: gdaldem hillshade (one layer)", t, mpix / t))
    rows.append((f"(synthetic DEM generation, {size}^2)", t_gen, mpix / t_gen))
    return rows


def _peak_mb() -> float:
    """This process's peak resident memory since the last :func:`_reset_peak` (VmHWM: unlike
    ``ru_maxrss`` it does not carry a spawning parent's peak into a worker)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024.0
    return float("nan")


def _reset_peak() -> None:
    """Peak resident memory back to the current one (Linux ``clear_refs`` 5)."""
    try:
        Path("/proc/self/clear_refs").write_text("5")
    except OSError:
        pass


def part2(size: int, workers: list[int], chunks: int, memory_limit: str) -> list[tuple]:
    import dask.array as da

    import sciviz_gbuf as sg
    from sciviz_gbuf.datasets import synthetic_dem
    from sciviz_gbuf.writers.cog import local_client, write_cog

    rows = []
    mpix = size * size / 1e6
    for n in workers:
        client = local_client(n, memory_limit=memory_limit)
        try:
            # warm the workers (imports, numba cache), then time the map's blocks alone ...
            small = synthetic_dem((512, 512), chunks=256)
            client.compute(sg.topographic_map(small)).result()
            dem = synthetic_dem((size, size), chunks=chunks)
            t0 = time.perf_counter()
            image = sg.topographic_map(dem)  # includes the reduction pass
            client.compute(da.sum(image[..., 3], dtype="int64")).result()
            t_blocks = time.perf_counter() - t0
            # ... and the whole pipeline to the COG, with peak memory
            client.run(_reset_peak)
            _reset_peak()
            with tempfile.TemporaryDirectory(dir=".") as tmp:
                out = Path(tmp) / "map.tif"
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
            peaks = client.run(_peak_mb)
            rows.append(
                (n, t_blocks, mpix / t_blocks, t, mpix / t, max(peaks.values()), _peak_mb(),
                 size_mb)
            )  # fmt: skip
        finally:
            cluster = client.cluster
            client.close()
            cluster.close()
    return rows


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--size", default="20000", help="part 2 grid edge(s), comma-separated (default 20000)"
    )
    p.add_argument("--part1-size", type=int, default=8192, help="part 1 grid edge")
    p.add_argument("--chunks", default="512,1024,2048,4096", help="part 1 chunk sizes")
    p.add_argument("--workers", default="1,2", help="part 2 worker counts")
    p.add_argument("--cluster-chunks", type=int, default=2048, help="part 2 chunk size")
    p.add_argument("--memory-limit", default="3GB", help="per worker (default 3GB)")
    p.add_argument("--skip-part1", action="store_true")
    p.add_argument("--skip-part2", action="store_true")
    args = p.parse_args(argv)
    print(f"python {sys.version.split()[0]}, {os.cpu_count()} cores")
    if not args.skip_part1:
        rows = part1(args.part1_size, [int(c) for c in args.chunks.split(",")])
        base = rows[0][2]
        print(f"\nPart 1: {args.part1_size}^2 synthetic DEM -> topographic map (this process)")
        print(f"{'run':<40} {'s':>8} {'MPix/s':>8} {'vs memory':>10}")
        for name, t, rate in rows:
            print(f"{name:<40} {t:8.2f} {rate:8.1f} {rate / base:9.2f}x")
    if args.skip_part2:
        return 0
    sizes = [int(v) for v in args.size.split(",")]
    workers = [int(w) for w in args.workers.split(",")]
    memory = []
    for size in sizes:
        rows = part2(size, workers, args.cluster_chunks, args.memory_limit)
        print(
            f"\nPart 2: {size}^2 synthetic DEM -> map -> COG + PNG overview, LocalCluster, "
            f"chunks {args.cluster_chunks}, memory limit {args.memory_limit} per worker"
        )
        print(
            f"{'workers':>7} {'map s':>7} {'MPix/s':>7} {'speed-up':>9} {'to COG s':>9} "
            f"{'MPix/s':>7} {'speed-up':>9} {'worker peak MB':>15} {'client peak MB':>15} "
            f"{'COG MB':>7}"
        )
        b0, c0 = rows[0][1], rows[0][3]
        for n, tb, rb, t, rate, wpeak, cpeak, mb in rows:
            print(
                f"{n:>7} {tb:7.1f} {rb:7.1f} {b0 / tb:8.2f}x {t:9.1f} {rate:7.1f} "
                f"{c0 / t:8.2f}x {wpeak:15.0f} {cpeak:15.0f} {mb:7.1f}"
            )
            memory.append((size, n, wpeak, cpeak))
    if len(sizes) > 1:
        # The acceptance of bounded memory: peak per worker independent of the raster's size.
        print(f"\nPeak memory against the raster's size (chunks {args.cluster_chunks})")
        print(f"{'size':>7} {'workers':>7} {'worker MB':>10} {'vs smallest':>12} {'client MB':>10}")
        first = {n: w for s_, n, w, _ in memory if s_ == sizes[0]}
        for size, n, wpeak, cpeak in memory:
            print(f"{size:>7} {n:>7} {wpeak:10.0f} {wpeak / first[n]:11.2f}x {cpeak:10.0f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
