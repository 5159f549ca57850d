"""Compile (and cache) the package's numba kernels in a second process while the suite runs.

On a fresh clone numba compiles every kernel once, single-threaded, which is most of a cold
test run; this script, started by ``conftest.py``, does that work on the other core. It calls
the public functions on tiny inputs, roughly in the reverse order of the test files, so the
suite mostly finds kernels already cached instead of compiling the same ones at the same time.
Results are discarded; a failure here only means the suite compiles that kernel itself.
"""

from __future__ import annotations

import warnings


def _steps():
    import numpy as np
    import pyvista as pv

    import sciviz_gbuf as sg
    from sciviz_gbuf import filters, styles
    from sciviz_gbuf.recipes.terrain import topographic_map

    rng = np.random.default_rng(0)
    z = (rng.random((40, 50)) * 50).astype(np.float32)
    z[3:6, 4:9] = np.nan
    sphere = pv.Sphere(theta_resolution=24, phi_resolution=24)
    sphere.texture_map_to_sphere(inplace=True)
    g2 = sg.capture(sphere, window_size=(48, 36), supersample=2)
    g1 = sg.capture([sphere, pv.Cube(center=(1, 0, 0))], window_size=(48, 36))

    yield lambda: (styles.gooch(g2), styles.toon(g2, smooth=0.1), styles.toon(g1))
    yield lambda: (styles.hatch(g2), styles.hatch(g2, space="uv"))
    yield lambda: (styles.line_drawing(g2, combo="shuv"), styles.photocopy(g1.depth, copies=2))
    yield lambda: (filters.reflection_lines(g2), filters.isophotes(g2, interval=10.0))
    yield lambda: filters.highlight_lines(g1)
    yield lambda: (filters.edge_map(g2), filters.edge_map(g1, operator="c1"))
    yield lambda: (filters.profile_edges(g1), filters.internal_edges(g1), filters.id_edges(g1))
    yield lambda: filters.crease_edges(g2)
    yield lambda: (filters.sky_view(z), filters.cast_shadows(z, sun_radius=0.3))
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


def main() -> None:
    warnings.simplefilter("ignore")
    try:
        for step in _steps():
            try:
                step()
            except Exception:
                continue
    except Exception:
        return


if __name__ == "__main__":
    main()
