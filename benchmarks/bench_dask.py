"""Out-of-core topographic maps on dask: throughput vs chunk size and workers, peak memory.

Part 1 (this process, dask's threaded scheduler): a DEM GeoTIFF (synthetic, written once)
mapped with :func:`sciviz_gbuf.topographic_map` read lazily with several chunk sizes (the
reduction pass included, the map's blocks computed and dropped), against reading it whole and
mapping it in memory, and ``gdaldem hillshade`` (one layer of the map) on the same file.

Part 2 (``dask.distributed.LocalCluster``; by default 1 worker on one core, 2 workers on one
core each, and 1 worker running its kernels on both cores; 3 GB memory limit each): a
synthetic DEM generated chunk by chunk on the workers (never held whole; its generation, done
twice, once for the reduction pass, is part of the time), mapped and written to a
Cloud-Optimised GeoTIFF with a PNG overview (the workers deflate the tiles), with the peak
resident memory of every worker and of this (writing) process, the COG checked by GDAL's
validator, and the tasks and bytes each worker moved. Peer in the same run: GDAL's COG
driver copying the finished COG (the serial re-encode ``write_cog`` used to end with).

    python benchmarks/bench_dask.py                    # 20000 x 20000 in part 2 (minutes)
    python benchmarks/bench_dask.py --size 6000 --part1-size 4096   # quicker
    python benchmarks/bench_dask.py --skip-part1 --size 4096,16384,30000 --workers 2x1
        # memory per worker against the raster's size, same chunks (about 8 minutes)
    python benchmarks/bench_dask.py --skip-part1 --size 50000 --workers 2x1 \
        --memory-limit 1.5GB --cog-only --no-gdal-peer
        # the continental map: 2.5 gigapixels in 2 x 1.5 GB workers (about 15 minutes)
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


def _worker_traffic(dask_worker) -> dict:
    """Bytes this worker received from and sent to other workers (halo chunks) or gave to the
    client (its blocks' results)."""
    received = sum(int(e.get("total", 0)) for e in dask_worker.transfer_incoming_log)
    return {"in": received, "out": int(dask_worker.transfer_outgoing_bytes_total)}


def part2(
    size: int,
    configs: list[tuple[int, int]],
    chunks: int,
    memory_limit: str,
    *,
    map_alone: bool = True,
    gdal_peer: bool = True,
) -> list:
    """Map a synthetic DEM to a COG on a LocalCluster for each (workers, cores per worker);
    ``map_alone``: also time the map's blocks without writing; ``gdal_peer``: time GDAL's COG
    copy of the first configuration's output."""
    import dask.array as da
    from distributed import get_task_stream

    import sciviz_gbuf as sg
    from sciviz_gbuf.datasets import synthetic_dem
    from sciviz_gbuf.writers.cog import local_client, write_cog

    rows = []
    mpix = size * size / 1e6
    for n, cores in configs:
        before = os.environ.get("NUMBA_NUM_THREADS")
        os.environ["NUMBA_NUM_THREADS"] = str(cores)  # the workers' kernel threads
        try:
            client = local_client(n, memory_limit=memory_limit)
        finally:
            if before is None:
                os.environ.pop("NUMBA_NUM_THREADS", None)
            else:
                os.environ["NUMBA_NUM_THREADS"] = before
        try:
            # warm the workers (imports, numba cache), then time the map's blocks alone ...
            small = synthetic_dem((512, 512), chunks=256)
            client.compute(sg.topographic_map(small)).result()
            dem = synthetic_dem((size, size), chunks=chunks)
            t_blocks = float("nan")
            if map_alone:
                t0 = time.perf_counter()
                image = sg.topographic_map(dem)  # includes the reduction pass
                client.compute(da.sum(image[..., 3], dtype="int64")).result()
                t_blocks = time.perf_counter() - t0
            # ... and the whole pipeline to the COG, with peak memory and traffic
            client.run(_reset_peak)
            _reset_peak()
            base = client.run(_worker_traffic)
            with tempfile.TemporaryDirectory(dir=".") as tmp, get_task_stream(client) as ts:
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
                valid = _validate(out)
                first = (n, cores) == configs[0]
                t_gdal = (
                    _gdal_cog_copy(out, Path(tmp) / "gdal.tif") if gdal_peer and first else None
                )
            traffic = client.run(_worker_traffic)
            peaks = client.run(_peak_mb)
            tasks: dict[str, int] = {}
            for rec in ts.data:
                tasks[rec["worker"]] = tasks.get(rec["worker"], 0) + 1
            moved = [
                (traffic[w]["in"] - base[w]["in"], traffic[w]["out"] - base[w]["out"])
                for w in traffic
            ]
            rows.append(
                {
                    "workers": n, "cores": cores, "t_blocks": t_blocks, "t": t,
                    "rate": mpix / t, "wpeak": max(peaks.values()), "cpeak": _peak_mb(),
                    "wsum": sum(peaks.values()),
                    "mb": size_mb, "valid": valid, "gdal": t_gdal,
                    "tasks": sorted(tasks.values()), "moved": moved,
                }
            )  # fmt: skip
        finally:
            cluster = client.cluster
            client.close()
            cluster.close()
    return rows


def _gdal_cog_copy(src: Path, dst: Path) -> float:
    """Seconds GDAL's COG driver takes to copy the map (what write_cog did after the blocks
    until this change: decode every tile, deflate it again, build the overviews)."""
    import rasterio
    import rasterio.shutil

    t0 = time.perf_counter()
    with rasterio.Env(GDAL_CACHEMAX=256):
        rasterio.shutil.copy(
            src, dst, driver="COG", BLOCKSIZE=512, COMPRESS="DEFLATE", LEVEL=1, PREDICTOR="YES",
            RESAMPLING="AVERAGE", OVERVIEWS="IGNORE_EXISTING", BIGTIFF="IF_SAFER",
            NUM_THREADS="ALL_CPUS",
        )  # fmt: skip
    return time.perf_counter() - t0


def _validate(path: Path) -> str:
    """GDAL's validate_cloud_optimized_geotiff.py (full check) if a Python with GDAL's
    bindings is on this machine, else our check_cog."""
    for python in ("/usr/bin/python3", shutil.which("python3")):
        if not python:
            continue
        run = subprocess.run(
            [python, "-m", "osgeo_utils.samples.validate_cloud_optimized_geotiff",
             "--full-check=yes", str(path)],
            capture_output=True, text=True,
        )  # fmt: skip
        if "No module named" in run.stderr:
            continue
        return "valid (GDAL)" if run.returncode == 0 else "INVALID: " + run.stdout.strip()[:60]
    from sciviz_gbuf.writers.cog import check_cog

    check_cog(path)
    return "valid (check_cog)"


def _print_part2(size: int, rows: list, chunks: int, memory_limit: str) -> None:
    print(
        f"\nPart 2: {size}^2 synthetic DEM -> map -> COG + PNG overview, LocalCluster, "
        f"chunks {chunks}, memory limit {memory_limit} per worker"
    )
    print(
        f"{'workers':>7} {'cores':>5} {'map s':>7} {'speed-up':>9} {'to COG s':>9} "
        f"{'MPix/s':>7} {'speed-up':>9} {'worker MB':>10} {'client MB':>10} {'total MB':>9} "
        f"{'COG MB':>7}  COG"
    )
    base = rows[0]
    for r in rows:
        print(
            f"{r['workers']:>7} {r['workers'] * r['cores']:>5} {r['t_blocks']:7.1f} "
            f"{base['t_blocks'] / r['t_blocks']:8.2f}x {r['t']:9.1f} {r['rate']:7.1f} "
            f"{base['t'] / r['t']:8.2f}x {r['wpeak']:10.0f} {r['cpeak']:10.0f} "
            f"{r['wsum'] + r['cpeak']:9.0f} {r['mb']:7.1f}  "
            f"{r['valid']}"
        )
    if base["gdal"] is not None:
        print(
            f"peer, same run: GDAL's COG driver copying that COG (re-encode + overviews, "
            f"NUM_THREADS=ALL_CPUS): {base['gdal']:.1f} s"
        )
    print(f"\n{'workers':>7} {'tasks per worker':>24} {'MB in per worker':>24} {'MB out':>18}")
    for r in rows:
        ins = [m[0] / 1e6 for m in r["moved"]]
        outs = [m[1] / 1e6 for m in r["moved"]]
        print(
            f"{r['workers']:>7} {r['tasks']!s:>24} "
            f"{' '.join(f'{v:.0f}' for v in ins):>24} {' '.join(f'{v:.0f}' for v in outs):>18}"
        )


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--size", default="20000", help="part 2 grid edge(s), comma-separated (default 20000)"
    )
    p.add_argument("--part1-size", type=int, default=8192, help="part 1 grid edge")
    p.add_argument("--chunks", default="512,1024,2048,4096", help="part 1 chunk sizes")
    p.add_argument(
        "--workers",
        default="1x1,2x1,1x2",
        help="part 2 clusters, WORKERSxCORES each (cores: numba kernel threads per worker); "
        "default 1x1,2x1,1x2: the scaling from one core to two workers of one core, and one "
        "worker running its kernels on both cores",
    )
    p.add_argument("--cluster-chunks", type=int, default=2048, help="part 2 chunk size")
    p.add_argument("--memory-limit", default="3GB", help="per worker (default 3GB)")
    p.add_argument("--skip-part1", action="store_true")
    p.add_argument(
        "--cog-only", action="store_true", help="part 2: skip timing the map without writing"
    )
    p.add_argument(
        "--no-gdal-peer", action="store_true", help="part 2: skip timing GDAL's COG copy"
    )
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
    configs = [tuple(int(x) for x in c.split("x")) for c in args.workers.split(",")]
    memory = []
    for size in sizes:
        rows = part2(
            size, configs, args.cluster_chunks, args.memory_limit,
            map_alone=not args.cog_only, gdal_peer=not args.no_gdal_peer,
        )  # fmt: skip
        _print_part2(size, rows, args.cluster_chunks, args.memory_limit)
        memory.extend((size, r["workers"], r["wpeak"], r["cpeak"]) for r in rows)
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
