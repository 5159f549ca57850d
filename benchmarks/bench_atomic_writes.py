"""What writing outputs completely-or-not-at-all costs (``sciviz_gbuf._atomic``).

Every writer fills a temporary file beside its output, checks it, syncs it to disk and renames
it. For each writer and image size this prints the time of a write as the package does it,
the same write without the two ``fsync`` calls (file and folder), and, for the TIFF writers,
the time of the completeness check (:func:`sciviz_gbuf.writers.geotiff.check_tiff`: the
directory read back, every block's offset and size within the file) on the output.

    python benchmarks/bench_atomic_writes.py                 # 2048 and 6144 pixels a side
    python benchmarks/bench_atomic_writes.py --sizes 1024 4096 --folder /some/disk
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np


def _map_like(n: int) -> np.ndarray:
    """An RGBA uint8 image of smooth colour areas with a little noise (compresses like a map)."""
    y, x = np.mgrid[0:n, 0:n].astype(np.float32) / n
    rng = np.random.default_rng(0)
    rgba = np.empty((n, n, 4), np.uint8)
    for k, f in enumerate((3.0, 5.0, 7.0)):
        band = 127 + 100 * np.sin(f * x + k) * np.cos(f * y)
        rgba[..., k] = np.clip(band + rng.normal(0, 2, (n, n)), 0, 255).astype(np.uint8)
    rgba[..., 3] = 255
    return rgba


def _time(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[2048, 6144])
    parser.add_argument("--folder", default=None, help="where to write (default: a temp dir)")
    args = parser.parse_args()

    import pyvista as pv

    from sciviz_gbuf import _atomic, capture
    from sciviz_gbuf.compose import write_geotiff, write_png
    from sciviz_gbuf.writers.cog import write_cog
    from sciviz_gbuf.writers.geotiff import check_tiff

    real_fsync = _atomic._fsync
    transform = (500000.0, 10.0, 0.0, 4000000.0, 0.0, -10.0)
    rows = []
    with tempfile.TemporaryDirectory(dir=args.folder) as tmp:
        folder = Path(tmp)
        for n in args.sizes:
            image = _map_like(n)
            gb = capture(pv.Sphere(), window_size=(min(n, 4096), min(n, 4096)))
            writers = {
                "write_png": (folder / "m.png", lambda p, im=image: write_png(p, im)),
                "write_geotiff": (
                    folder / "m.tif",
                    lambda p, im=image: write_geotiff(p, im, transform=transform),
                ),
                "write_cog": (
                    folder / "c.tif",
                    lambda p, im=image: write_cog(im, p, transform=transform),
                ),
                "GBuffer.save .npz": (folder / "g.npz", gb.save),
                "GBuffer.save .vti": (folder / "g.vti", gb.save),
            }
            for name, (path, write) in writers.items():
                t_full = _time(lambda w=write, p=path: w(p))
                _atomic._fsync = lambda *a, **k: None
                try:
                    t_nosync = _time(lambda w=write, p=path: w(p))
                finally:
                    _atomic._fsync = real_fsync
                t_check = float("nan")
                if path.suffix == ".tif":
                    with _atomic.atomic_output(folder / "copy.tif") as part:
                        part.path.write_bytes(path.read_bytes())
                        t_check = _time(lambda pt=part, sh=image.shape: check_tiff(pt, sh))
                side = gb.shape[1] if name.startswith("GBuffer") else n
                size_mb = path.stat().st_size / 1e6
                rows.append((name, side, size_mb, t_full, t_nosync, t_check))
                path.unlink()

    print(
        f"{'writer':<20} {'side px':>8} {'file MB':>8} {'write s':>8} {'no fsync s':>11} "
        f"{'check s':>8}"
    )
    for name, side, mb, t_full, t_nosync, t_check in rows:
        check = "-" if np.isnan(t_check) else f"{t_check:.3f}"
        print(f"{name:<20} {side:>8} {mb:>8.1f} {t_full:>8.2f} {t_nosync:>11.2f} {check:>8}")


if __name__ == "__main__":
    main()
