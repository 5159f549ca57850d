"""Compile the numba kernels of a first run on the other core.

numba compiles each kernel the first time it is called, on one core, and caches it; on a
fresh machine that compile is most of a first ``sciviz-gbuf demo`` or ``topo``. When the
cache is cold, a job starts a second Python process (:func:`start`) that runs the same steps
on tiny inputs in the *reverse* order, so the two processes compile different kernels at the
same time and each finds in the cache what the other already compiled. Results of the second
process are thrown away; if it fails or is slow, the job only compiles those kernels itself.
Nothing here changes what a job computes.

``python -m sciviz_gbuf.apps.warmup JOB`` runs the steps of ``JOB`` (:data:`JOBS`); the demo
runs its own (``python -m sciviz_gbuf.apps.demo --warmup``). ``SCIVIZ_GBUF_NO_WARMUP=1``
turns the second process off.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import warnings
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path

__all__ = [
    "COLD_MARKERS",
    "JOBS",
    "main",
    "numba_cache_is_cold",
    "preload_map",
    "run_steps",
    "start",
    "stop",
]


#: The kernel whose cache index tells a first run, per job: one that every run of it calls.
COLD_MARKERS = {
    "demo": "_edge_kernels._edge_pass_tasks",
    "all": "_edge_kernels._edge_pass_tasks",
    "topo": "_stencil_kernels._k_contour",
}


def numba_cache_is_cold(job: str = "demo") -> bool:
    """True if the numba kernels of ``job`` are not in numba's cache yet (a first run: they
    compile as they are first called). Looks for the cache index of the kernel
    :data:`COLD_MARKERS` names for the job where numba keeps it: under ``NUMBA_CACHE_DIR`` if
    set, else beside the module (``__pycache__``)."""
    pattern = f"*{COLD_MARKERS[job]}-*.nbi"
    root = os.environ.get("NUMBA_CACHE_DIR")
    if root:
        return not any(Path(root).rglob(pattern))
    here = Path(__file__).resolve().parents[1] / "filters" / "__pycache__"
    return not any(here.glob(pattern))


def start(argv: Sequence[str], job: str = "demo") -> subprocess.Popen | None:
    """Start ``python -m <argv...>`` as the second process, if the cache of ``job`` is cold.

    Parameters
    ----------
    argv : sequence of str
        Module and arguments, e.g. ``["sciviz_gbuf.apps.warmup", "topo"]``.
    job : str, default: "demo"
        The job (a key of :data:`COLD_MARKERS`) whose kernels must still compile.

    Returns
    -------
    subprocess.Popen or None
        The process (pass it to :func:`stop` when the job ends), or None when the cache is
        warm, ``SCIVIZ_GBUF_NO_WARMUP`` is set or the machine has one core.
    """
    if os.environ.get("SCIVIZ_GBUF_NO_WARMUP"):
        return None
    if (os.cpu_count() or 1) < 2:
        return None  # on one core a second compiler only competes with the job
    if not numba_cache_is_cold(job):
        return None
    try:
        return subprocess.Popen(
            [sys.executable, "-m", *argv],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            # One thread: its kernels run on tiny inputs, and the job needs the other core.
            env={**os.environ, "NUMBA_NUM_THREADS": "1", "SCIVIZ_GBUF_NO_WARMUP": "1"},
        )
    except OSError:
        return None


def stop(proc: subprocess.Popen | None) -> None:
    """End the second process (a job that is done needs none of what it still compiles).

    numba writes each cache file under a temporary name and renames it, so a kill leaves no
    partial entry."""
    if proc is None or proc.poll() is not None:
        return
    proc.kill()
    proc.wait()


def preload_map(**options: object) -> threading.Thread:
    """Start a thread that maps a tiny grid with a map's ``options`` (those of
    :func:`~sciviz_gbuf.recipes.terrain.topographic_map` that choose its kernels): numba
    loads each kernel the map will call from its cache (or compiles it) while the job reads
    its DEM, which waits for the disk and GDAL without holding the GIL. The job joins the
    thread before it maps; an error here only leaves a kernel for the job to load."""

    def run() -> None:
        import numpy as np

        from ..recipes.terrain import topographic_map

        ramp = np.add.outer(np.arange(40), np.arange(48)) * 2.0
        z = ramp.astype(np.float32)
        z[3:6, 4:9] = np.nan
        # no warnings.catch_warnings here: its filters are the process's, and the reader's
        # warnings on the other thread must still show (the tiny ramp raises none)
        try:
            topographic_map(z, **options)
        except Exception:
            return

    thread = threading.Thread(target=run, name="sciviz_gbuf_preload", daemon=True)
    thread.start()
    return thread


def _topo_steps() -> Iterator[Callable[[], object]]:
    """``sciviz-gbuf topo``'s kernels, those a map needs last first: the job compiles the
    contour kernel as its first step, so this process starts with relief and bands."""
    import numpy as np

    from ..recipes.terrain import topographic_map

    rng = np.random.default_rng(0)
    ramp = np.add.outer(np.arange(48), np.arange(64)) * 2.0 + rng.random((48, 64))
    z = ramp.astype(np.float32)
    z[3:6, 4:9] = np.nan
    yield lambda: topographic_map(z, contours=False)
    yield lambda: topographic_map(z)


def _all_steps() -> Iterator[Callable[[], object]]:
    """Every public filter and style on tiny inputs (what the test suite calls), roughly in
    the reverse order of the test files."""
    import numpy as np
    import pyvista as pv

    from .. import filters, styles
    from ..core.capture import capture
    from ..recipes.terrain import topographic_map

    rng = np.random.default_rng(0)
    z = (rng.random((40, 50)) * 50).astype(np.float32)
    z[3:6, 4:9] = np.nan
    sphere = pv.Sphere(theta_resolution=24, phi_resolution=24)
    sphere.texture_map_to_sphere(inplace=True)
    g2 = capture(sphere, window_size=(48, 36), supersample=2)
    g1 = capture([sphere, pv.Cube(center=(1, 0, 0))], window_size=(48, 36))

    yield lambda: (styles.gooch(g2), styles.toon(g2, smooth=0.1), styles.toon(g1))
    yield lambda: (styles.hatch(g2), styles.hatch(g2, space="uv"))
    yield lambda: (styles.line_drawing(g2, combo="shuv"), styles.photocopy(g1.depth, copies=2))
    yield lambda: (filters.reflection_lines(g2), filters.isophotes(g2, interval=10.0))
    yield lambda: filters.highlight_lines(g1)
    yield lambda: (filters.edge_map(g2), filters.edge_map(g1, operator="c1"))
    yield lambda: (filters.profile_edges(g1), filters.internal_edges(g1), filters.id_edges(g1))
    yield lambda: filters.crease_edges(g2)
    yield lambda: (filters.sky_view(z), filters.cast_shadows(z, sun_radius=0.3))
    yield lambda: (filters.cast_shadows(z), filters.cast_shadows(z, azimuth=290.0))
    yield lambda: (filters.openness(z), topographic_map(z, relief="vat", labels=True))
    yield lambda: topographic_map(z, sky_view=True)
    yield lambda: (filters.color_bands(z, interval=5.0), filters.hillshade(z))
    yield lambda: filters.hatching(z, spacing=4.0)
    yield lambda: filters.contour_lines(z, levels=[10.0, 20.0])
    yield lambda: filters.contour_lines(z, interval=5.0, major_interval=25.0)
    yield lambda: filters.diagonal_normal_discontinuity(g1.normal)
    for name in (
        "suppress_zeroth_order",
        "normalize_gradient",
        "diagonal_depth_discontinuity",
        "c1_discontinuity",
        "second_order",
        "sobel_gradient",
    ):
        func = getattr(filters, name)
        yield (lambda f=func: f(z, z)) if name == "suppress_zeroth_order" else (lambda f=func: f(z))


#: The jobs ``python -m sciviz_gbuf.apps.warmup`` knows, and their steps.
JOBS: dict[str, Callable[[], Iterator[Callable[[], object]]]] = {
    "topo": _topo_steps,
    "all": _all_steps,
}


def run_steps(steps: Iterator[Callable[[], object]]) -> None:
    """Run each step, ignoring its result and any error (a step that fails compiles nothing,
    and the job then compiles that kernel itself)."""
    warnings.simplefilter("ignore")
    try:
        for step in steps:
            try:
                step()
            except Exception:
                continue
    except Exception:
        return


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m sciviz_gbuf.apps.warmup JOB``: run the steps of ``JOB``."""
    args = list(sys.argv[1:] if argv is None else argv)
    if len(args) != 1 or args[0] not in JOBS:
        print(f"usage: python -m sciviz_gbuf.apps.warmup {{{','.join(JOBS)}}}", file=sys.stderr)
        return 2
    run_steps(JOBS[args[0]]())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
