"""``run_demo``: G-buffers of the bundled sample scenes as PNGs, ``.npz`` files and an HTML page.

Two scenes: PyVista's nut (iso view) and the Jacksboro fault DEM seen bird's-eye from the
south-east. Every channel of each G-buffer is written as a PNG, with a titled montage of all of
them. Then the edge figures of Saito & Takahashi (1990) on the nut: Fig. 3 (edge drawing from
the depth image) and Fig. 7 (edge enhancement, with the 2003 edge map); and their contour
figures, which need no capture: Fig. 5 (contour lines of s = xy, with the Fig. 4 line profiles),
Fig. 6 (curved hatching) and Fig. 11 (a plan-view topographic map of the DEM); the terrain
figures (Figs. 11-13), the medical figure (Fig. 14, on PyVista's segmented frog) and the surface
analysis figure (Fig. 15, two Bezier patches joined with C1 and with C2 continuity) and the NPR
styles (2003 §5: technical illustration, cartoon, hatching, a mirror; 1990 line drawings).
``index.html``
shows every image with a caption, the camera (of the captures) and the timings.
"""

from __future__ import annotations

import html
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

import numpy as np
import pyvista as pv

from .. import styles
from .._atomic import atomic_output
from ..compose import colorize, ids_to_rgb, montage, normals_to_rgb, with_colorbar, write_png
from ..core.capture import capture, check_window_size
from ..core.gbuffer import GBuffer
from ..datasets import (
    load_frog_body,
    load_frog_skeleton,
    load_jacksboro_dem,
    load_jacksboro_terrain,
    load_nut,
)
from ..errors import InputError, OutputError
from ..filters import lambert, profile_edges, suppress_zeroth_order
from ..recipes import CAPTIONS as EDGE_CAPTIONS
from ..recipes import (
    CONTOUR_CAPTIONS,
    birdseye_gbuffer,
    birdseye_panels,
    ct_gbuffer,
    ct_panels,
    ct_surface,
    ct_translucent,
    fig3_panels,
    fig5_panels,
    fig6_panels,
    fig7_panels,
    fig11_panels,
    named_view_camera,
    nut_camera,
    seam_patches,
    sumi_e,
    surface_analysis,
    surface_gbuffer,
    technical_drawing_image,
    terrain_birdseye_camera,
    topographic_map,
    write_panels,
)
from ..recipes.npr import MIRROR_CAMERA, mirror_scene
from ..styles.illustration import LIGHT, shade_image
from .warmup import numba_cache_is_cold, run_steps
from .warmup import start as start_warmup
from .warmup import stop as stop_warmup

__all__ = ["run_demo", "terrain_birdseye_camera"]

# One-line caption of each channel image; scalar channels are captioned where they are made.
CAPTIONS = {
    "depth": "depth: linear eye-space distance along the view axis (viridis, dark = near)",
    "sz": "sz: Saito's perspective depth d²/(w z) in pixels, larger = nearer (viridis)",
    "normal": "normal: eye-space unit normal, (x, y, z) in [-1, 1] shown as RGB in [0, 1]",
    "world_x": "world x: world x coordinate of the visible surface point (plasma)",
    "world_y": "world y: world y coordinate of the visible surface point (plasma)",
    "world_z": "world z: world z coordinate of the visible surface point (plasma)",
    "object_id": "object id: index of the dataset in the scene, one colour per id",
    "cell_id": "cell id: cell of the dataset, one hashed colour per cell",
    "mask": "mask: coverage, white where the scene covers the pixel",
}
# Largest size of the (square) contour figures, in pixels: 800 x 20 m pixels of the DEM still
# fit in it around the Fig. 11 map's centre.
CONTOUR_SIZE = 800


@dataclass
class _Scene:
    name: str
    title: str
    dataset: object
    camera: object = None
    scalars: tuple[str, ...] = ()
    # (azimuth, altitude) in degrees of a world-space sun for the shade; None: eye-space light
    sun: tuple[float, float] | None = None
    # Units of the colour bars: lengths (depth, world x, y), world z, the scalars.
    units: str = "scene units"
    z_units: str = "scene units"
    scalar_units: str = "data units"
    # Filled in by _write_scene, read by _write_index.
    images: list[tuple[str, Path]] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)
    npz: Path | None = None
    timings: dict[str, float] = field(default_factory=dict)
    gbuffer: GBuffer | None = None

    @property
    def shade_caption(self) -> str:
        light = (
            "light from the upper left of the view"
            if self.sun is None
            else f"sun at azimuth {self.sun[0]:g}°, altitude {self.sun[1]:g}° (GDAL convention)"
        )
        return f"sh: Lambert shade from the normals alone (Saito 1990 Fig. 9), {light}"


def _scenes(aspect: float) -> list[_Scene]:
    terrain = load_jacksboro_terrain(vert_exag=2.0)
    return [
        _Scene("nut", "PyVista nut, iso view", load_nut()),
        _Scene(
            "terrain",
            "Jacksboro fault DEM, bird's-eye view from the south-east (vertical exaggeration 2)",
            terrain,
            camera=terrain_birdseye_camera(terrain.bounds, aspect=aspect, points=terrain.points),
            scalars=("elevation",),
            sun=(315.0, 45.0),
            units="m",
            z_units="m, exaggerated 2x",
            scalar_units="m",
        ),
    ]


def _shade(g: GBuffer, scene: _Scene) -> np.ndarray:
    """Headlight-free shade: an upper-left eye-space light, or the scene's world-space sun."""
    if scene.sun is None:
        return lambert(g.normal, light=LIGHT, ambient=0.15)
    az, alt = np.radians(scene.sun)
    # GDAL's convention: azimuth clockwise from north (+y), altitude above the horizon
    sun = (np.sin(az) * np.cos(alt), np.cos(az) * np.cos(alt), np.sin(alt))
    return lambert(g.world_normal(), light=sun, ambient=0.0)


def _scalar_image(values: np.ndarray, cmap: str, label: str, **limits: float) -> np.ndarray:
    """A scalar channel through ``cmap`` with its colour bar (the range of its finite values,
    or ``limits`` vmin/vmax) labelled with what it measures and its unit."""
    finite = values[np.isfinite(values)]
    lo = float(limits.get("vmin", finite.min() if finite.size else 0.0))
    hi = float(limits.get("vmax", finite.max() if finite.size else 1.0))
    rgb = colorize(values, cmap=cmap, vmin=lo, vmax=max(lo, hi))
    return with_colorbar(rgb, cmap=cmap, vmin=lo, vmax=max(lo, hi), label=label)


def _channel_images(g: GBuffer, scene: _Scene) -> list[tuple[str, str, np.ndarray]]:
    """``(key, caption, image)`` of every channel of ``g``; scalar channels with a colour
    bar in their units."""
    u = scene.units
    out = [
        ("depth", CAPTIONS["depth"], _scalar_image(g.depth, "viridis", f"depth ({u})")),
        ("sz", CAPTIONS["sz"], _scalar_image(g.sz, "viridis", "sz = d^2/(w z) (px)")),
        ("normal", CAPTIONS["normal"], normals_to_rgb(g.normal)),
        (
            "shade",
            scene.shade_caption,
            _scalar_image(_shade(g, scene), "gray", "shade N·L (0 to 1)", vmin=0.0, vmax=1.0),
        ),
    ]
    for i, axis in enumerate("xyz"):
        key = f"world_{axis}"
        unit = scene.z_units if axis == "z" else u
        label = f"world {axis} ({unit})"
        out.append((key, CAPTIONS[key], _scalar_image(g.world[..., i], "plasma", label)))
    out += [
        ("object_id", CAPTIONS["object_id"], ids_to_rgb(g.object_id)),
        ("cell_id", CAPTIONS["cell_id"], ids_to_rgb(g.cell_id)),
        ("mask", CAPTIONS["mask"], g.mask),
    ]
    for name, values in g.scalars.items():
        if values.ndim == 2:  # multi-component arrays have no single colour map
            caption = f"scalars {name}: the point array {name!r} interpolated (terrain)"
            image = _scalar_image(values, "terrain", f"{name} ({scene.scalar_units})")
            out.append((f"scalars_{name}", caption, image))
    return out


def _write_scene(
    scene: _Scene, outdir: Path, window_size: tuple[int, int], progress_bar: bool
) -> None:
    t0 = time.perf_counter()
    g = capture(
        scene.dataset,
        window_size=window_size,
        camera=scene.camera,
        scalars=scene.scalars,
        progress_bar=progress_bar,
    )
    t1 = time.perf_counter()
    images = _channel_images(g, scene)
    for key, caption, image in images:
        path = write_png(outdir / f"{scene.name}_{key}.png", image)
        scene.images.append((caption, path))
    titles = [(caption.split(":")[0], image) for _, caption, image in images]
    path = write_png(outdir / f"{scene.name}_montage.png", montage(titles, columns=4))
    scene.images.append(("montage: all channels above, titled", path))
    t2 = time.perf_counter()
    scene.files = [p for _, p in scene.images]
    scene.npz = g.save(outdir / f"{scene.name}_gbuffer.npz")
    scene.files.append(scene.npz)
    scene.timings = {
        "capture": t1 - t0,
        "PNG images": t2 - t1,
        "G-buffer .npz": time.perf_counter() - t2,
    }
    scene.gbuffer = g


Panel = tuple[str, str, np.ndarray]


@dataclass
class _Figure:
    """One figure of the paper: its panels, made from its own capture of the nut (edge figures,
    ``supersample`` set; ``panels`` takes the G-buffer) or from nothing but the figure's own
    field or DEM grid (contour figures, ``supersample`` None; ``panels`` takes no argument)."""

    name: str
    title: str
    intro: str
    panels: Callable[..., list[Panel]]
    captions: Mapping[str, str]
    # Timing label of the panels' filters.
    stage: str
    supersample: int | None = None
    # Filled in by _write_figure, read by _write_index.
    images: list[tuple[str, Path]] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)
    gbuffer: GBuffer | None = None


LINEART_CAPTIONS = {
    "dashed": "technical drawing (sciviz_gbuf.recipes.technical_drawing): visible profiles and "
    "creases solid, the edges of the surfaces behind (capture(layers=4), hidden_edges) dashed; "
    "the same strokes `sciviz-gbuf edges nut.ply --hidden dashed -o nut.svg` writes as SVG",
    "thin": "the same with hidden lines thin and grey",
    "shaded": "visible edges as vector strokes (edge_strokes) over the Lambert shade: what "
    "`sciviz-gbuf edges ... --background shade -o out.pdf` writes",
}


def lineart_panels(window_size: tuple[int, int]) -> list[Panel]:
    """The nut as line art from a multi-layer G-buffer: hidden lines dashed and thin, and the
    visible edges as strokes over the shade (drawn as an SVG viewer draws them)."""
    nut = load_nut()
    gb = capture(nut, window_size=window_size, supersample=2, layers=4,
                 camera=nut_camera(nut.bounds, aspect=window_size[0] / window_size[1]))  # fmt: skip
    return [
        ("dashed", "hidden lines dashed", technical_drawing_image(gb, hidden="dashed")),
        ("thin", "hidden lines thin", technical_drawing_image(gb, hidden="thin")),
        ("shaded", "vector edges over the shade",
         technical_drawing_image(gb, hidden=None, background="shade")),
    ]  # fmt: skip


def _edge_figures() -> list[_Figure]:
    return [
        _Figure(
            "fig3",
            "Edges: Saito & Takahashi 1990 Fig. 3, edge drawing on the machine nut",
            "The paper's literal operators on the sz image (Eq. 1-4, k_g = 10, k_l = 2; the "
            "background is sz = 0, infinitely far), then the robust profile_edges and "
            "internal_edges. No supersampling: the operators work on single pixels.",
            fig3_panels,
            EDGE_CAPTIONS,
            "edge filters",
            supersample=1,
        ),
        _Figure(
            "fig7",
            "Edges: Saito & Takahashi 1990 Fig. 7, edge enhancement (and the 2003 edge map)",
            "A shaded image enhanced with white convex edges and black concave edges and "
            "profiles; then with black lines only; then with the RGBA edge map of Nienhaus & "
            "Döllner 2003. Captured 3x supersampled, lines 1.5 pixels wide, antialiased.",
            partial(fig7_panels, width=1.5),
            EDGE_CAPTIONS,
            "edge filters",
            supersample=3,
        ),
    ]


def _lineart_figures(window_size: tuple[int, int]) -> list[_Figure]:
    return [
        _Figure(
            "lineart",
            "Line art and hidden lines: vector strokes from G-buffers",
            "The nut captured with the three surfaces behind the visible one along every ray "
            "(capture(layers=4): the extended G-buffer of 1990 §5.1), its visible and hidden "
            "profiles and creases traced into strokes (vectorize) and drawn dashed, thin or "
            "over the shade. The SVG and PDF of the edges, mesh, patches and topo commands "
            "hold these strokes as vector paths.",
            partial(lineart_panels, window_size),
            LINEART_CAPTIONS,
            "capture of 4 layers, tracing and drawing",
        )
    ]


def _contour_figures(size: int) -> list[_Figure]:
    """The contour figures, ``size`` x ``size`` pixels each; no capture needed."""
    return [
        _Figure(
            "fig5",
            "Contours: Saito & Takahashi 1990 Fig. 5 (and Fig. 4), contour lines of s = xy",
            "Contour lines drawn per pixel from the value and its Eq. 9 gradient, without "
            "tracking (Eq. 7-15), lines 1.5 pixels wide: the flat centre fades to white "
            "(c_sparse = 0, Eq. 11), the crowded corners fill with c_dense (Eq. 15), black in "
            "(a), grey in (b). Then the three line profiles f1 of Fig. 4, zoomed 8x.",
            partial(fig5_panels, size),
            CONTOUR_CAPTIONS,
            "contour filters",
        ),
        _Figure(
            "fig6",
            "Contours: Saito & Takahashi 1990 Fig. 6, curved hatching of s = xy",
            "Regular contours crowd where the gradient is large and spread where it is small; "
            "curved hatching by binary thinning out (Eq. 17-21) keeps its lines about 6 pixels "
            "apart everywhere, with the filter's quick fade-in of the in-between lines and "
            "with Eq. 18 exactly.",
            partial(fig6_panels, size),
            CONTOUR_CAPTIONS,
            "hatching filters",
        ),
        _Figure(
            "fig11",
            "Contours: Saito & Takahashi 1990 Fig. 11, a topographic map of the Jacksboro DEM",
            "Plan view, north up, 20 m pixels; the DEM grid is the G-buffer (no rendering). "
            "100 m major contours 2 pixels wide never thin out; 20 m minor contours 1 pixel "
            "wide fade to white (c_dense = 0) where they come closer than 4 pixels, so only "
            "the majors remain on steep slopes. Relief shade from the grid's normals (sun "
            "azimuth 315°, altitude 45°), colour bands every 100 m, and their combination.",
            partial(fig11_panels, size),
            CONTOUR_CAPTIONS,
            "DEM loading, resampling and filters",
        ),
    ]


TERRAIN_CAPTIONS = {
    "topo": "topographic map (Fig. 11 mx3 on the DEM's own 3\" grid, sciviz-gbuf topo): colour "
    "bands every 200 m x GDAL-compatible relief with cast shadows, 200 m / 40 m contours "
    "(automatic: majors at least 6 px apart on the median slope)",
    "topo_labels": "the same map as a cartographer draws it (sciviz-gbuf topo --relief vat "
    "--labels --size 1200): RVT's VAT relief (hillshade, slope, openness, sky view) and the index "
    "contours' heights in the lines, their tops uphill, the lines broken under them",
    "cn": "(cn) bird's-eye contour image: contour lines of the true height in the G-buffer, "
    "constant width in pixels however far the ground",
    "pr": "(pr) profile image from sz: ridges drawn where they hide the ground behind them",
    "sh": "(sh) relief from the captured normals, sun azimuth 315°, altitude 45°",
    "mx2": "(mx2) combination of (pr) and (sh)",
    "mx4": "(mx4) combination of (pr), (cn), (sh) and colour bands (sciviz-gbuf birdseye)",
    "sumi_e": "Fig. 13 sumi-e from (cn) and (sz): ridge lines, contour strokes and a wash below "
    "the ridges, fading with distance and into the valleys",
}


def terrain_panels(window_size: tuple[int, int]) -> list[Panel]:
    """The terrain figures on the bundled Jacksboro DEM: the plan-view map, the 1990 Fig. 12
    bird's-eye panels (one capture) and the Fig. 13 sumi-e."""
    dem = load_jacksboro_dem()
    topo = topographic_map(dem, shadows=True)
    # the cartographer's map: every landform lit (RVT's VAT blend), index contours numbered
    labelled = topographic_map(dem, relief="vat", labels=True, size=1200)
    gb = birdseye_gbuffer(dem, window_size=window_size, vert_exag=2.0)
    bird = birdseye_panels(gb, background=(1.0, 1.0, 1.0))
    ink = sumi_e(dem, window_size=window_size, elevation_angle=15.0, vert_exag=2.5)
    titles = {"cn": "(cn) contour image", "pr": "(pr) profile image", "sh": "(sh) relief"}
    titles |= {"mx2": "(mx2) pr + sh", "mx4": "(mx4) pr + cn + sh + bands"}
    return [
        ("topo", "topographic map (plan view)", topo),
        ("topo_labels", "topographic map: VAT relief, contour labels reading uphill", labelled),
        *[(k, titles[k], bird[k]) for k in ("cn", "pr", "sh", "mx2", "mx4")],
        ("sumi_e", "Fig. 13 sumi-e", ink),
    ]


def _terrain_figures(window_size: tuple[int, int]) -> list[_Figure]:
    return [
        _Figure(
            "fig12",
            "Terrain: Saito & Takahashi 1990 Figs. 11-13 on the Jacksboro DEM",
            "A plan-view topographic map on the DEM's own grid (no rendering); then the terrain "
            "rendered once from the south-east (vertical exaggeration 2) and its G-buffer "
            "enhanced into the Fig. 12 bird's-eye maps; and a sumi-e from a lower view.",
            partial(terrain_panels, window_size),
            TERRAIN_CAPTIONS,
            "DEM reading, rendering and filters",
        )
    ]


MEDICAL_CAPTIONS = {
    "shaded": "(a) conventional shaded image: the skeleton's isosurface in bone colour, diffuse "
    "and specular light",
    "enhanced": "(b) enhanced image (sciviz_gbuf.ct_enhance): profiles, shading, contour lines of "
    "wx (every 6 voxels, head to tail) and colour bands of the depth axis wz (near warm, far cool)",
    "pr": "(pr) profiles from sz",
    "cn": "(cn) contour lines of the world coordinate wx: where each cross-section level meets "
    "the bone",
    "sh": "(sh) Lambert shade from the captured normals",
    "bands": "colour bands of wz, shaded",
    "translucent": "translucent skin (sciviz_gbuf.ct_translucent): the frog's body envelope at "
    "opacity 0.35 over its skeleton, both outlined: a multi-layer G-buffer (capture(layers=5)) "
    "composed front to back (compose.layered)",
}
#: The frog is seen from above its back, obliquely, head to the right.
FROG_VIEW = (0.0, -0.7, 1.0)


def medical_panels(window_size: tuple[int, int]) -> list[Panel]:
    """The 1990 Fig. 14 panels on PyVista's bundled frog: its skeleton label is surfaced (0.5
    isosurface of the smoothed label), rendered once and enhanced."""
    gb = ct_gbuffer(load_frog_skeleton(), iso=0.5, view=FROG_VIEW, window_size=window_size)
    layers = {"contour_axis": "x", "contour_interval": 6.0, "band_axis": "z"}
    panels = ct_panels(gb, background=(1.0, 1.0, 1.0), layer_options=layers)
    titles = {"shaded": "(a) conventional shaded", "enhanced": "(b) enhanced (Fig. 14)"}
    titles |= {"pr": "(pr) profiles", "cn": "(cn) contours of wx", "sh": "(sh) shade"}
    titles |= {"bands": "colour bands of wz"}
    out = [(k, titles[k], panels[k]) for k in titles]
    skin = ct_surface(load_frog_body(), iso=0.5, scalars="body")
    bone = ct_surface(load_frog_skeleton(), iso=0.5)
    translucent = ct_translucent(None, translucent=skin, inner=bone, view=FROG_VIEW,
                                 window_size=window_size, background=(1.0, 1.0, 1.0))  # fmt: skip
    return [*out, ("translucent", "translucent skin over the skeleton", translucent)]


def _medical_figures(window_size: tuple[int, int]) -> list[_Figure]:
    return [
        _Figure(
            "fig14",
            "Medical: Saito & Takahashi 1990 Fig. 14 on PyVista's segmented frog",
            "The skeleton label of pyvista.examples.load_frog_tissues() (an MRI segmentation: "
            "the bundled stand-in for a CT bone threshold) is smoothed and cut at 0.5 with "
            "flying edges, rendered once, and its G-buffer enhanced: profiles, shading, "
            "contour lines of one world coordinate and colour bands of another, beside the "
            "conventional shaded image. sciviz-gbuf ct does the same from a DICOM CT series.",
            partial(medical_panels, window_size),
            MEDICAL_CAPTIONS,
            "volume smoothing, isosurface, rendering and filters",
        )
    ]


SURFACE_CAPTIONS = {
    "a_contours": "(a) contour lines of height on the C1 surface (two bicubic patches joined "
    "along the middle)",
    "b_reflection_c1": "(b) pseudo-highlight pattern (reflection lines) on the C1, not C2, join: "
    "the lines turn sharply at the seam",
    "b_reflection_c2": "the same on a C2 join: the lines run on smoothly",
    "zebra_c1": "zebra stripes (the CAD tools' form of the pattern) on the C1 join",
    "zebra_c2": "zebra stripes on the C2 join",
    "curvature_c1": "analytic mean curvature, C1 join (diverging map symmetric about 0: blue "
    "negative, red positive, white flat; the sign follows the patch normal Su x Sv): it jumps "
    "at the seam",
    "curvature_c2": "analytic mean curvature, C2 join: continuous",
    "isophotes_c1": "isophotes (every 10 degrees of the light angle) on the C1 join",
}
#: Looking down on the seam surface; the seam runs up the middle of the picture.
SEAM_VIEW = ((1.0, -1.2, 4.0), (1.0, 0.75, 0.6), (0.0, 1.0, 0.0))


def _curvature_panel(gb: GBuffer, options: dict) -> np.ndarray:
    """A curvature panel with its colour bar: C1 and C2 share one fixed scale (the
    ``curvature_limit``), so their colours compare."""
    limit = float(options["curvature_limit"])
    image = surface_analysis(gb, mode="curvature", **options)
    label = f"mean curvature H (1 / patch units), clipped at ±{limit:g} in both panels"
    return with_colorbar(image, cmap="RdBu_r", vmin=-limit, vmax=limit, label=label)


def surface_panels(window_size: tuple[int, int]) -> list[Panel]:
    """The 1990 Fig. 15 panels on two bicubic patches built in code (C1 and C2 joins)."""
    opts = {"axis": (1.0, 0.4, 0.0), "stripes": 24, "background": (1.0, 1.0, 1.0)}
    gbs = {
        c: surface_gbuffer(seam_patches(c), view=SEAM_VIEW, window_size=window_size)
        for c in ("C1", "C2")
    }
    c1, c2 = gbs["C1"], gbs["C2"]
    curv = {"curvature": "mean", "curvature_limit": 1.5, "background": (1.0, 1.0, 1.0)}
    iso = opts | {"stripes": 36}  # a line every 10 degrees of the light angle
    return [
        ("a_contours", "(a) contour lines", surface_analysis(c1, mode="contours", **opts)),
        ("b_reflection_c1", "(b) reflection lines, C1", surface_analysis(c1, **opts)),
        ("b_reflection_c2", "reflection lines, C2", surface_analysis(c2, **opts)),
        ("zebra_c1", "zebra, C1", surface_analysis(c1, mode="stripes", **opts)),
        ("zebra_c2", "zebra, C2", surface_analysis(c2, mode="stripes", **opts)),
        ("curvature_c1", "mean curvature, C1", _curvature_panel(c1, curv)),
        ("curvature_c2", "mean curvature, C2", _curvature_panel(c2, curv)),
        ("isophotes_c1", "isophotes, C1", surface_analysis(c1, mode="isophote", **iso)),
    ]


def _surface_figures(window_size: tuple[int, int]) -> list[_Figure]:
    return [
        _Figure(
            "fig15",
            "Surface analysis: Saito & Takahashi 1990 Fig. 15, two bicubic patches",
            "Two bicubic Bezier patches joined along the middle with C1 (not C2) continuity, "
            "and for comparison with C2, tessellated with analytic normals and curvatures, "
            "rendered once each, then enhanced: contour lines of height, the pseudo-highlight "
            "pattern (reflections of parallel lights at infinity, axis (1, 0.4, 0), 24 per "
            "turn) as lines and as zebra stripes, the mean curvature and isophotes. The C1 "
            "join shows as a kink in every reflection line; the C2 join does not show.",
            partial(surface_panels, window_size),
            SURFACE_CAPTIONS,
            "tessellation, rendering and filters",
        )
    ]


NPR_CAPTIONS = {
    "gooch": "technical illustration (Gooch et al. 1998): warm-cool shading, inner edges white, "
    "profiles black via the 2003 edge map (Nienhaus & Döllner Fig. 7)",
    "toon": "cartoon shading (Lake et al. 2000): 3 shade levels by nearest lookup of N.L, black "
    "edges (2003 Fig. 9, left)",
    "toon_smooth": "the same with the transitions between the colour patches smoothed (the 2003 "
    "cartoon map, Fig. 9 right)",
    "hatch": "halftone hatching (Freudenberg et al. 2002): prioritised stroke families thicken "
    "smoothly with the shade, with profiles (2003 Fig. 8)",
    "lines_shuv": "1990 Fig. 9 (shuv): curved hatching of the torus's u and v, enhanced with the "
    "shade, with profiles",
    "hatch_uv": "hatching along the surface parameterisation (u, v) of two Bezier patches",
    "local": "local enhancement (1990 §5.2): the technical-illustration style on the nut only; "
    "the ball keeps the plain shade",
    "mirror": "an edge-enhanced planar mirror (2003 Fig. 8): the reflected nut and ball are "
    "rendered and enhanced from the reflected eye, so they have their own profiles",
}


def npr_panels(window_size: tuple[int, int]) -> list[Panel]:
    """NPR styles (2003 §5, 1990 §4.2, §5.2) on the nut, a torus and a mirrored scene."""
    w, h = window_size
    nut = load_nut()
    cam = named_view_camera(nut.points, "iso", aspect=w / h)
    gb = capture(nut, window_size=window_size, camera=cam, supersample=2)
    torus = pv.ParametricTorus(texture_coordinates=True)
    tcam = named_view_camera(torus.points, "iso", aspect=w / h)
    tgb = capture(torus, window_size=window_size, camera=tcam, supersample=2)
    sgb = capture(
        seam_patches("C2").to_mesh(resolution=48), window_size=window_size, camera=SEAM_VIEW,
        supersample=2,
    )  # fmt: skip
    centred = nut.translate([-c for c in nut.center])
    pair = [centred.translate((-22.0, 0.0, 0.0)), pv.Sphere(radius=12.0, center=(22.0, 0.0, 0.0))]
    pcam = named_view_camera(np.concatenate([d.points for d in pair]), "iso", aspect=w / h)
    pgb = capture(pair, window_size=window_size, camera=pcam, supersample=2)
    plain = np.repeat(shade_image(pgb)[..., None], 3, axis=2)
    panels = {
        "gooch": styles.gooch(gb),
        "toon": styles.toon(gb),
        "toon_smooth": styles.toon(gb, smooth=0.12),
        "hatch": styles.hatch(gb),
        "lines_shuv": styles.line_drawing(tgb, combo="shuv"),
        "hatch_uv": styles.hatch(sgb, space="uv"),
        "local": styles.local_style(styles.gooch(pgb), plain, pgb, ids=[0]),
        "mirror": styles.mirror_enhance(
            mirror_scene(), 0, camera=MIRROR_CAMERA, window_size=window_size
        ),
    }
    titles = {"gooch": "Gooch", "toon": "toon", "toon_smooth": "toon, smoothed"}
    titles |= {"hatch": "hatching", "lines_shuv": "(shuv) line drawing", "hatch_uv": "uv hatching"}
    titles |= {"local": "local (nut only)", "mirror": "mirror"}
    return [(k, titles[k], v) for k, v in panels.items()]


def _npr_figures(window_size: tuple[int, int]) -> list[_Figure]:
    return [
        _Figure(
            "npr",
            "NPR styles: Nienhaus & Döllner 2003 §5 (Figs. 7-9), Saito & Takahashi 1990 §4.2, §5.2",
            "Each scene is captured once (2x supersampled); every style is then a function of "
            "the G-buffer: technical illustration, cartoon shading with and without smoothed "
            "transitions, halftone hatching in screen space and along (u, v), the 1990 line "
            "drawing, a style applied to one object only, and a mirror whose reflected view "
            "has its own G-buffer and edges. sciviz-gbuf mesh FILE --style gooch|toon|hatch|"
            "lines does the same for any mesh file.",
            partial(npr_panels, window_size),
            NPR_CAPTIONS,
            "captures and styles",
        )
    ]


def _write_figure(
    fig: _Figure, outdir: Path, window_size: tuple[int, int], progress_bar: bool
) -> None:
    t0 = time.perf_counter()
    args: tuple[GBuffer, ...] = ()
    if fig.supersample is not None:  # an edge figure: its own capture of the nut
        nut = load_nut()
        fig.gbuffer = capture(
            nut,
            window_size=window_size,
            camera=nut_camera(nut.bounds, aspect=window_size[0] / window_size[1]),
            supersample=fig.supersample,
            progress_bar=progress_bar,
        )
        args = (fig.gbuffer,)
    t1 = time.perf_counter()
    panels = fig.panels(*args)
    t2 = time.perf_counter()
    *paths, path = write_panels(outdir, fig.name, panels, columns=4)
    fig.images = [(fig.captions[key], p) for (key, _, _), p in zip(panels, paths, strict=True)]
    fig.images.append(("montage: all panels above, titled as in the paper", path))
    fig.timings = {} if fig.gbuffer is None else {"capture": t1 - t0}
    fig.timings |= {fig.stage: t2 - t1, "PNG images": time.perf_counter() - t2}


def _camera_text(g: GBuffer) -> list[str]:
    c = g.camera

    def vec(v: tuple[float, ...]) -> str:
        return "(" + ", ".join(f"{x:.6g}" for x in v) + ")"

    angle = (
        f"parallel scale {c.parallel_scale:.6g}"
        if c.parallel_projection
        else f"view angle {c.view_angle:.6g}°"
    )
    return [
        f"position {vec(c.position)}, focal point {vec(c.focal_point)}, view up {vec(c.view_up)}",
        f"{angle}, clipping range {vec(c.clipping_range)}, "
        f"window {c.window_size[0]}x{c.window_size[1]} px, "
        f"pixel size at the focal plane {c.pixel_size:.6g}",
    ]


_STYLE = (
    "body{font-family:sans-serif;margin:0;color:#222}"
    "nav{position:sticky;top:0;z-index:1;background:#f6f6f6;border-bottom:1px solid #ccc;"
    "padding:.5em 1em;font-size:90%;line-height:1.8}"
    "nav a{margin-right:1em;white-space:nowrap}"
    "main{padding:0 1.5em 2em;max-width:100%;box-sizing:border-box}"
    "section{scroll-margin-top:5em}"
    ".grid{display:grid;grid-template-columns:repeat(auto-fill,minmax(230px,1fr));gap:14px}"
    "figure{margin:0}figure img{width:100%;height:auto;border:1px solid #ccc;display:block}"
    "figcaption{font-size:85%;margin-top:.3em}details{margin:.5em 0 1em;font-size:90%}"
    "p.intro{max-width:60em}"
)


def _section_id(name: str) -> str:
    return "s-" + "".join(c if c.isalnum() else "-" for c in name)


def _details(lines: list[str]) -> str:
    esc = html.escape
    body = "<br>".join(esc(line) for line in lines)
    return f"<details><summary>capture, camera and timings</summary>{body}</details>"


def _scene_html(scene: _Scene) -> str:
    assert scene.gbuffer is not None and scene.npz is not None
    esc = html.escape
    npz = scene.npz.name
    timing = ", ".join(f"{k} {v:.2f} s" for k, v in scene.timings.items())
    lines = [repr(scene.gbuffer), "Camera:", *_camera_text(scene.gbuffer), f"Timings: {timing}"]
    parts = [
        f'<section id="{_section_id(scene.name)}"><h2>{esc(scene.title)}</h2>',
        f'<p>G-buffer: <a href="{esc(npz)}">{esc(npz)}</a> (GBuffer.load)</p>',
        _details(lines),
    ]
    return "\n".join([*parts, _grid_html(scene.images), "</section>"])


def _grid_html(images: list[tuple[str, Path]]) -> str:
    """Thumbnails in a grid, each a link to its full-size PNG, captioned."""
    esc = html.escape
    items = [
        f'<figure><a href="{esc(path.name)}"><img src="{esc(path.name)}" alt="{esc(caption)}" '
        f'loading="lazy"></a><figcaption>{esc(caption)}</figcaption></figure>'
        for caption, path in images
    ]
    return '<div class="grid">\n' + "\n".join(items) + "\n</div>"


def _figure_html(fig: _Figure) -> str:
    esc = html.escape
    timing = ", ".join(f"{k} {v:.2f} s" for k, v in fig.timings.items())
    lines = [] if fig.gbuffer is None else [repr(fig.gbuffer), "Camera:"]
    if fig.gbuffer is not None:
        lines += _camera_text(fig.gbuffer)
    lines.append(f"Timings: {timing}")
    parts = [
        f'<section id="{_section_id(fig.name)}"><h2>{esc(fig.title)}</h2>',
        f'<p class="intro">{esc(fig.intro)}</p>',
        _details(lines),
    ]
    return "\n".join([*parts, _grid_html(fig.images), "</section>"])


def _nav_html(scenes: list[_Scene], figures: list[_Figure]) -> str:
    esc = html.escape
    links = [(s.name, s.title.split(",")[0]) for s in scenes]
    for f in figures:  # "fig3" + "Edges: ..." -> "Fig. 3 edges"
        topic = f.title.split(":")[0]
        label = f"Fig. {f.name[3:]} {topic.lower()}" if f.name[3:].isdigit() else topic
        links.append((f.name, label))
    items = " ".join(f'<a href="#{_section_id(n)}">{esc(t)}</a>' for n, t in links)
    return f"<nav>{items}</nav>"


def _write_index(scenes: list[_Scene], figures: list[_Figure], outdir: Path) -> Path:
    body = "\n".join([_scene_html(s) for s in scenes] + [_figure_html(f) for f in figures])
    page = (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f"<title>sciviz_gbuf demo</title><style>{_STYLE}</style></head><body>\n"
        f"{_nav_html(scenes, figures)}\n<main>\n"
        "<h1>sciviz_gbuf demo: G-buffers, edges and contours of bundled sample data</h1>\n"
        "<p>Click a picture for its full-size PNG. Scalar channels carry a colour bar in their "
        "units.</p>\n"
        f"{body}\n</main></body></html>\n"
    )
    path = outdir / "index.html"
    data = page.encode("utf-8")
    with atomic_output(path) as part:  # a page cut short by a full disk is not left behind
        part.expected_size = part.path.write_bytes(data)
    return path


def _steps(width: int, height: int) -> list[tuple[str, Callable, object]]:
    """The demo's steps in the order a run takes them: ``(title, writer, scene or figure)``.

    The gallery page lists them in the papers' order (:func:`_page_order`); a run takes the
    contour figures before the edge figures and the terrain figures after the medical and
    surface ones. On a first run that keeps the two processes from compiling the same kernels:
    the second one (:func:`_warm`) goes backwards and starts with the NPR styles, whose first
    kernel is the edge pass (the longest compile), while this one compiles the contour and
    operator kernels; the terrain kernels are then the second process's next ones.
    """
    size = (width, height)
    scenes = _scenes(width / height)
    groups = [
        _contour_figures(max(16, min(width, height, CONTOUR_SIZE))),
        _edge_figures(),
        _lineart_figures(size),
        _medical_figures(size),
        _surface_figures(size),
        _terrain_figures(size),
        _npr_figures(size),
    ]
    steps: list[tuple[str, Callable, object]] = [(sc.title, _write_scene, sc) for sc in scenes]
    return steps + [(fig.title, _write_figure, fig) for group in groups for fig in group]


#: The papers' order of the figure groups on the gallery page (title prefixes).
_PAGE_GROUPS = ("Edges", "Contours", "Terrain", "Medical", "Surface analysis", "NPR styles")


def _page_order(figures: list[_Figure]) -> list[_Figure]:
    """The figures as the gallery lists them: edges, contours, terrain, medical, surface
    analysis, NPR (a group's own figures in the order they ran)."""

    def group(fig: _Figure) -> int:
        topic = fig.title.split(":")[0]
        return _PAGE_GROUPS.index(topic) if topic in _PAGE_GROUPS else len(_PAGE_GROUPS)

    return sorted(figures, key=group)


#: Window size of the second process's steps (:mod:`.warmup`): small, so that compiling is
#: nearly all it does, and large enough for every figure's code path.
WARMUP_SIZE = (160, 120)


def _edge_lines_first() -> None:
    """The profile lines of a small capture: the edge pass and the line cleaning, the longest
    compile of a first run (about 15 s), which every figure after the contour ones needs; then
    Eq. 4's operator, the last of the four that Fig. 3 (the run's first edge figure) compiles
    while this process is busy with the edge pass."""
    gb = capture(load_nut(), window_size=WARMUP_SIZE)
    profile_edges(gb)
    img = np.zeros(gb.shape, dtype=np.float32)
    suppress_zeroth_order(img, img, k_l=2.0)


def _warm() -> None:
    """The second process of a first run (``python -m sciviz_gbuf.apps.demo --warmup``): the
    edge pass (:func:`_edge_lines_first`), then the demo's steps at :data:`WARMUP_SIZE` in
    reverse order, into a folder that is then removed."""
    import tempfile

    with tempfile.TemporaryDirectory(prefix="sciviz_gbuf_warmup_") as tmp:
        out = Path(tmp)
        steps = _steps(*WARMUP_SIZE)[::-1]
        figures = [partial(write, item, out, WARMUP_SIZE, False) for _, write, item in steps]
        run_steps(iter([_edge_lines_first, *figures]))


#: Smallest ``window_size`` of the demo: below it the figures' panels and labels are specks.
MIN_WINDOW = (160, 120)


def run_demo(
    outdir: str | Path = "sciviz_gbuf_demo",
    *,
    window_size: tuple[int, int] = (800, 600),
    progress_bar: bool = False,
    report: Callable[[str], None] | None = None,
) -> list[Path]:
    """Capture the sample scenes; write their channels, G-buffers, the paper's edge and contour
    figures and a gallery page.

    Parameters
    ----------
    outdir : str or path-like, default: "sciviz_gbuf_demo"
        Directory to write into (created if missing, and removed again if the run stops
        before its first file); nothing is written elsewhere.
    window_size : (int, int), default: (800, 600)
        ``(width, height)`` of the captures, of each channel image and of the edge figures, at
        least :data:`MIN_WINDOW` (160x120). The
        contour figures are square, ``min(width, height, 800)`` pixels across (at least 16).
    progress_bar : bool, default: False
        Show a progress bar for each capture.
    report : callable, optional
        Called with one line of text as each scene and figure starts and ends (which one, how
        long it took, and on a first run that the kernels compile): the command line prints
        them on a terminal.

    Returns
    -------
    list of pathlib.Path
        Every file written: per scene one PNG per channel, a montage PNG and the G-buffer
        ``.npz``; then one PNG per panel of the 1990 Fig. 3 and Fig. 7 edge figures and of the
        Fig. 5, Fig. 6 and Fig. 11 contour figures and of the terrain figures (a topographic
        map, the Fig. 12 bird's-eye maps, the Fig. 13 sumi-e) and of the Fig. 14 medical
        figure (the frog's skeleton), the Fig. 15 surface analysis and the NPR styles, with a
        montage each
        (``fig<n>_<key>.png``, ``fig<n>_montage.png``); finally ``index.html``.
    """
    width, height = check_window_size(window_size)
    if width < MIN_WINDOW[0] or height < MIN_WINDOW[1]:
        raise InputError(
            f"window_size: the demo's figures need at least {MIN_WINDOW[0]}x{MIN_WINDOW[1]} "
            f"pixels, got {width}x{height}"
        )
    out = Path(outdir)
    if out.exists() and not out.is_dir():
        raise InputError(f"output: {str(out)!r} is a file; expected a folder (new or existing)")
    made = not out.exists()
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"output: cannot make the folder {str(out)!r}: {exc.strerror}") from None
    try:
        return _run_steps(out, width, height, progress_bar, report)
    except BaseException:
        # stopped (Ctrl-C, SIGTERM, an error) before its first file: leave no empty folder
        if made and out.is_dir() and not any(out.iterdir()):
            out.rmdir()
        raise


def _run_steps(
    out: Path,
    width: int,
    height: int,
    progress_bar: bool,
    report: Callable[[str], None] | None,
) -> list[Path]:
    """:func:`run_demo`'s work in the folder ``out`` (made)."""
    say = report if report is not None else (lambda _line: None)
    second = None
    if numba_cache_is_cold():
        say(
            "first run: the numba kernels compile as each figure first needs them (on both "
            "cores) and are cached for later runs (those take a fraction of the time)"
        )
        second = start_warmup(["sciviz_gbuf.apps.demo", "--warmup"])
    try:
        steps = _steps(width, height)
        t_all = time.perf_counter()
        for k, (title, write, item) in enumerate(steps, 1):
            t0 = time.perf_counter()
            say(f"[{k}/{len(steps)}] {title} ...")
            write(item, out, (width, height), progress_bar)
            say(f"[{k}/{len(steps)}] {title}: {time.perf_counter() - t0:.1f} s "
                f"({time.perf_counter() - t_all:.0f} s in all)")  # fmt: skip
    finally:
        stop_warmup(second)
    scenes = [item for _, write, item in steps if write is _write_scene]
    figures = _page_order([item for _, write, item in steps if write is _write_figure])
    files = [p for s in scenes for p in s.files] + [p for f in figures for _, p in f.images]
    return [*files, _write_index(scenes, figures, out)]


if __name__ == "__main__":
    import sys

    if sys.argv[1:] == ["--warmup"]:
        _warm()
