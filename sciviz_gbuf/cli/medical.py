"""The ``sciviz-gbuf ct`` command: a DICOM CT series -> the enhanced image of 1990 Fig. 14."""

from __future__ import annotations

import argparse
import time

from ..compose import write_png
from ..errors import InputError
from ..readers.dicom import dicom_report
from ..recipes.medical import (
    LAYOUTS,
    SKIN_OPACITY,
    VIEWS,
    ct_enhance,
    ct_gbuffer,
    ct_translucent,
    read_ct_volume,
)
from ._args import add_progress, number, png_output, positive_int, show_progress, size

__all__ = ["add_ct"]


def _iso(text: str) -> str | float:
    key = text.strip().lower()
    if key in ("bone", "skin"):
        return key
    try:
        return float(key)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected a threshold in HU or 'bone' / 'skin', got {text!r}"
        ) from None


def _bands(text: str) -> int | float | list[float] | None:
    key = text.strip().lower()
    if key == "none":
        return None
    try:
        if "," in key:
            return [float(v) for v in key.split(",")]
        if key.endswith("mm"):
            return float(key[:-2])
        count = int(key)
    except ValueError:
        count = 0
    if count < 1:
        raise argparse.ArgumentTypeError(
            f"expected a band count, a width such as 20mm, edges L1,L2,... or none, got {text!r}"
        )
    return count


def _colour(text: str) -> tuple[float, float, float] | None:
    from matplotlib.colors import to_rgb

    if text.strip().lower() in ("none", "transparent"):
        return None
    try:
        return tuple(float(v) for v in to_rgb(text.strip()))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected a colour name or #rrggbb (or 'transparent'), got {text!r}"
        ) from None


def _cmd_ct(args: argparse.Namespace) -> int:
    out = png_output(args.output)
    t0 = time.perf_counter()
    show = show_progress(args)
    source = args.dicom[0] if len(args.dicom) == 1 else list(args.dicom)
    volume = read_ct_volume(
        source, series_uid=args.series, resample=args.resample, progress_bar=show
    )
    if "dicom_report" in volume.field_data:
        report = dicom_report(volume)
    else:  # a volume file
        report = {"n_slices": volume.dimensions[2], "geometry": "volume file"}
    t1 = time.perf_counter()
    if args.translucent is not None:
        if args.save_gbuffer:
            raise InputError(
                "--save-gbuffer: a translucent view keeps no single-surface G-buffer; save one "
                "without --translucent"
            )
        image = ct_translucent(
            volume, translucent=args.translucent, inner=args.iso, opacity=args.opacity,
            view=args.view, window_size=args.size, supersample=args.supersample,
            background=args.background, progress_bar=show, up=args.up, smooth=args.smooth,
            refine=args.refine, largest=args.largest,
        )  # fmt: skip
        write_png(out, image)
        print(
            f"wrote {out} ({image.shape[1]}x{image.shape[0]}, {args.iso} through translucent "
            f"{args.translucent} at opacity {args.opacity:g}) in {time.perf_counter() - t0:.1f} s"
        )
        return 0
    gb = ct_gbuffer(
        volume,
        iso=args.iso,
        view=args.view,
        window_size=args.size,
        supersample=args.supersample,
        smooth=args.smooth,
        refine=args.refine,
        largest=args.largest,
        progress_bar=show,
        up=args.up,
    )
    if args.save_gbuffer:
        gb.save(args.save_gbuffer)
    t2 = time.perf_counter()
    image = ct_enhance(
        gb,
        layout=args.layout,
        contour_axis=args.contour_axis,
        contour_interval=args.contour_interval,
        band_axis=args.band_axis,
        bands=args.bands,
        background=args.background,
    )
    write_png(out, image)
    t3 = time.perf_counter()
    n = report.get("n_slices", "?")
    excluded = len(report.get("excluded", []))
    print(
        f"wrote {out} ({image.shape[1]}x{image.shape[0]}, {args.layout}) from {n} slices"
        f" ({report.get('geometry', 'volume')}; {excluded} file(s) excluded) in"
        f" {t3 - t0:.1f} s: read {t1 - t0:.1f} s, surface + capture {t2 - t1:.1f} s,"
        f" filters + PNG {t3 - t2:.1f} s"
    )
    return 0


def add_ct(sub) -> None:
    """Add the ``ct`` sub-command to the ``sciviz-gbuf`` parser."""
    p = sub.add_parser(
        "ct",
        help="enhanced CT bone/skin surface from a DICOM series or a NRRD/MetaImage/NIfTI "
        "volume (Saito & Takahashi 1990 Fig. 14)",
        description="Read a DICOM CT series (ordered by patient position, rescaled to HU) or a "
        "volume file (NRRD, MetaImage, NIfTI; in the same patient frame), cut "
        "an isosurface, render it once, then draw profiles, shading, contour lines of one "
        "world coordinate and colour bands of another beside the conventional shaded image.",
    )
    p.add_argument(
        "dicom",
        nargs="+",
        help="DICOM series folder, or the files of one series, or one volume file (.nrrd, "
        ".nhdr, .mha, .mhd, .nii, .nii.gz)",
    )
    p.add_argument("-o", "--output", required=True, help="output image (.png)")
    p.add_argument(
        "--iso", type=_iso, default="bone", help="threshold in HU, or bone (300) / skin (-500)"
    )
    p.add_argument(
        "--view",
        default="anterior",
        help=f"anatomical view: {', '.join(VIEWS)}, or two joined by '-' (anterior-left)",
    )
    p.add_argument(
        "--up",
        choices=["x", "y", "z"],
        default=None,
        help="world axis upright in the picture (default: the head, +z, as DICOM's patient "
        "axes have it; the face, -y, for superior/inferior views)",
    )
    p.add_argument("--size", type=size, default=(1024, 1024), help="size of each picture WxH")
    p.add_argument("--supersample", type=positive_int, default=2, help="render at k times the size")
    p.add_argument(
        "--layout", default="pair", choices=LAYOUTS, help="shaded + enhanced side by side (pair)"
    )
    p.add_argument("--series", default=None, metavar="UID", help="SeriesInstanceUID to read")
    p.add_argument(
        "--resample",
        action="store_true",
        help="resample uneven or gantry-tilted series onto a regular grid (default: exact "
        "positions)",
    )
    p.add_argument(
        "--smooth", type=int, default=60, metavar="N", help="surface smoothing iterations"
    )
    p.add_argument(
        "--no-refine",
        dest="refine",
        action="store_false",
        help="cut the surface from the slices as they are (by default an axis of slices "
        "more than twice as far apart as the pixels is resampled first: no terraces)",
    )
    p.add_argument("--largest", action="store_true", help="keep the largest surface piece only")
    p.add_argument("--contour-axis", choices=["x", "y", "z"], default=None)
    p.add_argument(
        "--contour-interval",
        type=number(lambda v: v > 0, "a distance in mm > 0"),
        default=None,
        metavar="MM",
        help="distance between contour lines (default about 24 lines)",
    )
    p.add_argument("--band-axis", choices=["x", "y", "z"], default=None)
    p.add_argument(
        "--bands", type=_bands, default=6, help="band count, width (20mm), edges or none"
    )
    p.add_argument(
        "--background", type=_colour, default=None, help="background colour (transparent)"
    )
    p.add_argument(
        "--save-gbuffer", default=None, metavar="FILE.npz", help="also save the G-buffers"
    )
    p.add_argument(
        "--translucent",
        type=_iso,
        default=None,
        metavar="ISO",
        help="draw this surface (HU, or skin / bone) translucent over the --iso one, both "
        "outlined, instead of the Fig. 14 pair (e.g. --translucent skin --iso bone)",
    )
    p.add_argument(
        "--opacity",
        type=number(lambda v: 0 <= v <= 1, "an opacity in [0, 1]"),
        default=SKIN_OPACITY,
        help=f"of the --translucent surface (default {SKIN_OPACITY:g})",
    )
    add_progress(p)
    p.set_defaults(func=_cmd_ct)
