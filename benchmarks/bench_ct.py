"""Benchmark: a DICOM CT series -> bone isosurface -> 1024^2 enhanced PNG, stage by stage.

Run from the project root with the project's venv active::

    python benchmarks/bench_ct.py                        # the shared Philips phantom (~1 min)
    python benchmarks/bench_ct.py --series DIR --size 512

Ours (``sciviz_gbuf``): ``read_dicom_series`` (headers, order by position, per-slice rescale,
geometry checks) -> ``isosurface`` (flying edges at 300 HU + 60 windowed-sinc iterations + normals)
-> ``capture`` (1024^2, supersample 2) -> ``ct_enhance`` (profiles, shading, contours, bands) ->
PNG. Peer, same run: what a PyVista user writes by hand: ``pydicom.dcmread`` every file, sort by
ImagePositionPatient z, stack and rescale into a ``pyvista.ImageData``, ``contour(method=
"flying_edges")`` at 300 HU, and a plain shaded ``Plotter.screenshot`` at 1024^2 (no smoothing,
no supersampling, no enhancement). Our isosurface without smoothing is listed too, as the like
for like of the peer's contour.

In-process stages are warm (one run first, so numba kernels are loaded and files are in the page
cache) and the best of ``--repeats`` is reported. "whole process" runs each pipeline as a fresh
``python`` process (imports, numba cache loading and the render window included): what a user
waits for at the command line (``sciviz-gbuf ct``).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

# Headless: VTK's default window class would try X first; must precede the sciviz_gbuf import.
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numpy as np
import pydicom
import pyvista as pv

from sciviz_gbuf.compose import write_png
from sciviz_gbuf.core.capture import capture
from sciviz_gbuf.core.isosurface import isosurface
from sciviz_gbuf.readers.dicom import read_dicom_series
from sciviz_gbuf.recipes.medical import ct_enhance, view_camera

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SERIES = ROOT.parent / "shared" / "data" / "ct" / "dcm_qa_ct_Philips_phantom_5mm"

PEER_SCRIPT = """
import sys, numpy as np, pydicom, pyvista as pv
from pathlib import Path
folder, out, size = Path(sys.argv[1]), sys.argv[2], int(sys.argv[3])
ds = [pydicom.dcmread(p) for p in sorted(folder.iterdir())]
ds.sort(key=lambda d: float(d.ImagePositionPatient[2]))
hu = np.stack([d.pixel_array * float(d.RescaleSlope) + float(d.RescaleIntercept) for d in ds])
dy, dx = (float(v) for v in ds[0].PixelSpacing)
dz = float(ds[1].ImagePositionPatient[2]) - float(ds[0].ImagePositionPatient[2])
vol = pv.ImageData(dimensions=hu.shape[::-1], spacing=(dx, dy, dz),
                   origin=[float(v) for v in ds[0].ImagePositionPatient])
vol.point_data["HU"] = hu.astype(np.float32).ravel()
surf = vol.contour([300.0], scalars="HU", method="flying_edges")
pl = pv.Plotter(off_screen=True, window_size=(size, size))
pl.add_mesh(surf, color="ivory")
pl.view_xz()
pl.screenshot(out)
"""


def best(fn: Callable[[], object], repeats: int) -> tuple[float, object]:
    times, result = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return min(times), result


def peer_read(folder: Path) -> pv.ImageData:
    ds = [pydicom.dcmread(p) for p in sorted(folder.iterdir())]
    ds.sort(key=lambda d: float(d.ImagePositionPatient[2]))
    hu = np.stack([d.pixel_array * float(d.RescaleSlope) + float(d.RescaleIntercept) for d in ds])
    dy, dx = (float(v) for v in ds[0].PixelSpacing)
    dz = float(ds[1].ImagePositionPatient[2]) - float(ds[0].ImagePositionPatient[2])
    vol = pv.ImageData(
        dimensions=hu.shape[::-1],
        spacing=(dx, dy, dz),
        origin=[float(v) for v in ds[0].ImagePositionPatient],
    )
    vol.point_data["HU"] = hu.astype(np.float32).ravel()
    return vol


def peer_screenshot(surf: pv.PolyData, size: int, path: Path) -> None:
    pl = pv.Plotter(off_screen=True, window_size=(size, size))
    pl.add_mesh(surf, color="ivory")
    pl.view_xz()
    pl.screenshot(str(path))
    pl.close()


def whole_process(cmd: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--series", type=Path, default=DEFAULT_SERIES, help="DICOM series folder")
    ap.add_argument("--size", type=int, default=1024, help="output picture size (square)")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    if not args.series.is_dir():
        sys.exit(f"no series folder {args.series} (give --series DIR)")
    size, reps = args.size, args.repeats
    tmp = Path(tempfile.mkdtemp(prefix="bench_ct_"))

    # Warm-up: numba kernels, page cache, the EGL context.
    vol = read_dicom_series(args.series)
    surf = isosurface(vol, iso="bone")
    ct_enhance(surf, window_size=(64, 64), layout="enhanced")

    rows: list[tuple[str, float, float | None]] = []
    t_read, vol = best(lambda: read_dicom_series(args.series), reps)
    t_peer_read, pvol = best(lambda: peer_read(args.series), reps)
    rows.append(("read series -> HU volume", t_read, t_peer_read))
    t_iso0, _ = best(lambda: isosurface(vol, iso="bone", smooth=0), reps)
    t_peer_iso, psurf = best(
        lambda: pvol.contour([300.0], scalars="HU", method="flying_edges"), reps
    )
    rows.append(("isosurface, no smoothing", t_iso0, t_peer_iso))
    t_iso, surf = best(lambda: isosurface(vol, iso="bone"), reps)
    rows.append(("isosurface + smoothing + normals (ours)", t_iso, None))
    pos, focal, up = view_camera(surf.points, "anterior", view_angle=20.0)
    cam = pv.Camera()
    cam.position, cam.focal_point, cam.up, cam.view_angle = pos, focal, up, 20.0
    t_cap, gb = best(
        lambda: capture(surf, window_size=(size, size), camera=cam, supersample=2), reps
    )
    t_shot, _ = best(lambda: peer_screenshot(psurf, size, tmp / "peer.png"), reps)
    rows.append((f"capture {size}^2 x2 supersampled / screenshot", t_cap, t_shot))
    t_filt, img = best(lambda: ct_enhance(gb, layout="enhanced"), reps)
    rows.append(("filters: Fig. 14 (b) (ours)", t_filt, None))
    t_png, _ = best(lambda: write_png(tmp / "ours.png", img), reps)
    rows.append(("PNG", t_png, None))
    total = t_read + t_iso + t_cap + t_filt + t_png
    rows.append(("sum of stages", total, t_peer_read + t_peer_iso + t_shot))

    cli = [sys.executable, "-m", "sciviz_gbuf", "ct", str(args.series), "-o"]
    cli += [str(tmp / "cli.png"), "--layout", "enhanced", "--size", f"{size}x{size}"]
    peer = [sys.executable, "-c", PEER_SCRIPT, str(args.series), str(tmp / "p.png"), str(size)]
    t_cli = min(whole_process(cli) for _ in range(reps))
    t_peer_cli = min(whole_process(peer) for _ in range(reps))
    rows.append(("whole process (fresh python)", t_cli, t_peer_cli))

    print(f"series {args.series.name}: {vol.dimensions} voxels, surface {surf.n_cells} triangles")
    print(f"picture {size}x{size}; best of {reps}; peer = pydicom + pyvista flying edges + plain")
    print(f"{'stage':<44} {'ours s':>8} {'peer s':>8} {'ours/peer':>10}")
    for name, ours, peer_t in rows:
        ratio = f"{ours / peer_t:10.2f}" if peer_t else " " * 10
        peer_s = f"{peer_t:8.3f}" if peer_t is not None else " " * 8
        print(f"{name:<44} {ours:8.3f} {peer_s} {ratio}")


if __name__ == "__main__":
    main()
