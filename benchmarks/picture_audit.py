"""Picture audit: measurable defects of every demo figure and of the maps of every shared DEM.

For each PNG of a demo run (``sciviz-gbuf demo``; run here into a temporary folder unless
``--demo DIR`` names one) it prints, in one markdown table:

- ``specks/1000``: isolated ink components (8-connected groups of dark pixels of at most
  ``--speck`` = 4 px) per 1000 ink pixels. Ink is luminance < 0.45 on the picture's own
  background with hysteresis (the pixels darker than 0.6 joined to it: a brown line whose
  antialiased luminance hovers about 0.45 over bright bands is one line, not dots), so a line
  drawing's stray dots and a map's contour speckle both count (the maps' contour specks proper
  are measured below, without bands and relief). Under 300 ink px there is no rate (``-``: a
  few dark pixels of a colour-mapped G-buffer make no speckle figure). A colour bar strip
  below the picture (``compose.with_colorbar``, found by its black frame) is cut off first:
  its tick labels are text, not specks. (A black top-hat, ink as what is thin and dark, was
  tried: it breaks outlines that run beside dark faces into false specks.)
- ``black %``: the largest solid-black area (8-connected content pixels of luminance < 0.1,
  after an opening of 3x3 so that lines and outlines do not count) as a percentage of the
  content pixels.
- ``empty %``: the share of the limiting image dimension that the content's bounding box
  leaves empty (``1 - max(box_w / W, box_h / H)``): 8 % to 25 % is the framing rule's range.
  Content is every pixel that differs from the background colour (the most common colour of
  the image border) by more than 0.08 in some channel.
- ``off-centre %``: the distance of that box's centre from the image centre, as a percentage
  of the image's diagonal.

Then, for every DEM in ``../shared/data/dem``: the plan-view map's contour ink with default
options (``topographic_map(dem, bands=False, relief=False)``: isolated components of at most
6 px per 1000 ink px) and, at a fixed interval per DEM, the ink's line position against real
``gdal_contour`` lines: the share of ink pixels within 1 px of a GDAL line (precision) and of
GDAL line samples within 1 px of ink (recall), where the slope is more than 2 px per interval.

    python benchmarks/picture_audit.py                      # demo (about 2 minutes) + maps
    python benchmarks/picture_audit.py --demo /tmp/demo     # an existing demo folder

Timings are not measured here. LOOK at the pictures too: numbers catch specks, blobs and
empty frames, not every defect.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np
from PIL import Image
from scipy import ndimage
from scipy.spatial import cKDTree

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the tests' helpers: gdal_contour's lines, the same reference
from tests.helpers.gdal_contour import gdal_samples  # noqa: E402

SHARED = ROOT.parent / "shared" / "data" / "dem"
# A fixed contour interval per DEM for the comparison with gdal_contour (lines a few px apart).
GDAL_INTERVALS = {
    "hugo_site.asc": 10.0,
    "pre_runout_DEM.asc": 20.0,
    "SRTMGL3_40.09_-105.55_40.21_-105.35.asc": 100.0,
    "N10W110.hgt": 1.0,
}
EIGHT = np.ones((3, 3), bool)
#: Fewest ink pixels for a speck rate.
MIN_INK = 300


def load_rgb(path: Path) -> np.ndarray:
    """(H, W, 3) float in [0, 1], an alpha channel composited on white."""
    with Image.open(path) as im:
        a = np.asarray(im.convert("RGBA"), dtype=np.float64) / 255.0
    return a[..., :3] * a[..., 3:] + (1.0 - a[..., 3:])


def luminance(rgb: np.ndarray) -> np.ndarray:
    return rgb @ np.array([0.2126, 0.7152, 0.0722])


def background(rgb: np.ndarray) -> np.ndarray:
    """The most common colour of the image's border pixels."""
    border = np.concatenate([rgb[0], rgb[-1], rgb[:, 0], rgb[:, -1]])
    q = np.round(border * 255).astype(np.int64)
    keys, counts = np.unique(q[:, 0] * 65536 + q[:, 1] * 256 + q[:, 2], return_counts=True)
    k = keys[np.argmax(counts)]
    return np.array([k // 65536, (k // 256) % 256, k % 256], float) / 255.0


def specks(ink: np.ndarray, most: int) -> tuple[int, float]:
    """(ink pixels, isolated components of at most ``most`` px per 1000 ink pixels)."""
    n = int(ink.sum())
    if n == 0:
        return 0, 0.0
    labels, _ = ndimage.label(ink, structure=EIGHT)
    sizes = np.bincount(labels.ravel())[1:]
    return n, 1000.0 * float(np.sum(sizes <= most)) / n


def without_colorbar(rgb: np.ndarray) -> tuple[np.ndarray, bool]:
    """``rgb`` without the colour bar strip of ``compose.with_colorbar`` below it (found by the
    top edge of the bar's black frame: a row of the lowest quarter that is dark over at least
    80 % of the width), and whether there was one."""
    h, w = rgb.shape[:2]
    dark = luminance(rgb) < 0.2
    for y in range(h - 1, h - h // 4 - 1, -1):
        if dark[y].sum() >= 0.8 * w and y + 1 < h and not dark[y + 1].sum() >= 0.8 * w:
            # the frame's bottom edge was seen first: go on to its top edge
            top = y
            while top - 1 >= 0 and not dark[top - 1].sum() >= 0.8 * w and top > y - h // 8:
                top -= 1
            if top - 1 >= 0 and dark[top - 1].sum() >= 0.8 * w:
                return rgb[: max(1, top - 1 - 2)], True  # the frame is 2 rows below
            return rgb, False
    return rgb, False


def audit_png(path: Path, speck: int) -> dict[str, float]:
    rgb, _ = without_colorbar(load_rgb(path))
    h, w = rgb.shape[:2]
    bg = background(rgb)
    content = np.abs(rgb - bg).max(axis=2) > 0.08
    lum = luminance(rgb)
    # hysteresis: dark pixels (< 0.45) and the pixels darker than 0.6 joined to them, so an
    # antialiased line whose luminance hovers about 0.45 (brown lines over bright bands) is one
    # line, not a row of dots
    low = content & (lum < 0.6)
    labels, _ = ndimage.label(low, structure=EIGHT)
    keep = np.zeros(labels.max() + 1, bool)
    keep[np.unique(labels[low & (lum < 0.45)])] = True
    keep[0] = False
    ink = keep[labels]
    n_ink, per_k = specks(ink, speck)
    # only content: a black background (depth, mask images) is not a black blob
    black = ndimage.binary_opening(content & (lum < 0.1), structure=np.ones((3, 3), bool))
    largest = 0
    if black.any():
        labels, _ = ndimage.label(black, structure=EIGHT)
        largest = int(np.bincount(labels.ravel())[1:].max())
    n_content = int(content.sum())
    if n_content:
        rows, cols = np.nonzero(content)
        bh, bw = rows.max() - rows.min() + 1, cols.max() - cols.min() + 1
        empty = 1.0 - max(bw / w, bh / h)
        cy, cx = (rows.max() + rows.min()) / 2, (cols.max() + cols.min()) / 2
        off = float(np.hypot(cy - (h - 1) / 2, cx - (w - 1) / 2) / np.hypot(h, w))
    else:
        empty, off = 1.0, 0.0
    return {
        "ink px": n_ink,
        "specks/1000": per_k,
        "black %": 100.0 * largest / max(n_content, 1),
        "empty %": 100.0 * empty,
        "off-centre %": 100.0 * off,
    }


def run_demo(outdir: Path) -> None:
    cmd = [sys.executable, "-m", "sciviz_gbuf", "demo", "-o", str(outdir)]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)


def map_ink(rgba: np.ndarray) -> np.ndarray:
    """The contour ink of a bands-free, relief-free map: dark on the map's paper."""
    rgb = rgba[..., :3].astype(np.float64) / 255.0
    alpha = rgba[..., 3] > 0
    return alpha & (luminance(rgb) < 0.85)  # minor lines fade: anything not paper is ink


def audit_dems(tmp: Path) -> list[tuple]:
    import sciviz_gbuf as sg
    from sciviz_gbuf.readers import read_dem

    rows = []
    for path in sorted(SHARED.glob("*")):
        if path.suffix.lower() not in (".asc", ".hgt", ".tif", ".dem"):
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            dem = read_dem(path)
        ink = map_ink(np.asarray(sg.topographic_map(dem, bands=False, relief=False)))
        n6, per_k6 = specks(ink, 6)
        precision = recall = float("nan")
        interval = GDAL_INTERVALS.get(path.name)
        pts = gdal_samples(path, interval, tmp) if interval else None  # tests/helpers
        if pts is not None:
            fixed = np.asarray(
                sg.topographic_map(dem, bands=False, relief=False, interval=interval)
            )
            line = map_ink(fixed)
            z = dem.heights.astype(np.float64)
            gy, gx = np.gradient(z)
            # "slope > 2 px per interval": neighbouring levels more than 2 px apart
            steep = (np.hypot(gx, gy) * 2.0 < interval) & np.isfinite(z)
            judged = np.argwhere(line & steep)
            r, c = np.round(pts).astype(int).T
            inside = (r >= 0) & (r < z.shape[0]) & (c >= 0) & (c < z.shape[1])
            pts = pts[inside][steep[r[inside], c[inside]]]
            if len(judged) and len(pts):
                d_ours, _ = cKDTree(pts).query(judged, distance_upper_bound=3.0)
                d_gdal, _ = cKDTree(np.argwhere(line)).query(pts, distance_upper_bound=3.0)
                precision, recall = float(np.mean(d_ours <= 1.0)), float(np.mean(d_gdal <= 1.0))
        rows.append((path.name, dem.heights.shape, n6, per_k6, interval, precision, recall))
    return rows


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--demo", type=Path, help="an existing demo folder (default: run the demo)")
    p.add_argument("--speck", type=int, default=4, help="largest isolated component, px")
    p.add_argument("--skip-dems", action="store_true")
    args = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        folder = args.demo
        if folder is None:
            folder = tmp / "demo"
            run_demo(folder)
        pngs = sorted(folder.glob("*.png"))
        print(f"## Demo pictures ({folder}, {len(pngs)} PNGs)\n")
        keys = ["ink px", "specks/1000", "black %", "empty %", "off-centre %"]
        print("| picture | " + " | ".join(keys) + " |")
        print("|---|" + "---:|" * len(keys))
        for png in pngs:
            if png.stem.endswith("montage"):
                continue  # tiles of the pictures above
            m = audit_png(png, args.speck)
            cells = [f"{m[k]:.0f}" if k == "ink px" else f"{m[k]:.1f}" for k in keys]
            if m["ink px"] < MIN_INK:
                cells[1] = "-"
            print(f"| {png.name} | " + " | ".join(cells) + " |")
        if args.skip_dems or not SHARED.is_dir():
            return 0
        print(f"\n## Maps of the shared DEMs ({SHARED})\n")
        print(
            "| DEM | grid | ink px | specks (<= 6 px) /1000 | interval vs gdal_contour | "
            "precision 1 px | recall 1 px |"
        )
        print("|---|---|---:|---:|---:|---:|---:|")
        for name, shape, n, per_k, interval, prec, rec in audit_dems(tmp):
            print(
                f"| {name} | {shape[1]}x{shape[0]} | {n} | {per_k:.1f} | {interval or '-'} | "
                f"{prec:.3f} | {rec:.3f} |"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
