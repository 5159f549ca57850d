"""read_dicom_series: real Philips CT series (straight and gantry-tilted), synthetic series with
known geometry, messy folders, pydicom's own test corpus, and Hypothesis round trips.

Expected values are computed here from the files with pydicom and textbook DICOM geometry
(IPP + column * column spacing * row cosine + row * row spacing * column cosine), never with
the reader's helpers.
"""

from __future__ import annotations

import hashlib
import os
import random
import shutil
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pydicom
import pytest
import pyvista as pv
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pydicom.uid import RLELossless, generate_uid
from scipy import ndimage

from sciviz_gbuf.errors import InputError
from sciviz_gbuf.readers import dicom as dicom_mod
from sciviz_gbuf.readers import dicom_report, read_dicom_series
from sciviz_gbuf.readers.dicom import DicomDecoderError, DicomSeriesError
from tests.helpers.dicom_factory import (
    AXIAL,
    make_slice,
    positions_along,
    random_raws,
    rotation_iop,
    write_series,
)
from tests.helpers.paths import SHARED_DATA

CT_DATA = SHARED_DATA / "ct"
PHILIPS = CT_DATA / "dcm_qa_ct_Philips_phantom_5mm"
TILT = CT_DATA / "dcm_qa_ct_Philips_phantom_tilt-18.5"
needs_philips = pytest.mark.skipif(not PHILIPS.is_dir(), reason="Philips 5 mm series absent")
needs_tilt = pytest.mark.skipif(not TILT.is_dir(), reason="Philips tilt series absent")
CORPUS = sorted((Path(pydicom.__file__).parent / "data" / "test_files").glob("*.dcm"))


# ----------------------------------------------------------------------------- independent truth


def truth(files):
    """Per file, sorted along the normal: paths, IPP, r, c, n, (dr, dc), HU slices (float64)."""
    dss = [pydicom.dcmread(f) for f in files]
    iop = np.array([float(v) for v in dss[0].ImageOrientationPatient])
    r, c = iop[:3], iop[3:]
    n = np.cross(r, c)
    ipp = np.array([[float(v) for v in d.ImagePositionPatient] for d in dss])
    order = np.argsort(ipp @ n)
    dss = [dss[i] for i in order]
    hu = [
        d.pixel_array.astype(np.float64) * float(d.RescaleSlope) + float(d.RescaleIntercept)
        for d in dss
    ]
    dr, dc = (float(v) for v in dss[0].PixelSpacing)
    return {
        "files": [str(files[i]) for i in order],
        "ipp": ipp[order],
        "r": r,
        "c": c,
        "n": n,
        "dr": dr,
        "dc": dc,
        "hu": hu,
    }


def expected_points(t, nx, ny):
    """(nz, ny, nx, 3) patient positions of every voxel centre from each slice's IPP."""
    j, i = np.meshgrid(np.arange(ny), np.arange(nx), indexing="ij")
    plane = i[..., None] * t["dc"] * t["r"] + j[..., None] * t["dr"] * t["c"]
    return t["ipp"][:, None, None, :] + plane[None]


def volume(ds):
    nx, ny, nz = ds.dimensions
    return ds["HU"].reshape(nz, ny, nx)


def assert_same_dataset(a, b):
    assert type(a) is type(b)
    assert a.dimensions == b.dimensions
    np.testing.assert_array_equal(a["HU"], b["HU"])
    if isinstance(a, pv.ImageData):  # (ImageData.points would be slow to build)
        np.testing.assert_array_equal(a.origin, b.origin)
        np.testing.assert_array_equal(a.spacing, b.spacing)
        np.testing.assert_array_equal(a.direction_matrix, b.direction_matrix)
    else:
        np.testing.assert_array_equal(a.points, b.points)
    np.testing.assert_array_equal(a.field_data["slice_positions"], b.field_data["slice_positions"])


def copy_series(src: Path, dst: Path, skip=()) -> list[Path]:
    dst.mkdir(parents=True, exist_ok=True)
    out = []
    for f in sorted(src.iterdir()):
        if f.name not in skip:
            shutil.copy(f, dst / f.name)
            out.append(dst / f.name)
    return out


def digest(paths):
    return {
        str(p): (hashlib.sha256(Path(p).read_bytes()).hexdigest(), os.stat(p).st_mtime_ns)
        for p in paths
    }


@pytest.fixture(scope="module")
def philips():
    if not PHILIPS.is_dir():
        pytest.skip("Philips 5 mm series absent")
    files = sorted(PHILIPS.glob("*.dcm"))
    return files, truth(files), read_dicom_series(PHILIPS)


# ----------------------------------------------------------------------------- real series


@needs_philips
def test_philips_5mm_order_values_and_geometry(philips):
    files, t, ds = philips
    assert len(files) == 28
    assert isinstance(ds, pv.ImageData)
    assert ds.dimensions == (512, 512, 28)
    np.testing.assert_allclose(ds.spacing, (t["dc"], t["dr"], 5.0), rtol=0, atol=1e-9)
    np.testing.assert_array_equal(ds.origin, t["ipp"][0])
    np.testing.assert_allclose(ds.direction_matrix, np.column_stack([t["r"], t["c"], t["n"]]))
    s = ds.field_data["slice_positions"]
    assert np.all(np.diff(s) > 0)
    np.testing.assert_allclose(s, t["ipp"] @ t["n"], atol=1e-9)
    vol = volume(ds)
    for k in range(28):
        np.testing.assert_array_equal(vol[k], t["hu"][k].astype(np.float32))
    raws = [pydicom.dcmread(f) for f in files]
    lo = min(
        float(d.pixel_array.min()) * float(d.RescaleSlope) + float(d.RescaleIntercept) for d in raws
    )
    hi = max(
        float(d.pixel_array.max()) * float(d.RescaleSlope) + float(d.RescaleIntercept) for d in raws
    )
    assert float(ds["HU"].min()) == lo and float(ds["HU"].max()) == hi
    np.testing.assert_allclose(
        ds.points.reshape(28, 512, 512, 3), expected_points(t, 512, 512), atol=1e-6
    )
    rep = dicom_report(ds)
    assert rep["n_slices"] == 28 and rep["geometry"] == "ImageData"
    assert rep["kind"] == "rectangular" and not rep["resampled"]
    assert rep["files"] == t["files"]
    assert rep["excluded"] == [] and rep["other_series"] == []
    assert "padding" not in ds.point_data and rep["padding_voxels"] == 0


@needs_philips
def test_philips_shuffled_file_list_gives_identical_dataset(philips):
    files, _, ds = philips
    shuffled = list(files)
    random.Random(3).shuffle(shuffled)
    again = read_dicom_series([str(f) for f in shuffled])
    assert_same_dataset(ds, again)
    assert dicom_report(ds) == dicom_report(again)


@needs_tilt
def test_tilt_exact_structured_grid():
    files = sorted(TILT.glob("*.dcm"))
    t = truth(files)
    ds = read_dicom_series(TILT)
    assert isinstance(ds, pv.StructuredGrid)
    assert ds.dimensions == (512, 512, 54)
    got = ds.points.reshape(54, 512, 512, 3)
    assert np.abs(got - expected_points(t, 512, 512)).max() < 1e-3
    vol = volume(ds)
    for k in (0, 17, 53):
        np.testing.assert_array_equal(vol[k], t["hu"][k].astype(np.float32))
    rep = dicom_report(ds)
    assert rep["sheared"] and rep["kind"] == "sheared" and not rep["resampled"]
    assert rep["shear_magnitude_mm_per_slice"] == pytest.approx(0.793, abs=2e-3)


@needs_tilt
def test_tilt_resampled_is_rectangular_with_shear_removed():
    files = sorted(TILT.glob("*.dcm"))
    t = truth(files)
    ds = read_dicom_series(TILT, resample=True)
    assert isinstance(ds, pv.ImageData)
    assert ds.dimensions == (512, 512, 54)
    r, c, n, ipp = t["r"], t["c"], t["n"], t["ipp"]
    d = np.diff(ipp, axis=0)
    h = float(np.median(d @ n))
    inplane = d - np.outer(d @ n, n)
    rep = dicom_report(ds)
    assert rep["resampled"] and rep["geometry"] == "ImageData"
    assert rep["shear_removed_magnitude_mm_per_slice"] == pytest.approx(
        np.linalg.norm(inplane, axis=1).mean(), rel=1e-3
    )
    np.testing.assert_allclose(rep["shear_removed_mm_per_slice"], inplane.mean(axis=0), atol=2e-3)
    np.testing.assert_allclose(ds.direction_matrix, np.column_stack([r, c, n]), atol=1e-9)
    np.testing.assert_allclose(ds.origin, ipp[0], atol=1e-9)
    np.testing.assert_allclose(ds.spacing, (t["dc"], t["dr"], h), atol=1e-6)
    vol = volume(ds)
    # Independent bilinear sample of the source slice at the voxel centre's patient position.
    for k, j, i in [(0, 256, 256), (20, 100, 300), (53, 400, 50), (37, 250, 511)]:
        p = ipp[0] + i * t["dc"] * r + j * t["dr"] * c + k * h * n
        u, v = (p - ipp[k]) @ r / t["dc"], (p - ipp[k]) @ c / t["dr"]
        want = ndimage.map_coordinates(t["hu"][k], [[v], [u]], order=1)[0]
        assert vol[k, j, i] == pytest.approx(want, abs=2e-3)
    # Rows shifted in from outside the field of view are air and flagged.
    shift = -(ipp - ipp[0]) @ c / t["dr"]
    rows = np.arange(512)[None, :] + shift[:, None]
    outside = (rows < -1e-9) | (rows > 511 + 1e-9)
    assert rep["outside_fov_voxels"] == int(outside.sum()) * 512
    pad = ds["padding"].reshape(54, 512, 512)
    np.testing.assert_array_equal(pad.any(axis=2), outside)
    assert np.all(vol[pad == 1] == -1024)


@needs_philips
def test_missing_middle_slice_kept_error_or_resampled(philips, tmp_path):
    _, t, _ = philips
    gone = Path(t["files"][14]).name
    before, after = Path(t["files"][13]).name, Path(t["files"][15]).name
    copy_series(PHILIPS, tmp_path, skip={gone})
    ds = read_dicom_series(tmp_path)
    assert isinstance(ds, pv.StructuredGrid)
    assert ds.dimensions == (512, 512, 27)
    ipp = np.delete(t["ipp"], 14, axis=0)
    corners = ds.points.reshape(27, 512, 512, 3)[:, 0, 0]
    np.testing.assert_allclose(corners, ipp, atol=1e-9)
    np.testing.assert_allclose(ds.field_data["slice_positions"], ipp @ t["n"], atol=1e-9)
    rep = dicom_report(ds)
    assert rep["uneven_spacing"] and rep["kind"] == "uneven"
    assert [(Path(g["after"]).name, Path(g["before"]).name) for g in rep["gaps"]] == [
        (before, after)
    ]
    assert rep["gaps"][0]["step_mm"] == pytest.approx(10.0)

    with pytest.raises(InputError, match=f"{before}.*{after}"):
        read_dicom_series(tmp_path, gaps="error")
    with pytest.raises(InputError, match=f"{before}.*{after}"):
        read_dicom_series(tmp_path, gaps="error", resample=True)

    rs = read_dicom_series(tmp_path, resample=True)
    assert isinstance(rs, pv.ImageData)
    assert rs.dimensions == (512, 512, 28)
    assert rs.spacing[2] == pytest.approx(5.0, abs=1e-9)
    rep = dicom_report(rs)
    assert rep["resampled"]
    assert [
        (s["index"], [Path(f).name for f in s["between"]]) for s in rep["interpolated_slices"]
    ] == [(14, [before, after])]
    vol = volume(rs)
    np.testing.assert_allclose(vol[14], (t["hu"][13] + t["hu"][15]) / 2, atol=1e-3)
    for k in (0, 13, 15, 27):
        np.testing.assert_array_equal(vol[k], t["hu"][k].astype(np.float32))


@needs_philips
def test_duplicated_slice_names_both_files(tmp_path):
    copy_series(PHILIPS, tmp_path)
    shutil.copy(PHILIPS / "I100.dcm", tmp_path / "copy_of_I100.dcm")
    with pytest.raises(DicomSeriesError, match=r"duplicate") as err:
        read_dicom_series(tmp_path)
    assert "copy_of_I100.dcm" in str(err.value) and f"{os.sep}I100.dcm" in str(err.value)


@needs_philips
def test_strays_and_localizers_are_excluded_and_reported(philips, tmp_path):
    good = philips[2]
    copy_series(PHILIPS, tmp_path)
    (tmp_path / "README").write_text("not dicom\n")
    (tmp_path / "notes.txt").write_text("scan notes\n")
    (tmp_path / ".DS_Store").write_bytes(b"\0\1\2")
    (tmp_path / "sub").mkdir()
    dicomdir = pydicom.Dataset()
    dicomdir.file_meta = pydicom.dataset.FileMetaDataset()
    dicomdir.file_meta.MediaStorageSOPClassUID = "1.2.840.10008.1.3.10"
    dicomdir.file_meta.MediaStorageSOPInstanceUID = generate_uid()
    dicomdir.file_meta.TransferSyntaxUID = pydicom.uid.ExplicitVRLittleEndian
    dicomdir.DirectoryRecordSequence = []
    dicomdir.save_as(tmp_path / "DICOMDIR", enforce_file_format=True)

    src = pydicom.dcmread(PHILIPS / "I10.dcm")

    def variant(name, **changes):
        d = pydicom.dcmread(PHILIPS / "I10.dcm")
        d.SOPInstanceUID = generate_uid()
        for k, v in changes.items():
            if v is None:
                delattr(d, k)
            else:
                setattr(d, k, v)
        d.save_as(tmp_path / name)

    far = [float(v) for v in src.ImagePositionPatient]
    variant(
        "scout.dcm",
        ImageType=["ORIGINAL", "PRIMARY", "LOCALIZER"],
        ImagePositionPatient=[far[0], far[1], far[2] + 2.5],
    )
    variant("nopix.dcm", PixelData=None, ImagePositionPatient=[far[0], far[1], far[2] + 1.0])
    variant(
        "oblique.dcm",
        ImageOrientationPatient=[1, 0, 0, 0, 0, -1],
        ImagePositionPatient=[far[0], far[1], far[2] + 1.5],
    )
    small = np.zeros((256, 256), np.uint16)
    variant(
        "small.dcm",
        Rows=256,
        Columns=256,
        PixelData=small.tobytes(),
        ImagePositionPatient=[far[0], far[1], far[2] + 3.5],
    )

    ds = read_dicom_series(tmp_path)
    assert_same_dataset(ds, good)
    reasons = {Path(e["file"]).name: e["reason"] for e in dicom_report(ds)["excluded"]}
    assert "not a readable DICOM" in reasons["README"]
    assert "not a readable DICOM" in reasons["notes.txt"]
    assert reasons[".DS_Store"] == "hidden file"
    assert "directory" in reasons["sub"]
    assert "DICOMDIR" in reasons["DICOMDIR"]
    assert "no pixel data" in reasons["nopix.dcm"]
    assert "localizer" in reasons["scout.dcm"]
    assert "ImageOrientationPatient" in reasons["oblique.dcm"]
    assert "Rows/Columns" in reasons["small.dcm"]
    assert len(reasons) == 9


def test_nothing_usable_names_the_folder(tmp_path):
    (tmp_path / "README").write_text("nothing here")
    (tmp_path / "a.txt").write_text("x")
    with pytest.raises(InputError, match=f"{tmp_path}.*no DICOM image.*2 file"):
        read_dicom_series(tmp_path)


# ----------------------------------------------------------------------------- synthetic series


def test_two_series_default_largest_warns_and_series_uid_picks(tmp_path):
    rng = np.random.default_rng(0)
    big, small, mr = "1.2.826.0.1.3680043.8.498.10", "1.2.826.0.1.3680043.8.498.11", "1.2.3.99"
    write_series(
        tmp_path,
        random_raws(rng, 5),
        positions_along((0, 0, 0), AXIAL, [2] * 4),
        series_uid=big,
        names=[f"a{k}.dcm" for k in range(5)],
    )
    write_series(
        tmp_path,
        random_raws(rng, 3),
        positions_along((0, 0, 0), AXIAL, [3] * 2),
        series_uid=small,
        names=[f"b{k}.dcm" for k in range(3)],
    )
    write_series(
        tmp_path,
        random_raws(rng, 7),
        positions_along((0, 0, 0), AXIAL, [1] * 6),
        series_uid=mr,
        modality="MR",
        names=[f"m{k}.dcm" for k in range(7)],
    )
    with pytest.warns(UserWarning, match="3 series") as rec:
        ds = read_dicom_series(tmp_path)
    msg = str(rec[0].message)
    assert big in msg and small in msg and mr in msg and "MR" in msg
    rep = dicom_report(ds)
    assert rep["series_uid"] == big and ds.dimensions[2] == 5
    assert {o["uid"]: o["n_files"] for o in rep["other_series"]} == {small: 3, mr: 7}

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        other = read_dicom_series(tmp_path, series_uid=small)
    assert dicom_report(other)["series_uid"] == small and other.dimensions[2] == 3
    assert other.spacing[2] == pytest.approx(3.0)
    with pytest.raises(InputError, match=f"1.2.3.4.*{big}.*{small}"):
        read_dicom_series(tmp_path, series_uid="1.2.3.4")


def test_oblique_orientation_direction_matrix_and_points(tmp_path):
    rng = np.random.default_rng(1)
    a, b = np.radians(25), np.radians(-40)
    rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    rx = np.array([[1, 0, 0], [0, np.cos(b), -np.sin(b)], [0, np.sin(b), np.cos(b)]])
    iop = rotation_iop(rz @ rx)
    raws = random_raws(rng, 4)
    files = write_series(tmp_path, raws, positions_along((10, -20, 30), iop, [1.25] * 3), iop=iop)
    t = truth(files)
    ds = read_dicom_series(tmp_path)
    assert isinstance(ds, pv.ImageData)
    np.testing.assert_allclose(
        ds.direction_matrix, np.column_stack([t["r"], t["c"], t["n"]]), atol=1e-12
    )
    np.testing.assert_allclose(ds.spacing, (t["dc"], t["dr"], 1.25), atol=1e-9)
    np.testing.assert_allclose(
        ds.points.reshape(4, 16, 16, 3), expected_points(t, 16, 16), atol=1e-9
    )
    for k in range(4):
        np.testing.assert_array_equal(volume(ds)[k], t["hu"][k].astype(np.float32))


def test_synthetic_oblique_shear_exact_and_resampled(tmp_path):
    rng = np.random.default_rng(13)
    a = np.radians(30)
    rot = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    iop = rotation_iop(rot)
    r, c, n = rot[:, 0], rot[:, 1], rot[:, 2]
    shear = 0.3 * r - 0.45 * c  # mm per slice, in-plane: a gantry tilt in an odd direction
    raws = random_raws(rng, 5)
    files = write_series(
        tmp_path, raws, positions_along((5, 6, 7), iop, [2.0] * 4, shear=shear), iop=iop
    )
    t = truth(files)
    ds = read_dicom_series(tmp_path)
    assert isinstance(ds, pv.StructuredGrid)
    np.testing.assert_allclose(
        ds.points.reshape(5, 16, 16, 3), expected_points(t, 16, 16), atol=1e-9
    )
    rs = read_dicom_series(tmp_path, resample=True, padding="nan")
    rep = dicom_report(rs)
    assert isinstance(rs, pv.ImageData) and rep["resampled"]
    np.testing.assert_allclose(rep["shear_removed_mm_per_slice"], shear, atol=1e-9)
    np.testing.assert_allclose(rs.direction_matrix, np.column_stack([r, c, n]), atol=1e-9)
    vol = volume(rs)
    pad = rs["padding"].reshape(vol.shape) == 1
    ipp = t["ipp"]
    for k in range(5):
        j, i = np.meshgrid(np.arange(16), np.arange(16), indexing="ij")
        p = ipp[0] + (i[..., None] * t["dc"]) * r + (j[..., None] * t["dr"]) * c + k * 2.0 * n
        u = (p - ipp[k]) @ r / t["dc"]
        v = (p - ipp[k]) @ c / t["dr"]
        inside = (u >= -1e-9) & (u <= 15 + 1e-9) & (v >= -1e-9) & (v <= 15 + 1e-9)
        want = ndimage.map_coordinates(t["hu"][k], [v.ravel(), u.ravel()], order=1)
        np.testing.assert_allclose(vol[k][inside], want.reshape(16, 16)[inside], atol=1e-3)
        np.testing.assert_array_equal(pad[k], ~inside)
        assert np.all(np.isnan(vol[k][~inside]))
    assert rep["outside_fov_voxels"] == rep["padding_voxels"] == int(pad.sum()) > 0


def test_orientation_tie_is_an_error(tmp_path):
    rng = np.random.default_rng(14)
    uid = generate_uid()
    write_series(tmp_path, random_raws(rng, 1), [(0, 0, 0)], series_uid=uid, names=["a.dcm"])
    write_series(
        tmp_path,
        random_raws(rng, 1),
        [(0, 0, 1)],
        series_uid=uid,
        names=["b.dcm"],
        iop=(1, 0, 0, 0, 0, 1),
    )
    with pytest.raises(DicomSeriesError, match=r"no majority.*a\.dcm.*b\.dcm"):
        read_dicom_series(tmp_path)


def test_per_slice_rescale(tmp_path):
    rng = np.random.default_rng(2)
    raws = random_raws(rng, 3)
    files = write_series(
        tmp_path,
        raws,
        positions_along((0, 0, 0), AXIAL, [1, 1]),
        slopes=[1, 2, 0.5],
        intercepts=[-1024, -1000, 10],
    )
    vol = volume(read_dicom_series(files))
    for k, (sl, ic) in enumerate([(1, -1024), (2, -1000), (0.5, 10)]):
        np.testing.assert_array_equal(vol[k], (raws[k].astype(float) * sl + ic).astype(np.float32))


def test_zero_or_missing_rescale(tmp_path):
    rng = np.random.default_rng(21)
    raws = random_raws(rng, 2)
    files = write_series(tmp_path, raws, positions_along((0, 0, 0), AXIAL, [1]))
    d = pydicom.dcmread(files[0])
    del d.RescaleSlope, d.RescaleIntercept
    d.save_as(files[0])
    vol = volume(read_dicom_series(tmp_path))
    np.testing.assert_array_equal(vol[0], raws[0].astype(np.float32))  # identity when absent
    d.RescaleSlope = 0
    d.save_as(files[0])
    with pytest.raises(DicomSeriesError, match=r"slice000\.dcm: RescaleSlope 0"):
        read_dicom_series(tmp_path)


@pytest.mark.parametrize("mode", ["air", "nan"])
def test_padding_value_and_range(tmp_path, mode):
    rng = np.random.default_rng(3)
    raws = random_raws(rng, 2)
    raws[0][:3, :] = 3000
    raws[1][5, 5] = 3004
    raws[1][6, 6] = 2999  # just below the range: real data
    raws[1][7, 7] = 3006  # just above
    write_series(
        tmp_path,
        raws,
        positions_along((0, 0, 0), AXIAL, [1]),
        padding_value=3000,
        padding_limit=3005,
    )
    ds = read_dicom_series(tmp_path, padding=mode)
    pad = ds["padding"].reshape(2, 16, 16)
    assert ds["padding"].dtype == np.uint8
    expected = np.stack([(r >= 3000) & (r <= 3005) for r in raws])
    np.testing.assert_array_equal(pad == 1, expected)
    vol = volume(ds)
    if mode == "air":
        assert np.all(vol[expected] == -1024)
    else:
        assert np.all(np.isnan(vol[expected]))
    truth_hu = np.stack(raws).astype(np.float64) - 1024
    np.testing.assert_array_equal(vol[~expected], truth_hu[~expected].astype(np.float32))
    rep = dicom_report(ds)
    assert rep["padding_voxels"] == rep["stored_padding_voxels"] == int(expected.sum())


@pytest.mark.parametrize(("vr", "stored"), [("SS", -2000), ("US", 65536 - 2000)])
def test_signed_pixels_with_negative_padding(tmp_path, vr, stored):
    rng = np.random.default_rng(4)
    raws = random_raws(rng, 3, signed=True)
    raws[1][0, :] = -2000
    raws[2][1, 1] = -1999
    write_series(
        tmp_path,
        raws,
        positions_along((0, 0, 0), AXIAL, [2, 2]),
        intercepts=[0, 0, 0],
        padding_value=stored,
        padding_vr=vr,
    )
    ds = read_dicom_series(tmp_path, padding="nan")
    vol = volume(ds)
    stack = np.stack(raws).astype(np.float32)
    expected = np.stack(raws) == -2000
    np.testing.assert_array_equal(ds["padding"].reshape(3, 16, 16) == 1, expected)
    np.testing.assert_array_equal(vol[~expected], stack[~expected])
    assert vol[2, 1, 1] == -1999 and np.nanmin(vol) < -1000


def test_uneven_synthetic_spacing_true_positions_and_resample(tmp_path):
    rng = np.random.default_rng(5)
    raws = random_raws(rng, 5)
    files = write_series(tmp_path, raws, positions_along((0, 0, 0), AXIAL, [1, 1, 2.5, 1]))
    ds = read_dicom_series(files)
    assert isinstance(ds, pv.StructuredGrid)
    z = ds.points.reshape(5, 16, 16, 3)[:, 0, 0, 2]
    np.testing.assert_allclose(z, [0, 1, 2, 4.5, 5.5], atol=1e-12)
    rep = dicom_report(ds)
    assert rep["uneven_spacing"] and len(rep["gaps"]) == 1
    rs = read_dicom_series(files, resample=True)
    assert isinstance(rs, pv.ImageData) and rs.dimensions[2] == 6 and rs.spacing[2] == 1.0
    vol = volume(rs)
    hu = [r.astype(np.float64) - 1024 for r in raws]
    np.testing.assert_allclose(vol[3], hu[2] * 0.6 + hu[3] * 0.4, atol=1e-3)  # z = 3
    np.testing.assert_allclose(vol[4], hu[2] * 0.2 + hu[3] * 0.8, atol=1e-3)  # z = 4
    np.testing.assert_allclose(vol[5], hu[3] * 0.5 + hu[4] * 0.5, atol=1e-3)  # z = 5
    assert [s["index"] for s in dicom_report(rs)["interpolated_slices"]] == [3, 4, 5]


def test_rle_compressed_series_equals_native(tmp_path):
    rng = np.random.default_rng(6)
    raws = random_raws(rng, 3)
    pos = positions_along((0, 0, 0), AXIAL, [1, 1])
    uid = generate_uid()
    write_series(tmp_path / "native", raws, pos, series_uid=uid)
    write_series(tmp_path / "rle", raws, pos, series_uid=uid, compress=RLELossless)
    a, b = read_dicom_series(tmp_path / "native"), read_dicom_series(tmp_path / "rle")
    np.testing.assert_array_equal(a["HU"], b["HU"])
    assert dicom_report(b)["transfer_syntaxes"] == [RLELossless]


def test_missing_decoder_plugin_is_an_input_error(tmp_path, monkeypatch):
    rng = np.random.default_rng(7)
    files = write_series(
        tmp_path, random_raws(rng, 2), positions_along((0, 0, 0), AXIAL, [1]), compress=RLELossless
    )

    def no_plugin(ds):
        # pydicom 3 (pixels/common.py, CoderBase._validate_plugins) raises exactly this.
        raise RuntimeError(
            f"Unable to decompress '{RLELossless.name}' pixel data because all plugins are "
            "missing dependencies:\n\tgdcm - requires gdcm\n\tpylibjpeg - requires pylibjpeg "
            "and pylibjpeg-rle"
        )

    monkeypatch.setattr(dicom_mod, "_pixel_array", no_plugin)
    with pytest.raises(DicomDecoderError) as err:
        read_dicom_series(tmp_path)
    msg = str(err.value)
    assert str(sorted(files)[0]) in msg and RLELossless in msg and "RLE Lossless" in msg
    assert 'pip install "sciviz-gbuf[dicom]"' in msg
    assert isinstance(err.value.__cause__, RuntimeError)


def test_unavailable_decoder_detected_before_decoding(tmp_path, monkeypatch):
    rng = np.random.default_rng(8)
    write_series(
        tmp_path, random_raws(rng, 1), positions_along((0, 0, 0), AXIAL, []), compress=RLELossless
    )

    class Unavailable:
        is_available = False

    monkeypatch.setattr(pydicom.pixels, "get_decoder", lambda uid: Unavailable())
    with pytest.raises(InputError, match=r"slice000\.dcm.*RLE Lossless.*pip install"):
        read_dicom_series(tmp_path)


@pytest.mark.parametrize("tag", ["ImageOrientationPatient", "ImagePositionPatient", "PixelSpacing"])
def test_missing_geometry_tag_names_file_and_tag(tmp_path, tag):
    rng = np.random.default_rng(9)
    files = write_series(tmp_path, random_raws(rng, 3), positions_along((0, 0, 0), AXIAL, [1, 1]))
    d = pydicom.dcmread(files[1])
    delattr(d, tag)
    d.save_as(files[1])
    with pytest.raises(DicomSeriesError, match=rf"slice001\.dcm: {tag} missing"):
        read_dicom_series(tmp_path)


def test_multiframe_rejected(tmp_path):
    raw = np.zeros((16, 16), np.uint16)
    d = make_slice(raw, ipp=(0, 0, 0), series_uid=generate_uid())
    d.NumberOfFrames = 2
    d.PixelData = np.zeros((2, 16, 16), np.uint16).tobytes()
    d.save_as(tmp_path / "mf.dcm", enforce_file_format=True)
    with pytest.raises(DicomSeriesError, match=r"mf\.dcm: multi-frame.*not supported"):
        read_dicom_series(tmp_path / "mf.dcm")


def test_colour_slice_excluded(tmp_path):
    rng = np.random.default_rng(10)
    uid = generate_uid()
    raws = random_raws(rng, 3)
    write_series(tmp_path, raws, positions_along((0, 0, 0), AXIAL, [1, 1]), series_uid=uid)
    plain = read_dicom_series(tmp_path)
    d = make_slice(raws[0], ipp=(0, 0, 1.5), series_uid=uid)
    d.SamplesPerPixel, d.PhotometricInterpretation, d.PlanarConfiguration = 3, "RGB", 0
    d.BitsAllocated, d.BitsStored, d.HighBit = 8, 8, 7
    d.PixelData = np.zeros((16, 16, 3), np.uint8).tobytes()
    d.save_as(tmp_path / "rgb.dcm", enforce_file_format=True)
    ds = read_dicom_series(tmp_path)
    assert_same_dataset(ds, plain)
    reasons = {Path(e["file"]).name: e["reason"] for e in dicom_report(ds)["excluded"]}
    assert "colour" in reasons["rgb.dcm"]


def test_truncated_pixels_and_inconsistent_bits(tmp_path):
    rng = np.random.default_rng(11)
    files = write_series(
        tmp_path / "t", random_raws(rng, 3), positions_along((0, 0, 0), AXIAL, [1, 1])
    )
    d = pydicom.dcmread(files[2])
    d.PixelData = d.PixelData[:-10]
    d.save_as(files[2])
    with pytest.raises(DicomSeriesError, match=r"slice002\.dcm: pixel data holds 502 bytes"):
        read_dicom_series(tmp_path / "t")
    files = write_series(
        tmp_path / "b", random_raws(rng, 3), positions_along((0, 0, 0), AXIAL, [1, 1])
    )
    d = pydicom.dcmread(files[0])
    d.BitsAllocated, d.BitsStored, d.HighBit = 8, 8, 7
    d.PixelData = np.zeros((16, 16), np.uint8).tobytes()
    d.save_as(files[0])
    with pytest.raises(DicomSeriesError, match=r"BitsAllocated.*slice000\.dcm=8"):
        read_dicom_series(tmp_path / "b")


def test_inputs_never_modified_and_progress_bar(tmp_path):
    rng = np.random.default_rng(12)
    files = write_series(tmp_path, random_raws(rng, 3), positions_along((0, 0, 0), AXIAL, [1, 1]))
    before = digest(files)
    a = read_dicom_series(tmp_path, progress_bar=True)
    b = read_dicom_series(tmp_path)
    assert digest(files) == before
    assert_same_dataset(a, b)


def test_argument_errors(tmp_path):
    with pytest.raises(InputError, match="gaps"):
        read_dicom_series(tmp_path, gaps="fill")
    with pytest.raises(InputError, match="padding"):
        read_dicom_series(tmp_path, padding="zero")
    with pytest.raises(InputError, match="no such file"):
        read_dicom_series(tmp_path / "nope")
    with pytest.raises(InputError, match="empty"):
        read_dicom_series([])
    with pytest.raises(InputError, match="dicom_report"):
        dicom_report(pv.ImageData(dimensions=(2, 2, 2)))


# ----------------------------------------------------------------------------- pydicom corpus


@pytest.mark.parametrize("path", CORPUS, ids=[p.name for p in CORPUS])
def test_corpus_file_alone_reads_correctly_or_input_error(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            ds = read_dicom_series(path)
        except InputError:
            return
        ref = pydicom.dcmread(path)
        raw = ref.pixel_array
    assert raw.shape == (ref.Rows, ref.Columns)
    want = raw * float(ref.get("RescaleSlope", 1)) + float(ref.get("RescaleIntercept", 0))
    vol = volume(ds)
    assert vol.shape == (1, *raw.shape)
    valid = ds["padding"].reshape(vol.shape)[0] == 0 if "padding" in ds.point_data else True
    np.testing.assert_array_equal(vol[0][valid], want.astype(np.float32)[valid])
    np.testing.assert_allclose(ds.points[0], [float(v) for v in ref.ImagePositionPatient])


@needs_philips
@pytest.mark.parametrize("path", CORPUS, ids=[p.name for p in CORPUS])
def test_corpus_file_mixed_into_good_series(path, philips, tmp_path):
    _, _, good = philips
    for f in sorted(PHILIPS.glob("*.dcm")):
        os.symlink(f, tmp_path / f.name)
    shutil.copy(path, tmp_path / ("zz_" + path.name))
    same_series = False
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            header = pydicom.dcmread(path, stop_before_pixels=True)
            same_series = header.get("SeriesInstanceUID") == dicom_report(good)["series_uid"]
        except Exception:  # not DICOM at all: certainly not the same series
            pass
        if same_series:
            try:
                read_dicom_series(tmp_path)
            except InputError:
                pass
            return
        ds = read_dicom_series(tmp_path)
    assert_same_dataset(ds, good)


# ----------------------------------------------------------------------------- Hypothesis


unit = st.floats(-1, 1, allow_nan=False)


@st.composite
def series_specs(draw):
    q = np.array([draw(unit) for _ in range(4)])
    if np.linalg.norm(q) < 0.1:
        q = np.array([1.0, 0, 0, 0])
    w, x, y, z = q / np.linalg.norm(q)
    rot = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    return {
        "iop": rotation_iop(rot),
        "n": draw(st.integers(1, 6)),
        "rows": draw(st.integers(2, 12)),
        "cols": draw(st.integers(2, 12)),
        "spacing": (draw(st.floats(0.2, 2.0)), draw(st.floats(0.2, 2.0))),
        "step": draw(st.floats(0.5, 5.0)),
        "origin": [draw(st.floats(-300, 300)) for _ in range(3)],
        "seed": draw(st.integers(0, 2**31)),
    }


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(spec=series_specs())
def test_hypothesis_random_series_round_trip(spec):
    rng = np.random.default_rng(spec["seed"])
    n = spec["n"]
    raws = random_raws(rng, n, spec["rows"], spec["cols"])
    slopes = rng.choice([1.0, 0.5, 2.0, 1.25], n)
    intercepts = rng.choice([-1024.0, 0.0, -1000.5], n)
    with tempfile.TemporaryDirectory() as tmp:
        files = write_series(
            Path(tmp),
            raws,
            positions_along(spec["origin"], spec["iop"], [spec["step"]] * (n - 1)),
            iop=spec["iop"],
            pixel_spacing=spec["spacing"],
            slopes=slopes,
            intercepts=intercepts,
        )
        shuffled = list(files)
        random.Random(spec["seed"]).shuffle(shuffled)
        ds = read_dicom_series(shuffled)
        t = truth(files)
    assert ds.dimensions == (spec["cols"], spec["rows"], n)
    np.testing.assert_allclose(
        ds.points.reshape(n, spec["rows"], spec["cols"], 3),
        expected_points(t, spec["cols"], spec["rows"]),
        atol=1e-6,
    )
    vol = volume(ds)
    for k in range(n):
        np.testing.assert_array_equal(vol[k], t["hu"][k].astype(np.float32))


CORRUPTIONS = [
    "delete_iop",
    "delete_ipp",
    "delete_ps",
    "rows_one",
    "rows_all",
    "nan_ipp",
    "text_ipp",
    "zero_spacing",
    "bad_iop",
]


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(kind=st.sampled_from(CORRUPTIONS), victim=st.integers(0, 2), seed=st.integers(0, 99))
def test_hypothesis_corrupt_headers_raise_input_error_only(kind, victim, seed):
    rng = np.random.default_rng(seed)
    with tempfile.TemporaryDirectory() as tmp:
        files = write_series(
            Path(tmp), random_raws(rng, 3), positions_along((0, 0, 0), AXIAL, [1, 1])
        )
        targets = files if kind == "rows_all" else [files[victim]]
        for f in targets:
            d = pydicom.dcmread(f)
            if kind.startswith("delete_"):
                delattr(
                    d,
                    {
                        "delete_iop": "ImageOrientationPatient",
                        "delete_ipp": "ImagePositionPatient",
                        "delete_ps": "PixelSpacing",
                    }[kind],
                )
            elif kind.startswith("rows_"):
                d.Rows = int(rng.choice([1, 8, 15, 17, 40]))
            elif kind in ("nan_ipp", "text_ipp"):
                d.ImagePositionPatient = [0, "99999.5", victim]
            elif kind == "zero_spacing":
                d.PixelSpacing = [0, 0.5]
            else:
                d.ImageOrientationPatient = [1, 0, 0, 1, 0, 0]
            d.save_as(f)
            if kind in ("nan_ipp", "text_ipp"):
                # pydicom refuses to write a bad DS: patch the bytes (same length).
                bad = b"  nan  " if kind == "nan_ipp" else b"abc.xyz"
                data = f.read_bytes()
                assert data.count(b"99999.5") == 1
                f.write_bytes(data.replace(b"99999.5", bad))
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ds = read_dicom_series(tmp)
        except InputError:
            return
    # Reading may only succeed by leaving the corrupted slice out, and saying so.
    excluded = [e["file"] for e in dicom_report(ds)["excluded"]]
    assert [str(f) for f in targets] == excluded and ds.dimensions[2] == 2
