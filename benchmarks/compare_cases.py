"""The cases of ``benchmarks/compare.py``: each run in a fresh process against one tree.

``python benchmarks/compare_cases.py CASE --quick`` prints one JSON object ``{metric: value}``
(seconds, or a ratio for the ``/plain`` metrics) for the ``sciviz_gbuf`` that ``import`` finds
first (``compare.py`` sets ``PYTHONPATH`` to the tree under test). Every case does its own
untimed warm-up (first touch, numba's compile or cache load), then takes the median of
``--repeat`` timed runs. The cases use the public API only, so one file times old and new
commits alike; a metric the tree cannot run (an option it does not have yet) is left out
and shows as ``-`` in the table.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
STL = HERE.parents[1] / "shared" / "data" / "meshes" / "vtkdata_42400-IDGH.stl"


def median_time(fn: Callable[[], object], repeat: int, warm: int = 1) -> float:
    """Median seconds of ``repeat`` calls of ``fn`` after ``warm`` untimed ones."""
    for _ in range(warm):
        fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def fractal(n: int, hurst: float, seed: int = 1) -> np.ndarray:
    """The benchmarks' synthetic terrain (``bench_terrain.make_dem``'s heights, 0 - 2000 m,
    10 m cells, a round nodata lake as NaN): Hurst 0.8 smooth hills, 0.6 rugged."""
    sys.path.insert(0, str(HERE))
    import rasterio
    from bench_terrain import make_dem

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "dem.tif"
        make_dem(path, n, seed=seed, hurst=hurst)
        with rasterio.open(path) as f:
            z = f.read(1)
    z[z == -9999.0] = np.nan
    return z


def stale_wave(res: int):
    """A ``res`` x ``res`` plane (2 (res - 1)^2 triangles) whose normals were computed before
    its points were lifted into a wave: the surface of issue 44's capture regression."""
    import pyvista as pv

    plane = pv.Plane(i_resolution=res - 1, j_resolution=res - 1).triangulate().compute_normals()
    pts = np.asarray(plane.points).copy()
    pts[:, 2] = 0.1 * np.sin(12 * pts[:, 0]) * np.cos(9 * pts[:, 1])
    plane.points = pts
    return plane


def _forget(sg) -> None:
    forget = getattr(sg, "clear_capture_cache", None)  # trees before issue 44 keep nothing
    if forget is not None:
        forget()


def case_capture(quick: bool, repeat: int) -> dict[str, float]:
    """1M-triangle capture (fresh and again) against a plain PyVista render + screenshot."""
    import pyvista as pv

    import sciviz_gbuf as sg

    mesh = stale_wave(300 if quick else 708)
    n = 512 if quick else 1024

    def plain() -> None:
        pl = pv.Plotter(off_screen=True, window_size=(n, n))
        pl.add_mesh(mesh)
        pl.screenshot()
        pl.close()

    def fresh() -> None:
        _forget(sg)
        sg.capture(mesh, window_size=(n, n))

    fresh()  # untimed: numba, the first GL context, PyVista's theme
    plain()
    t_plain, t_fresh, t_again = [], [], []
    for _ in range(repeat):  # interleaved, so both see the same machine state
        t_plain.append(median_time(plain, 1, warm=0))
        t_fresh.append(median_time(fresh, 1, warm=0))
        t_again.append(median_time(lambda: sg.capture(mesh, window_size=(n, n)), 1, warm=0))
    p = statistics.median(t_plain)
    return {
        "capture/plain": statistics.median(t_fresh) / p,
        "re-capture/plain": statistics.median(t_again) / p,
        "capture s": statistics.median(t_fresh),
        "plain s": p,
    }


def case_live(quick: bool, repeat: int) -> dict[str, float]:
    """Orbit frames (render + screenshot) with the live edge overlay, per route, over plain."""
    import pyvista as pv

    import sciviz_gbuf  # noqa: F401  (registers pl.gbuf)

    mesh = pv.read(STL) if STL.is_file() else pv.ParametricRandomHills().triangulate()
    size = (640, 480) if quick else (1024, 768)
    frames = 5 if quick else 15

    def frame_time(source: str | None, enable: bool) -> float:
        pl = pv.Plotter(off_screen=True, window_size=size)
        pl.add_mesh(mesh)
        if enable:
            if source is None:
                pl.gbuf.enable_edge_enhancement()
            else:
                pl.gbuf.enable_edge_enhancement(source=source)
        pl.screenshot()
        t0 = time.perf_counter()
        for _ in range(frames):
            pl.camera.azimuth += 3.0
            pl.render()
            pl.screenshot()
        dt = (time.perf_counter() - t0) / frames
        pl.close()
        return dt

    out: dict[str, float] = {}
    plain = statistics.median(frame_time(None, False) for _ in range(repeat))
    out["plain frame s"] = plain
    for label, source in (("default", None), ("capture", "capture"), ("frame", "frame")):
        try:
            t = statistics.median(frame_time(source, True) for _ in range(repeat))
        except TypeError:  # a tree without the ``source`` option
            continue
        out[f"overlay {label}/plain"] = t / plain
    return out


def case_edge_map(quick: bool, repeat: int) -> dict[str, float]:
    """``edge_map`` of a 1024^2 G-buffer (the CAD part, or PyVista's hills)."""
    import pyvista as pv

    import sciviz_gbuf as sg

    mesh = pv.read(STL) if STL.is_file() else pv.ParametricRandomHills().triangulate()
    n = 512 if quick else 1024
    gb = sg.capture(mesh, window_size=(n, n))
    return {"edge_map s": median_time(lambda: sg.filters.edge_map(gb), repeat)}


def case_terrain_filters(quick: bool, repeat: int) -> dict[str, float]:
    """``contour_lines``, ``hillshade`` and ``sky_view`` (16 directions, 50 px) of a DEM."""
    import sciviz_gbuf as sg

    n = 1024 if quick else 2048
    z = fractal(n, 0.8)
    out = {
        "contour_lines s": median_time(lambda: sg.filters.contour_lines(z, interval=20.0), repeat),
        "hillshade s": median_time(lambda: sg.filters.hillshade(z, dx=10, dy=10), repeat),
    }
    sky = median_time(
        lambda: sg.filters.sky_view(z, dx=10, dy=10, directions=16, radius=500.0), repeat
    )
    out["sky_view s"] = sky
    out["sky_view MPix/s"] = n * n / sky / 1e6
    return out


def case_topo_map(quick: bool, repeat: int) -> dict[str, float]:
    """``topographic_map`` of a 2048^2 DEM, default (generalised) and exact contours."""
    import sciviz_gbuf as sg

    n = 1024 if quick else 2048
    out = {}
    for hurst, label in ((0.8, "smooth"), (0.6, "rugged")):
        z = fractal(n, hurst)
        for kind, extra in (("default", {}), ("exact", {"generalize": False})):
            try:
                out[f"topo map {label} {kind} s"] = median_time(
                    lambda z=z, extra=extra: sg.recipes.topographic_map(
                        z, interval=20.0, major_interval=100.0, **extra
                    ),
                    repeat,
                )
            except TypeError:  # a tree from before generalised maps (its default is exact)
                continue
    return out


def _process_time(cmd: list[str], repeat: int) -> float:
    def run() -> None:
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    return median_time(run, repeat)


def case_processes(quick: bool, repeat: int) -> dict[str, float]:
    """Whole processes: ``import sciviz_gbuf``, ``sciviz-gbuf topo`` of a 2048^2 GeoTIFF, the
    demo (numba's cache warm: the warm-up run fills it)."""
    sys.path.insert(0, str(HERE))
    from bench_terrain import make_dem

    py = sys.executable
    out = {"import s": _process_time([py, "-c", "import sciviz_gbuf"], repeat)}
    with tempfile.TemporaryDirectory() as tmp:
        dem = Path(tmp) / "dem.tif"
        make_dem(dem, 1024 if quick else 2048)
        topo = [py, "-m", "sciviz_gbuf", "topo", str(dem), "-o", str(Path(tmp) / "map.png")]
        out["cli topo s"] = _process_time(topo, repeat)
        demo = [py, "-m", "sciviz_gbuf", "demo", "-o", str(Path(tmp) / "demo")]
        out["demo s"] = _process_time(demo, max(1, repeat // 2))
    return out


CASES: dict[str, Callable[[bool, int], dict[str, float]]] = {
    "capture": case_capture,
    "live": case_live,
    "edge_map": case_edge_map,
    "terrain_filters": case_terrain_filters,
    "topo_map": case_topo_map,
    "processes": case_processes,
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("case", choices=sorted(CASES))
    ap.add_argument("--quick", action="store_true", help="smaller sizes (a minute a tree)")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
    print(json.dumps(CASES[args.case](args.quick, max(1, min(args.repeat, 50)))))


if __name__ == "__main__":
    main()
