"""Synthetic DICOM CT series for the reader tests, written with pydicom only.

Every slice is a small CT Image Storage file whose geometry, rescale, padding and transfer
syntax the test chooses. Positions are given explicitly, so tests know the truth exactly.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from pydicom.dataset import Dataset, FileMetaDataset
from pydicom.uid import CTImageStorage, ExplicitVRLittleEndian, generate_uid

AXIAL = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0)


def frame_of(iop: Sequence[float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Row cosine, column cosine and normal (r x c) of an ImageOrientationPatient."""
    r, c = np.asarray(iop[:3], dtype=float), np.asarray(iop[3:], dtype=float)
    return r, c, np.cross(r, c)


def rotation_iop(rot: np.ndarray) -> tuple[float, ...]:
    """ImageOrientationPatient whose cosines are the first two columns of a rotation matrix."""
    return tuple(float(v) for v in (*rot[:, 0], *rot[:, 1]))


def positions_along(
    origin: Sequence[float], iop: Sequence[float], steps: Sequence[float], shear=(0.0, 0.0, 0.0)
) -> np.ndarray:
    """IPPs from ``origin``, ``steps`` mm apart along the normal, plus ``shear`` per slice."""
    _, _, n = frame_of(iop)
    s = np.concatenate([[0.0], np.cumsum(steps)])
    k = np.arange(len(s))[:, None]
    return np.asarray(origin, float) + s[:, None] * n + k * np.asarray(shear, float)


def make_slice(
    raw: np.ndarray,
    *,
    ipp: Sequence[float] | None,
    iop: Sequence[float] | None = AXIAL,
    pixel_spacing: Sequence[float] | None = (0.5, 0.75),
    slope: float = 1.0,
    intercept: float = -1024.0,
    series_uid: str,
    instance: int = 1,
    modality: str = "CT",
    description: str = "synthetic",
    image_type: Sequence[str] = ("ORIGINAL", "PRIMARY", "AXIAL"),
    padding_value: int | None = None,
    padding_limit: int | None = None,
    padding_vr: str | None = None,
) -> Dataset:
    """One CT slice; ``raw`` (rows, cols) uint16 or int16 sets PixelRepresentation.

    ``padding_vr`` forces the VR of PixelPaddingValue (scanners write US for signed data too).
    """
    raw = np.ascontiguousarray(raw)
    signed = raw.dtype == np.int16
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = CTImageStorage
    meta.MediaStorageSOPInstanceUID = generate_uid()
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds = Dataset()
    ds.file_meta = meta
    ds.SOPClassUID = CTImageStorage
    ds.SOPInstanceUID = meta.MediaStorageSOPInstanceUID
    ds.StudyInstanceUID = "1.2.826.0.1.3680043.8.498.1"
    ds.SeriesInstanceUID = series_uid
    ds.FrameOfReferenceUID = "1.2.826.0.1.3680043.8.498.2"
    ds.Modality = modality
    ds.SeriesDescription = description
    ds.ImageType = list(image_type)
    ds.InstanceNumber = instance
    ds.PatientName = "Synthetic^Phantom"
    ds.PatientID = "0"
    if ipp is not None:
        ds.ImagePositionPatient = [_ds(v) for v in ipp]
    if iop is not None:
        ds.ImageOrientationPatient = [_ds(v) for v in iop]
    if pixel_spacing is not None:
        ds.PixelSpacing = [_ds(v) for v in pixel_spacing]
    ds.SliceThickness = "1"
    ds.SamplesPerPixel = 1
    ds.PhotometricInterpretation = "MONOCHROME2"
    ds.Rows, ds.Columns = raw.shape
    ds.BitsAllocated = 16
    ds.BitsStored = 16
    ds.HighBit = 15
    ds.PixelRepresentation = 1 if signed else 0
    ds.RescaleSlope = _ds(slope)
    ds.RescaleIntercept = _ds(intercept)
    ds.RescaleType = "HU"
    if padding_value is not None:
        vr = padding_vr or ("SS" if signed else "US")
        ds.add_new(0x00280120, vr, int(padding_value))
        if padding_limit is not None:
            ds.add_new(0x00280121, vr, int(padding_limit))
    ds.PixelData = raw.astype("<i2" if signed else "<u2").tobytes()
    return ds


def _ds(v: float) -> str:
    """A decimal string of at most 16 characters (the DS limit) that round-trips closely."""
    for digits in range(16, 5, -1):
        text = f"{float(v):.{digits}g}"
        if len(text) <= 16:
            return text
    raise ValueError(v)


def write_series(
    folder: Path,
    raws: Sequence[np.ndarray],
    positions: np.ndarray,
    *,
    iop: Sequence[float] = AXIAL,
    slopes: Sequence[float] | None = None,
    intercepts: Sequence[float] | None = None,
    series_uid: str | None = None,
    names: Sequence[str] | None = None,
    compress: str | None = None,
    **kwargs,
) -> list[Path]:
    """Write one slice file per raw image; returns the paths in the given order.

    ``compress`` is a transfer syntax UID to encode with pydicom (e.g. RLE Lossless).
    """
    folder.mkdir(parents=True, exist_ok=True)
    series_uid = series_uid or generate_uid()
    paths = []
    for k, (raw, ipp) in enumerate(zip(raws, positions, strict=True)):
        ds = make_slice(
            raw,
            ipp=ipp,
            iop=iop,
            slope=1.0 if slopes is None else slopes[k],
            intercept=-1024.0 if intercepts is None else intercepts[k],
            series_uid=series_uid,
            instance=k + 1,
            **kwargs,
        )
        if compress is not None:
            ds.compress(compress)
        path = folder / (names[k] if names else f"slice{k:03d}.dcm")
        ds.save_as(path, enforce_file_format=True)
        paths.append(path)
    return paths


def random_raws(rng: np.random.Generator, n: int, rows: int = 16, cols: int = 16, signed=False):
    """``n`` random (rows, cols) images, uint16 (or int16 when ``signed``)."""
    if signed:
        return [rng.integers(-2000, 3000, (rows, cols)).astype(np.int16) for _ in range(n)]
    return [rng.integers(0, 4000, (rows, cols)).astype(np.uint16) for _ in range(n)]
