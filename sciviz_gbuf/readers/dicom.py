"""DICOM CT series -> PyVista volume in patient coordinates (LPS, mm), with a report.

Real series are messy: several series in one folder, scouts, stray files, missing or uneven
slices, gantry tilt, padding values, compressed pixel data. :func:`read_dicom_series` handles
each case explicitly and records what it did in the dataset's ``field_data["dicom_report"]``
(read it back with :func:`dicom_report`). It never guesses silently: what cannot be read
unambiguously raises :class:`~sciviz_gbuf.errors.InputError` (or a subclass defined here)
naming the file(s) and what was expected.

Pipeline: list the files (a folder's own files, not sub-folders), read every header with
``defer_size`` (pixel data skipped), group by SeriesInstanceUID, pick one series, drop what does
not belong to the volume (localizers, colour images, odd orientations or sizes), order the
slices by ImagePositionPatient along the slice normal, and only then decode the pixels of the
chosen slices. Files are opened read-only and never written.

Not supported (rejected with :class:`DicomSeriesError`, not guessed): multi-frame images
(NumberOfFrames > 1, e.g. Enhanced CT; a single-frame Enhanced CT file fails on its missing
top-level ImagePositionPatient), Modality LUT sequences, slices without ImagePositionPatient /
ImageOrientationPatient / PixelSpacing (also single 2-D images without them), and uncompressed
pixel data whose length differs from Rows x Columns x BitsAllocated (pydicom would silently
drop excess bytes; a wrong Rows value looks exactly like that). The point array is named
``"HU"`` whatever the modality: it holds StoredValue * RescaleSlope + RescaleIntercept.
"""

from __future__ import annotations

import json
import os
import warnings
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import _validate
from .._progress import progress
from ..errors import InputError
from ._dicom_geometry import (
    analyse_positions,
    duplicate_pairs,
    resample_along_normal,
    shift_bilinear,
    slice_frame,
)

if TYPE_CHECKING:
    import pyvista

__all__ = ["DicomDecoderError", "DicomSeriesError", "dicom_report", "read_dicom_series"]

AIR_HU = -1024.0
_DICOMDIR_CLASS = "1.2.840.10008.1.3.10"
_INSTALL_HINT = 'pip install "sciviz-gbuf[dicom]"'


class DicomSeriesError(InputError):
    """A DICOM series that cannot be turned into a volume; the message names the file(s)."""


class DicomDecoderError(DicomSeriesError):
    """Compressed pixel data for which no pydicom decoder plugin is installed."""


@dataclass(eq=False)
class _Header:
    """What the header pass learned about one file (pixel data not read)."""

    path: Path
    uid: str = ""
    modality: str = ""
    description: str = ""
    image_type: tuple[str, ...] = ()
    transfer_syntax: str = ""
    samples: int | None = None
    frames: int = 1
    rows: int | None = None
    cols: int | None = None
    bits_allocated: int | None = None
    # Geometry tags: the value, or the problem with it (missing, not numeric, ...).
    values: dict[str, Any] = field(default_factory=dict)
    problems: dict[str, str] = field(default_factory=dict)
    modality_lut: bool = False
    step_hint: float | None = None

    @property
    def name(self) -> str:
        return str(self.path)


def read_dicom_series(
    path_or_files: str | os.PathLike | Iterable[str | os.PathLike],
    *,
    series_uid: str | None = None,
    resample: bool = False,
    gaps: str = "keep",
    padding: str = "air",
    progress_bar: bool = False,
) -> pyvista.ImageData | pyvista.StructuredGrid:
    """Read one DICOM image series as a volume of rescaled values (HU for CT).

    Parameters
    ----------
    path_or_files : path or iterable of paths
        A folder (its files only: sub-folders are not searched and are listed as excluded;
        hidden files are skipped), a single file, or a list of files.
    series_uid : str, optional
        SeriesInstanceUID to read. Default: the series with modality CT, then with the most
        image files (ties: smallest UID); a warning lists all series when there are several.
    resample : bool, optional
        If the slices are sheared (gantry tilt) or unevenly spaced, resample linearly onto a
        rectangular, uniform grid and return an :class:`pyvista.ImageData`: each slice is
        shifted in-plane onto the first slice's grid (bilinear), then the stack is
        interpolated along the normal onto the median step from the first slice. Voxels
        needing data outside the field of view become padding.
    gaps : {"keep", "error"}, optional
        What to do with uneven slice steps (a step more than 1% off the median step):
        ``"keep"`` the true positions (or resample if ``resample``), or raise ``"error"``
        naming the files on both sides of each gap (even with ``resample=True``).
    padding : {"air", "nan"}, optional
        Value of voxels equal to PixelPaddingValue (or within PixelPaddingRangeLimit), compared
        with the stored values before rescaling, and of voxels outside the field of view after
        resampling: -1024 HU or NaN. Either way point array ``"padding"`` (uint8, 1 = padded)
        is added when there is any.
    progress_bar : bool, optional
        Show tqdm bars over the header pass and the pixel pass.

    Returns
    -------
    pyvista.ImageData or pyvista.StructuredGrid
        Point array ``"HU"`` (float32, StoredValue * RescaleSlope + RescaleIntercept of each
        slice, slope 1 / intercept 0 when absent), index order x = column, y = row, z = slice
        ascending along the normal ``n = r x c`` (r: direction of increasing column index, c:
        of increasing row index, from ImageOrientationPatient), Fortran order:
        ``ds["HU"].reshape(nz, ny, nx)[k, j, i]``. Slices are ordered by ImagePositionPatient
        projected on ``n`` only. ImageData (origin = first slice's IPP, spacing = (column
        spacing, row spacing, median step), ``direction_matrix`` columns r, c, n) when the
        slice origins line up along ``n`` (within 1% of a pixel) with steps within 1% of the
        median; otherwise a StructuredGrid whose point ``(i, j, k)`` is exactly
        ``IPP_k + i * colspacing * r + j * rowspacing * c``. ``field_data`` holds
        ``"dicom_report"`` (JSON, see :func:`dicom_report`), ``"slice_positions"`` (output
        slice positions along ``n``, mm), ``"source_slice_positions"``, ``"rescale_slope"``
        and ``"rescale_intercept"`` (per source slice, in slice order).

    Raises
    ------
    InputError
        Bad arguments, a missing path, no usable image, unknown ``series_uid``.
    DicomSeriesError
        A file of the chosen series with missing/invalid geometry tags, duplicate slice
        positions (both files named), uneven steps with ``gaps="error"``, multi-frame or
        undecodable/truncated pixel data, inconsistent BitsAllocated or PixelSpacing.
    DicomDecoderError
        Compressed pixel data and no decoder plugin installed (install the ``dicom`` extra).
    """
    if gaps not in ("keep", "error"):
        raise InputError(f"gaps must be 'keep' or 'error', got {gaps!r}")
    if padding not in ("air", "nan"):
        raise InputError(f"padding must be 'air' or 'nan', got {padding!r}")
    if series_uid is not None and not isinstance(series_uid, str):
        raise InputError(f"series_uid must be a str or None, got {series_uid!r}")

    files, excluded, where = _collect(path_or_files)
    headers: list[_Header] = []
    with progress(progress_bar, len(files), "DICOM headers") as bar:
        for path in files:
            header = _read_header(path)
            if isinstance(header, str):
                excluded.append({"file": str(path), "reason": header})
            else:
                headers.append(header)
            bar.step(path.name)

    series = _group_series(headers)
    if not series:
        reasons = sorted({e["reason"].split(":")[0] for e in excluded})
        raise InputError(
            f"{where}: no DICOM image found ({len(files)} file(s) looked at; "
            f"excluded: {'; '.join(reasons) or 'nothing'})"
        )
    uid = _choose_series(series, series_uid, where)
    others = [_series_summary(u, hs) for u, hs in sorted(series.items()) if u != uid]
    for u, hs in series.items():
        if u != uid:
            excluded.extend({"file": h.name, "reason": f"other series {u!r}"} for h in hs)

    slices, more_excluded = _select_slices(series[uid], where)
    excluded.extend(more_excluded)
    frame, spacing, step_hint = _series_geometry(slices)
    positions = np.array([h.values["ImagePositionPatient"] for h in slices])
    geo = analyse_positions(positions, frame, spacing, step_hint)
    slices = [slices[i] for i in geo.order]
    dups = duplicate_pairs(geo.s)
    if dups:
        pairs = "; ".join(f"{slices[k].name} and {slices[k + 1].name}" for k in dups)
        raise DicomSeriesError(
            f"duplicate slice positions along the slice normal (same position "
            f"{', '.join(f'{geo.s[k]:.4f}' for k in dups)} mm): {pairs}; "
            "remove one file of each pair, or read the series it belongs to with series_uid="
        )
    gap_list = [
        {
            "after": slices[k].name,
            "before": slices[k + 1].name,
            "step_mm": float(geo.steps[k]),
            "expected_mm": geo.step,
        }
        for k in geo.uneven
    ]
    if gap_list and gaps == "error":
        desc = "; ".join(
            f"{g['step_mm']:.4g} mm between {g['after']} and {g['before']}" for g in gap_list
        )
        raise DicomSeriesError(
            f"{where}: uneven slice spacing (median step {geo.step:.4g} mm, tolerance 1%): {desc}"
        )

    volume, slopes, intercepts, n_padding = _read_volume(slices, progress_bar)
    r, c, n = frame
    report: dict[str, Any] = {
        "source": where,
        "series_uid": uid,
        "modality": slices[0].modality,
        "series_description": slices[0].description,
        "n_source_slices": len(slices),
        "files": [h.name for h in slices],
        "excluded": sorted(excluded, key=lambda e: (e["file"], e["reason"])),
        "other_series": others,
        "transfer_syntaxes": sorted({h.transfer_syntax for h in slices}),
        "row_cosine": r.tolist(),
        "column_cosine": c.tolist(),
        "normal": n.tolist(),
        "pixel_spacing_mm": [spacing[1], spacing[0]],
        "spacing": [spacing[0], spacing[1], geo.step],
        "slice_steps_mm": geo.steps.tolist(),
        "uneven_spacing": bool(gap_list),
        "gaps": gap_list,
        "sheared": geo.sheared,
        "shear_mm_per_slice": geo.shear.tolist(),
        "shear_magnitude_mm_per_slice": float(np.linalg.norm(geo.shear)),
        "max_inplane_offset_mm": float(np.abs(geo.offsets).max(initial=0.0)),
        "resampled": False,
        "shear_removed_mm_per_slice": None,
        "shear_removed_magnitude_mm_per_slice": 0.0,
        "interpolated_slices": [],
        "stored_padding_voxels": n_padding,
        "outside_fov_voxels": 0,
        "padding_mode": padding,
    }
    s_out = geo.s
    if resample and not geo.rectangular:
        volume, s_out = _resample(volume, slices, geo, spacing, report)
        report["resampled"] = True
    rectangular = geo.rectangular or report["resampled"]

    ds = _to_pyvista(volume, slices, frame, spacing, geo.step, rectangular, padding, report)
    report["kind"] = _kind(geo)
    ds.field_data["dicom_report"] = json.dumps(report)
    ds.field_data["slice_positions"] = np.asarray(s_out, dtype=np.float64)
    ds.field_data["source_slice_positions"] = geo.s.astype(np.float64)
    ds.field_data["rescale_slope"] = slopes
    ds.field_data["rescale_intercept"] = intercepts
    return ds


def dicom_report(ds: Any) -> dict:
    """The report written by :func:`read_dicom_series`, as a dict.

    Keys: ``source``, ``series_uid``, ``modality``, ``series_description``, ``n_slices``
    (output), ``n_source_slices``, ``files`` (in slice order), ``excluded`` (list of
    ``{"file", "reason"}``), ``other_series`` (``{"uid", "modality", "n_files",
    "description"}``), ``transfer_syntaxes``, ``row_cosine``, ``column_cosine``, ``normal``,
    ``pixel_spacing_mm`` (as in the file: row spacing, column spacing), ``spacing`` (column,
    row, median slice step), ``slice_steps_mm``, ``uneven_spacing``, ``gaps`` (``{"after",
    "before", "step_mm", "expected_mm"}``), ``sheared``, ``shear_mm_per_slice`` (LPS vector),
    ``shear_magnitude_mm_per_slice``, ``max_inplane_offset_mm``, ``resampled``,
    ``shear_removed_mm_per_slice`` (None if none), ``shear_removed_magnitude_mm_per_slice``,
    ``interpolated_slices`` (``{"index", "position_mm", "between", "weight"}``),
    ``stored_padding_voxels`` (PixelPaddingValue matches in the source slices),
    ``outside_fov_voxels`` (voxels of the shear-corrected source slices that needed data outside
    the field of view, counted before any interpolation along the normal), ``padding_voxels``
    (padding voxels in the output, the sum of the ``"padding"`` array),
    ``padding_mode``, ``geometry`` ("ImageData"/"StructuredGrid"), ``kind`` ("rectangular",
    "sheared", "uneven", "sheared+uneven": the input), ``max_position_deviation_mm``,
    ``dimensions``.

    Raises
    ------
    InputError
        ``ds`` has no DICOM report.
    """
    try:
        raw = ds.field_data["dicom_report"]
    except (KeyError, AttributeError) as exc:
        raise InputError(
            "dataset has no field_data['dicom_report']: not made by read_dicom_series"
        ) from exc
    if not isinstance(raw, str):
        raw = str(np.asarray(raw).ravel()[0])
    return json.loads(raw)


# ----------------------------------------------------------------------------- files, headers


def _collect(path_or_files: Any) -> tuple[list[Path], list[dict], str]:
    """The candidate files (sorted, so input order never matters), early exclusions, a label."""
    excluded: list[dict] = []
    if isinstance(path_or_files, (str, os.PathLike)):
        root = Path(path_or_files)
        if root.is_dir():
            files = []
            for p in sorted(root.iterdir()):
                if p.name.startswith("."):
                    excluded.append({"file": str(p), "reason": "hidden file"})
                elif p.is_dir():
                    excluded.append(
                        {"file": str(p), "reason": "directory (folders are not searched)"}
                    )
                else:
                    files.append(p)
            return files, excluded, str(root)
        if root.is_file():
            return [root], excluded, str(root)
        raise InputError(f"{root}: no such file or folder (expected DICOM files)")
    try:
        files = [Path(p) for p in path_or_files]
    except TypeError as exc:
        raise InputError(
            f"path_or_files must be a folder, a file or a list of files, got {path_or_files!r}"
        ) from exc
    if not files:
        raise InputError("path_or_files is an empty list (expected DICOM files)")
    missing = [str(p) for p in files if not p.is_file()]
    if missing:
        raise InputError(f"not a file: {', '.join(missing)} (expected DICOM files)")
    files.sort(key=str)
    where = str(files[0].parent) if len({p.parent for p in files}) == 1 else "file list"
    return files, excluded, where


def _read_header(path: Path) -> _Header | str:
    """Header of one file, or the reason it is not a candidate image."""
    import pydicom

    try:
        # Deferred values are not loaded: the pixel data is only skipped over here.
        ds = pydicom.dcmread(path, defer_size=1024)
    except Exception as exc:  # any parse failure means "not a readable DICOM file"
        return f"not a readable DICOM file: {type(exc).__name__}: {exc}"[:300]
    h = _Header(path)
    try:
        meta = getattr(ds, "file_meta", None)
        sop = str(ds.get("SOPClassUID", "") or (meta or {}).get("MediaStorageSOPClassUID", ""))
        if sop == _DICOMDIR_CLASS or "DirectoryRecordSequence" in ds:
            return "DICOMDIR (a directory index, not an image)"
        if "PixelData" not in ds:
            return "no pixel data (7FE0,0010)"
        h.uid = str(ds.get("SeriesInstanceUID", "") or "")
        h.modality = str(ds.get("Modality", "") or "")
        h.description = str(ds.get("SeriesDescription", "") or "")
        it = ds.get("ImageType", None)
        if it is not None:
            h.image_type = tuple(str(v).upper() for v in (it if _is_multi(it) else [it]))
        h.transfer_syntax = str((meta or {}).get("TransferSyntaxUID", "") or "")
    except Exception as exc:
        return f"unreadable header: {type(exc).__name__}: {exc}"[:300]
    h.samples = _int_tag(ds, "SamplesPerPixel", h)
    h.rows = _int_tag(ds, "Rows", h)
    h.cols = _int_tag(ds, "Columns", h)
    h.bits_allocated = _int_tag(ds, "BitsAllocated", h)
    frames = _int_tag(ds, "NumberOfFrames", h, required=False)
    h.frames = 1 if frames is None else frames
    for key, n in (
        ("ImageOrientationPatient", 6),
        ("ImagePositionPatient", 3),
        ("PixelSpacing", 2),
    ):
        value = _float_tag(ds, key, n, h)
        if value is not None:
            h.values[key] = value
    try:
        h.modality_lut = "ModalityLUTSequence" in ds and "RescaleSlope" not in ds
        for key in ("SpacingBetweenSlices", "SliceThickness"):
            v = ds.get(key, None)
            if v not in (None, "") and h.step_hint is None and np.isfinite(float(v)) and v > 0:
                h.step_hint = float(v)
    except Exception:  # an unusable hint is not an error: only used for single slices
        pass
    return h


def _is_multi(value: Any) -> bool:
    return isinstance(value, (list, tuple)) or type(value).__name__ == "MultiValue"


def _int_tag(ds: Any, key: str, h: _Header, required: bool = True) -> int | None:
    try:
        v = ds.get(key, None)
        if v is None or v == "":
            if required:
                h.problems[key] = "missing"
            return None
        return int(v)
    except Exception as exc:
        h.problems[key] = f"not an integer ({type(exc).__name__}: {exc})"
        return None


def _float_tag(ds: Any, key: str, n: int, h: _Header) -> list[float] | None:
    try:
        v = ds.get(key, None)
        if v is None or v == "":
            h.problems[key] = "missing"
            return None
        vals = [float(x) for x in (v if _is_multi(v) else [v])]
    except Exception as exc:
        h.problems[key] = f"not numeric ({type(exc).__name__}: {exc})"
        return None
    if len(vals) != n:
        h.problems[key] = f"has {len(vals)} values, expected {n}"
        return None
    if not all(np.isfinite(vals)):
        h.problems[key] = f"not finite: {vals}"
        return None
    return vals


# ----------------------------------------------------------------------------- series, slices


def _group_series(headers: list[_Header]) -> dict[str, list[_Header]]:
    series: dict[str, list[_Header]] = {}
    for h in headers:
        series.setdefault(h.uid, []).append(h)
    return series


def _series_summary(uid: str, hs: list[_Header]) -> dict:
    return {
        "uid": uid,
        "modality": hs[0].modality,
        "n_files": len(hs),
        "description": hs[0].description,
    }


def _choose_series(series: dict[str, list[_Header]], wanted: str | None, where: str) -> str:
    listing = "; ".join(
        f"{u or '(no SeriesInstanceUID)'} ({hs[0].modality or '?'}, {len(hs)} file(s), "
        f"{hs[0].description!r})"
        for u, hs in sorted(series.items())
    )
    if wanted is not None:
        if wanted not in series:
            raise InputError(
                f"{where}: no series with SeriesInstanceUID {wanted!r}; found: {listing}"
            )
        return wanted
    uid = max(sorted(series), key=lambda u: (series[u][0].modality == "CT", len(series[u])))
    if len(series) > 1:
        warnings.warn(
            f"{where}: {len(series)} series found: {listing}; reading {uid!r} (CT first, then "
            "the most files); pass series_uid= to choose another",
            stacklevel=3,
        )
    return uid


def _select_slices(hs: list[_Header], where: str) -> tuple[list[_Header], list[dict]]:
    """Drop localizers, colour images and odd orientations/sizes; reject bad geometry."""
    excluded = []
    kept = []
    for h in hs:
        if "LOCALIZER" in h.image_type:
            excluded.append({"file": h.name, "reason": "localizer (ImageType LOCALIZER)"})
        elif h.samples is not None and h.samples != 1:
            excluded.append(
                {"file": h.name, "reason": f"colour image (SamplesPerPixel={h.samples})"}
            )
        else:
            kept.append(h)
    if not kept:
        reasons = "; ".join(f"{e['file']}: {e['reason']}" for e in excluded)
        raise InputError(f"{where}: the chosen series has no usable slice ({reasons[:2000]})")
    for h in kept:
        if h.frames > 1:
            raise DicomSeriesError(
                f"{h.name}: multi-frame image (NumberOfFrames={h.frames}) is not supported; "
                "expected one slice per file"
            )
        if h.modality_lut:
            raise DicomSeriesError(
                f"{h.name}: Modality LUT Sequence without RescaleSlope is not supported"
            )
        for key in (
            "Rows",
            "Columns",
            "BitsAllocated",
            "ImageOrientationPatient",
            "ImagePositionPatient",
            "PixelSpacing",
        ):
            if key in h.problems:
                raise DicomSeriesError(
                    f"{h.name}: {key} {h.problems[key]}; expected it on every slice to place "
                    "it in patient space"
                )
        if h.rows < 1 or h.cols < 1:
            raise DicomSeriesError(
                f"{h.name}: Rows/Columns must be positive, got {h.rows}x{h.cols}"
            )
        frame = slice_frame(np.array(h.values["ImageOrientationPatient"]))
        if isinstance(frame, str):
            raise DicomSeriesError(f"{h.name}: ImageOrientationPatient {frame}")
        if min(h.values["PixelSpacing"]) <= 0:
            raise DicomSeriesError(
                f"{h.name}: PixelSpacing must be positive, got {h.values['PixelSpacing']}"
            )

    iop = np.array([h.values["ImageOrientationPatient"] for h in kept])
    keep = _majority(iop, 1e-4, kept, "ImageOrientationPatient")
    for h, ok in zip(kept, keep, strict=True):
        if not ok:
            excluded.append(
                {
                    "file": h.name,
                    "reason": "ImageOrientationPatient differs from the series majority "
                    "(localizer or reformat)",
                }
            )
    kept = [h for h, ok in zip(kept, keep, strict=True) if ok]
    size = np.array([(h.rows, h.cols) for h in kept])
    keep = _majority(size, 0, kept, "Rows/Columns")
    for h, ok in zip(kept, keep, strict=True):
        if not ok:
            excluded.append(
                {
                    "file": h.name,
                    "reason": f"Rows/Columns {h.rows}x{h.cols} differ from the series majority",
                }
            )
    kept = [h for h, ok in zip(kept, keep, strict=True) if ok]
    bits = {h.bits_allocated for h in kept}
    if len(bits) > 1:
        raise DicomSeriesError(
            "inconsistent BitsAllocated in one series: "
            + ", ".join(f"{h.name}={h.bits_allocated}" for h in kept)[:2000]
        )
    return kept, excluded


def _majority(values: np.ndarray, tol: float, hs: list[_Header], what: str) -> np.ndarray:
    """Mask of the largest group of rows of ``values`` equal within ``tol``; a tie is an error.

    Greedy clustering against a few representatives (O(N) memory, unlike all pairs); the
    headers come sorted by path, so the result does not depend on the input order.
    """
    reps: list[np.ndarray] = []
    label = np.empty(len(values), dtype=int)
    for k, v in enumerate(values):
        hit = [i for i, rep in enumerate(reps) if np.abs(v - rep).max() <= tol]
        if hit:
            label[k] = hit[0]
        else:
            label[k] = len(reps)
            reps.append(v)
    counts = np.bincount(label)
    best = np.flatnonzero(counts == counts.max())
    if best.size > 1:
        names = ", ".join(h.name for h, lab in zip(hs, label, strict=True) if lab in best)
        raise DicomSeriesError(
            f"{what} disagree between the files of one series with no majority: {names[:2000]}"
        )
    return label == best[0]


def _series_geometry(
    hs: list[_Header],
) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], tuple[float, float], float]:
    """Common frame, (column spacing, row spacing) and single-slice step of the slices."""
    # Medians are independent of the file order (means are not, to the last bit).
    iop = np.median(np.array([h.values["ImageOrientationPatient"] for h in hs]), axis=0)
    frame = slice_frame(iop)
    if isinstance(frame, str):  # cannot happen for cosines within 1e-4 of valid ones
        raise DicomSeriesError(f"{hs[0].name}: ImageOrientationPatient {frame}")
    ps = np.array([h.values["PixelSpacing"] for h in hs])
    med = np.median(ps, axis=0)
    odd = [h.name for h, p in zip(hs, ps, strict=True) if np.any(np.abs(p - med) > 1e-4 * med)]
    if odd:
        raise DicomSeriesError(
            f"PixelSpacing differs from the series' {med.tolist()} in: {', '.join(odd)[:2000]}"
        )
    hints = sorted(h.step_hint for h in hs if h.step_hint)
    step_hint = hints[len(hints) // 2] if hints else 1.0
    # PixelSpacing is (row spacing, column spacing): mm between rows, then between columns.
    return frame, (float(med[1]), float(med[0])), step_hint


def _kind(geo: Any) -> str:
    parts = [p for p, on in (("sheared", geo.sheared), ("uneven", geo.uneven.size > 0)) if on]
    return "+".join(parts) or "rectangular"


# ----------------------------------------------------------------------------- pixels


def _pixel_array(ds: Any) -> np.ndarray:
    """Decode the pixel data (the one place pydicom's pixel handlers are called)."""
    return ds.pixel_array


def _read_volume(
    slices: list[_Header], progress_bar: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """(N, rows, cols) float64 rescaled values, NaN at padding; slopes, intercepts, #padded."""
    rows, cols = slices[0].rows, slices[0].cols
    # The first slice is decoded before the volume is allocated: Rows/Columns that lie about
    # the pixel data (Rows=65535 over 512x512 data) fail here, not as a 56 GiB allocation.
    first = _read_slice(slices[0])
    _check_volume_memory(len(slices), rows, cols, slices[0])
    volume = np.empty((len(slices), rows, cols), dtype=np.float64)
    slopes = np.empty(len(slices))
    intercepts = np.empty(len(slices))
    n_padding = 0
    with progress(progress_bar, len(slices), "DICOM pixels") as bar:
        for k, h in enumerate(slices):
            raw, slope, intercept, pad = first if k == 0 else _read_slice(h)
            volume[k] = raw * slope + intercept
            if pad is not None:
                volume[k][pad] = np.nan
                n_padding += int(pad.sum())
            slopes[k], intercepts[k] = slope, intercept
            bar.step(h.path.name)
    return volume, slopes, intercepts, n_padding


def _check_volume_memory(n: int, rows: int, cols: int, h: _Header) -> None:
    """The float64 volume (and its float32 copy) must fit in the memory available now."""
    need = n * rows * cols * (8 + 4)
    have = _validate.available_memory()
    if have is not None and need > have:
        raise DicomSeriesError(
            f"{h.name}: {n} slices of {rows}x{cols} need {need / 2**30:.1f} GiB, only "
            f"{have / 2**30:.1f} GiB of memory is available (read fewer slices or a series "
            "with fewer rows/columns)"
        )


#: JPEG 2000 codestream markers: start of codestream, end of codestream.
_J2K_SOC, _J2K_EOC = b"\xff\x4f", b"\xff\xd9"


def _check_j2k_frames(ds: Any, h: _Header) -> None:
    """A JPEG 2000 frame must be a whole codestream (SOC ... EOC): openjpeg decodes a damaged
    or truncated one into plausible-looking garbage without an error."""
    from pydicom.encaps import generate_frames

    try:
        n = int(ds.get("NumberOfFrames", 1) or 1)
        for frame in generate_frames(ds.PixelData, number_of_frames=n):
            start = frame.find(_J2K_SOC)
            if start < 0 or start > 64 or not frame.rstrip(b"\x00").endswith(_J2K_EOC):
                raise DicomSeriesError(
                    f"{h.name}: JPEG 2000 pixel data is damaged or truncated (the codestream "
                    "does not run from its start to its end marker)"
                )
    except DicomSeriesError:
        raise
    except Exception as exc:  # pydicom's encapsulation parser on damaged items
        raise DicomSeriesError(f"{h.name}: encapsulated pixel data is damaged: {exc}") from exc


def _read_slice(h: _Header) -> tuple[np.ndarray, float, float, np.ndarray | None]:
    import pydicom
    from pydicom.pixels import get_decoder

    try:
        ds = pydicom.dcmread(h.path)
    except Exception as exc:
        raise DicomSeriesError(f"{h.name}: cannot be read again for its pixels: {exc}") from exc
    ts = ds.file_meta.get("TransferSyntaxUID", None) if hasattr(ds, "file_meta") else None
    ts_name = f"{ts} ({ts.name})" if ts else "(no transfer syntax)"
    if ts is not None:
        try:
            decoder = get_decoder(ts)
        except NotImplementedError as exc:
            raise DicomSeriesError(
                f"{h.name}: transfer syntax {ts_name} is not supported by pydicom"
            ) from exc
        if not decoder.is_available:
            raise DicomDecoderError(_missing_decoder_message(h, ts_name))
        if not ts.is_encapsulated:
            _check_native_length(ds, h)
        elif "JPEG 2000" in ts.name:
            _check_j2k_frames(ds, h)
    try:
        raw = _pixel_array(ds)
    except RuntimeError as exc:
        if "missing dependencies" in str(exc):
            raise DicomDecoderError(_missing_decoder_message(h, ts_name)) from exc
        raise DicomSeriesError(f"{h.name}: cannot decode pixel data ({ts_name}): {exc}") from exc
    except Exception as exc:
        raise DicomSeriesError(f"{h.name}: cannot decode pixel data ({ts_name}): {exc}") from exc
    raw = np.asarray(raw)
    if raw.shape != (h.rows, h.cols):
        raise DicomSeriesError(
            f"{h.name}: decoded pixel data has shape {raw.shape}, expected (Rows, Columns) = "
            f"({h.rows}, {h.cols})"
        )
    if not np.issubdtype(raw.dtype, np.integer):
        raise DicomSeriesError(f"{h.name}: expected integer stored values, got {raw.dtype}")
    try:
        # Absent (or empty) means identity; a present 0 must stay 0 and be rejected below.
        slope, intercept = (
            default if (v := ds.get(key, None)) is None or v == "" else float(v)
            for key, default in (("RescaleSlope", 1.0), ("RescaleIntercept", 0.0))
        )
    except Exception as exc:
        raise DicomSeriesError(f"{h.name}: RescaleSlope/RescaleIntercept not numeric") from exc
    if not (np.isfinite(slope) and np.isfinite(intercept)) or slope == 0:
        raise DicomSeriesError(
            f"{h.name}: RescaleSlope {slope} / RescaleIntercept {intercept} must be finite, "
            "slope non-zero"
        )
    return raw, slope, intercept, _padding_mask(ds, raw, h)


def _missing_decoder_message(h: _Header, ts_name: str) -> str:
    return (
        f"{h.name}: pixel data is compressed with transfer syntax {ts_name} and no "
        f"decoder plugin is installed; install them with: {_INSTALL_HINT}"
    )


def _check_native_length(ds: Any, h: _Header) -> None:
    """Uncompressed data must hold exactly Rows*Columns samples: pydicom only warns on excess."""
    bits = int(ds.get("BitsAllocated", 0) or 0)
    if bits not in (8, 16, 32, 64):
        raise DicomSeriesError(f"{h.name}: BitsAllocated {bits} not supported (8/16/32/64)")
    try:
        length = len(ds.PixelData)
    except Exception as exc:
        raise DicomSeriesError(f"{h.name}: pixel data cannot be read: {exc}") from exc
    expected = h.rows * h.cols * bits // 8
    if length not in (expected, expected + 1):
        raise DicomSeriesError(
            f"{h.name}: pixel data holds {length} bytes, expected {expected} for "
            f"{h.rows}x{h.cols} pixels of {bits} bits (truncated file or wrong Rows/Columns?)"
        )


def _padding_mask(ds: Any, raw: np.ndarray, h: _Header) -> np.ndarray | None:
    """Stored values equal to PixelPaddingValue (or within the range limit), before rescaling."""
    if "PixelPaddingValue" not in ds:
        return None
    try:
        bits = int(ds.get("BitsAllocated", 16))
        signed = int(ds.get("PixelRepresentation", 0)) == 1
        values = [_as_stored(int(ds.PixelPaddingValue), bits, signed)]
        if "PixelPaddingRangeLimit" in ds:
            values.append(_as_stored(int(ds.PixelPaddingRangeLimit), bits, signed))
    except Exception as exc:
        raise DicomSeriesError(f"{h.name}: PixelPaddingValue is not an integer: {exc}") from exc
    lo, hi = min(values), max(values)
    mask = (raw >= lo) & (raw <= hi)
    return mask if mask.any() else None


def _as_stored(value: int, bits: int, signed: bool) -> int:
    """Reinterpret a US/SS padding value with the pixels' signedness (VR may disagree)."""
    if signed and value >= 2 ** (bits - 1):
        return value - 2**bits
    if not signed and value < 0:
        return value + 2**bits
    return value


# ----------------------------------------------------------------------------- geometry output


def _to_pyvista(
    volume: np.ndarray,
    slices: list[_Header],
    frame: tuple[np.ndarray, np.ndarray, np.ndarray],
    spacing: tuple[float, float],
    step: float,
    rectangular: bool,
    padding: str,
    report: dict,
) -> pyvista.ImageData | pyvista.StructuredGrid:
    """The (N, rows, cols) volume (NaN = padding) as ImageData or exact StructuredGrid."""
    r, c, n = frame
    mask = np.isnan(volume)
    report["padding_voxels"] = int(mask.sum())
    volume[mask] = AIR_HU if padding == "air" else np.nan
    nz, ny, nx = volume.shape
    origin = np.asarray(slices[0].values["ImagePositionPatient"], dtype=np.float64)
    import pyvista

    if rectangular:
        ds = pyvista.ImageData(
            dimensions=(nx, ny, nz),
            spacing=(spacing[0], spacing[1], step),
            origin=origin,
            direction_matrix=np.column_stack([r, c, n]),
        )
        # Deviation of the true origins from the uniform grid (bounded by the 1% tolerances).
        ideal = origin + np.outer(np.arange(len(slices)) * step, n)
        true = np.array([h.values["ImagePositionPatient"] for h in slices])
        dev = 0.0 if report["resampled"] else float(np.abs(true - ideal).max())
        report["max_position_deviation_mm"] = dev
        report["geometry"] = "ImageData"
    else:
        ds = pyvista.StructuredGrid()
        ds.points = _exact_points(slices, frame, spacing, nx, ny)
        ds.dimensions = (nx, ny, nz)
        report["max_position_deviation_mm"] = 0.0
        report["geometry"] = "StructuredGrid"
    report["n_slices"] = nz
    report["dimensions"] = [nx, ny, nz]
    ds.point_data["HU"] = volume.astype(np.float32).ravel()
    if mask.any():
        ds.point_data["padding"] = mask.astype(np.uint8).ravel()
    return ds


def _exact_points(
    slices: list[_Header],
    frame: tuple[np.ndarray, np.ndarray, np.ndarray],
    spacing: tuple[float, float],
    nx: int,
    ny: int,
) -> np.ndarray:
    """(N*ny*nx, 3) float64: IPP_k + i * colspacing * r + j * rowspacing * c, i fastest."""
    r, c, _ = frame
    ipp = np.array([h.values["ImagePositionPatient"] for h in slices], dtype=np.float64)
    plane = (np.arange(ny)[:, None, None] * spacing[1]) * c + (
        np.arange(nx)[None, :, None] * spacing[0]
    ) * r
    pts = ipp[:, None, None, :] + plane[None]
    return pts.reshape(-1, 3)


def _resample(
    volume: np.ndarray,
    slices: list[_Header],
    geo: Any,
    spacing: tuple[float, float],
    report: dict,
) -> tuple[np.ndarray, np.ndarray]:
    """Remove the in-plane drift, then interpolate onto the median step; fill the report."""
    outside = 0
    if geo.sheared:
        ones = np.ones(volume.shape[1:])
        for k in range(volume.shape[0]):
            # Output (j, i) lies at slice k's (row j - b/rowspacing, column i - a/colspacing).
            dy, dx = -geo.offsets[k, 1] / spacing[1], -geo.offsets[k, 0] / spacing[0]
            volume[k] = shift_bilinear(volume[k], dy, dx)
            outside += int(np.isnan(shift_bilinear(ones, dy, dx)).sum())
        report["shear_removed_mm_per_slice"] = geo.shear.tolist()
        report["shear_removed_magnitude_mm_per_slice"] = float(np.linalg.norm(geo.shear))
    s_out = geo.s
    if geo.uneven.size:
        n_out = int(np.floor((geo.s[-1] - geo.s[0]) / geo.step + 1e-3)) + 1
        s_out = geo.s[0] + np.arange(n_out) * geo.step
        volume, lower, weight = resample_along_normal(volume, geo.s, s_out)
        report["interpolated_slices"] = [
            {
                "index": m,
                "position_mm": float(s_out[m]),
                "between": [slices[lower[m]].name, slices[lower[m] + 1].name],
                "weight": float(weight[m]),
            }
            for m in range(n_out)
            if weight[m] != 0.0
        ]
    report["outside_fov_voxels"] = outside
    return volume, s_out
