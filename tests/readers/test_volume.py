"""NRRD, MetaImage and NIfTI volumes: geometry round trips into DICOM's LPS frame, and refusals.

Each file is written here, with an oblique voxel frame, anisotropic spacing and an offset
origin, by a writer independent of the reader (the headers by hand; NIfTI by nibabel), and
read back: every voxel must land where the file's own transform puts it, with its value.
"""

from __future__ import annotations

import gzip
import zlib

import nibabel
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOImage import vtkMetaImageReader, vtkNrrdReader

from sciviz_gbuf.errors import InputError
from sciviz_gbuf.readers import kind_of, read_scene, read_volume
from sciviz_gbuf.recipes.medical import ct_surface
from tests.helpers.cli import assert_clean_failure, run_cli

SHAPE = (7, 5, 4)  # i, j, k
SPACING = np.array([0.7, 0.9, 2.5])
ROT = Rotation.from_euler("zyx", [20.0, -10.0, 5.0], degrees=True).as_matrix()
ORIGIN = np.array([-40.0, 12.5, 300.0])
RAS = np.diag([-1.0, -1.0, 1.0])


def _values() -> np.ndarray:
    i, j, k = np.indices(SHAPE)
    return (i * 100 + j * 10 + k - 500).astype(np.int16)  # every voxel its own value


def _expected_points() -> np.ndarray:
    """LPS position of voxel (i, j, k), in the Fortran order of ImageData's points."""
    idx = np.indices(SHAPE).reshape(3, -1, order="F").T.astype(np.float64)
    return ORIGIN + (idx * SPACING) @ ROT.T


def _check(ds, f32: bool = False) -> None:
    """``f32``: the file stores its transform in float32 (NIfTI)."""
    assert ds.dimensions == SHAPE
    np.testing.assert_allclose(ds.spacing, SPACING, rtol=1e-6 if f32 else 1e-9)
    np.testing.assert_allclose(ds.points, _expected_points(), atol=1e-4 if f32 else 1e-6)
    np.testing.assert_array_equal(ds["HU"], _values().ravel(order="F").astype(np.float32))


def _vec(v) -> str:
    return "(" + ",".join(repr(float(x)) for x in v) + ")"


def _write_nrrd(path, space="left-posterior-superior", encoding="raw", detached=False, **extra):
    to_space = np.eye(3) if space.startswith("left-p") else RAS
    cols = (to_space @ ROT) * SPACING
    data = _values().astype(">i2").tobytes(order="F")
    if encoding == "gzip":
        data = gzip.compress(data)
    lines = [
        "NRRD0004",
        "# written by the test",
        "type: short",
        "dimension: 3",
        f"space: {space}",
        f"sizes: {' '.join(map(str, SHAPE))}",
        "space directions: " + " ".join(_vec(cols[:, d]) for d in range(3)),
        "kinds: domain domain domain",
        "endian: big",
        f"encoding: {encoding}",
        f"space origin: {_vec(to_space @ ORIGIN)}",
        "units:=mm",
    ] + [f"{k.replace('_', ' ')}: {v}" for k, v in extra.items()]
    if detached:
        raw = path.with_suffix(".raw" if encoding == "raw" else ".raw.gz")
        raw.write_bytes(data)
        lines.append(f"data file: {raw.name}")
        path.write_text("\n".join(lines) + "\n")
    else:
        path.write_bytes(("\n".join(lines) + "\n\n").encode() + data)
    return path


def _write_meta(path, compressed=False, detached=False):
    data = _values().astype("<i2").tobytes(order="F")
    if compressed:
        data = zlib.compress(data)
    head = [
        "ObjectType = Image",
        "NDims = 3",
        "BinaryData = True",
        "BinaryDataByteOrderMSB = False",
        f"CompressedData = {compressed}",
        # ITK: row d is the direction of axis d
        "TransformMatrix = " + " ".join(repr(float(v)) for v in ROT.T.ravel()),
        "Offset = " + " ".join(repr(float(v)) for v in ORIGIN),
        "AnatomicalOrientation = RAI",
        "ElementSpacing = " + " ".join(repr(float(v)) for v in SPACING),
        f"DimSize = {' '.join(map(str, SHAPE))}",
        "ElementType = MET_SHORT",
    ]
    if detached:
        raw = path.with_suffix(".raw")
        raw.write_bytes(data)
        path.write_text("\n".join([*head, f"ElementDataFile = {raw.name}"]) + "\n")
    else:
        path.write_bytes(("\n".join([*head, "ElementDataFile = LOCAL"]) + "\n").encode() + data)
    return path


def _write_nifti(path, slope=1.0, inter=0.0):
    affine = np.eye(4)
    affine[:3, :3] = RAS @ ROT * SPACING
    affine[:3, 3] = RAS @ ORIGIN
    img = nibabel.Nifti1Image(((_values() - inter) / slope).astype(np.float32), affine)
    img.set_sform(affine, code=1)
    img.set_qform(affine, code=1)
    nibabel.save(img, str(path))
    return path


@pytest.mark.parametrize(
    ("name", "kw"),
    [
        ("a.nrrd", {}),
        ("b.nrrd", {"space": "right-anterior-superior", "encoding": "gzip"}),
        ("c.nhdr", {"detached": True}),
        ("d.nhdr", {"detached": True, "encoding": "gzip"}),
    ],
)
def test_nrrd_round_trip(tmp_path, name, kw):
    path = _write_nrrd(tmp_path / name, **kw)
    before = path.read_bytes()
    ds = read_volume(path)
    _check(ds)
    assert path.read_bytes() == before  # read-only
    assert kind_of(path) == "volume"
    assert read_scene(path)[1] == "volume"


@pytest.mark.parametrize(
    ("name", "kw"),
    [("a.mha", {}), ("b.mha", {"compressed": True}), ("c.mhd", {"detached": True})],
)
def test_metaimage_round_trip(tmp_path, name, kw):
    ds = read_volume(_write_meta(tmp_path / name, **kw))
    _check(ds)


@pytest.mark.parametrize("name", ["a.nii", "b.nii.gz"])
def test_nifti_round_trip(tmp_path, name):
    path = _write_nifti(tmp_path / name)
    assert kind_of(path) == "volume"
    _check(read_volume(path), f32=True)


def test_nifti_scaling_is_applied(tmp_path):
    path = tmp_path / "scaled.nii"
    affine = np.diag([1.0, 1.0, 1.0, 1.0])
    img = nibabel.Nifti1Image(np.arange(24, dtype=np.int16).reshape(2, 3, 4), affine)
    img.header.set_slope_inter(2.0, -1024.0)
    nibabel.save(img, str(path))
    ds = read_volume(path)
    want = np.arange(24).reshape(2, 3, 4) * 2.0 - 1024.0
    np.testing.assert_allclose(ds["HU"], want.ravel(order="F"))
    # RAS identity -> LPS: x and y flip
    np.testing.assert_allclose(ds.direction_matrix, np.diag([-1.0, -1.0, 1.0]))


def test_values_and_spacing_agree_with_vtk_readers(tmp_path):
    """VTK's own readers (which ignore the direction) as an independent reference: the same
    values in the same order (vtkNrrdReader takes the first axis of this file for components,
    so only the MetaImage reader's grid is compared)."""
    for path, reader in (
        (_write_nrrd(tmp_path / "v.nrrd"), vtkNrrdReader()),
        (_write_meta(tmp_path / "v.mha"), vtkMetaImageReader()),
    ):
        reader.SetFileName(str(path))
        reader.Update()
        out = reader.GetOutput()
        ref = vtk_to_numpy(out.GetPointData().GetScalars()).astype(np.float32).ravel()
        ds = read_volume(path)
        np.testing.assert_array_equal(ds["HU"], ref)
        if isinstance(reader, vtkMetaImageReader):
            assert tuple(out.GetDimensions()) == ds.dimensions
            np.testing.assert_allclose(np.abs(out.GetSpacing()), SPACING, rtol=1e-6)


def test_broken_volume_files_are_refused_by_name(tmp_path):
    good = _write_nrrd(tmp_path / "g.nrrd").read_bytes()
    cases = {
        "short.nrrd": good[:-10],
        "magic.nrrd": b"NOTNRRD\n\n" + good[10:],
        "enc.nrrd": good.replace(b"encoding: raw", b"encoding: bzip2"),
        "type.nrrd": good.replace(b"type: short", b"type: quaternion"),
        "huge.nrrd": good.replace(b"sizes: 7 5 4", b"sizes: 70000 50000 4000"),
        "space.nrrd": good.replace(b"space: left-posterior-superior", b"space: scanner-xyz"),
        "gz.nrrd": good.replace(b"encoding: raw", b"encoding: gzip"),  # raw bytes, not gzip
    }
    for name, blob in cases.items():
        path = tmp_path / name
        path.write_bytes(blob)
        with pytest.raises(InputError, match=name):
            read_volume(path)
    meta = tmp_path / "m.mhd"
    meta.write_text(
        "NDims = 3\nDimSize = 2 2 2\nElementType = MET_SHORT\nElementDataFile = no.raw\n"
    )
    with pytest.raises(InputError, match=r"no\.raw"):
        read_volume(meta)
    vec = tmp_path / "vec.mha"
    vec.write_bytes(
        b"NDims = 3\nDimSize = 2 2 2\nElementNumberOfChannels = 3\nElementType = MET_FLOAT\n"
        b"ElementDataFile = LOCAL\n" + bytes(96)
    )
    with pytest.raises(InputError, match="single-channel"):
        read_volume(vec)
    bad_nii = tmp_path / "bad.nii.gz"
    bad_nii.write_bytes(b"\x1f\x8b not really")
    with pytest.raises(InputError, match=r"bad\.nii\.gz"):
        read_volume(bad_nii)
    with pytest.raises(InputError, match="no such file"):
        read_volume(tmp_path / "missing.nrrd")


def _ball(path):
    """A bone ball (1000 HU in air) in a NIfTI file, 2 mm voxels, oblique."""
    n = 24
    z, y, x = np.mgrid[:n, :n, :n] - (n - 1) / 2.0
    vol = np.where(x**2 + y**2 + z**2 < 8.0**2, 1000.0, -1000.0).astype(np.float32)
    affine = np.eye(4)
    affine[:3, :3] = RAS @ ROT * 2.0
    nibabel.save(nibabel.Nifti1Image(vol, affine), str(path))
    return path


def test_ct_surface_of_a_volume_file_is_the_ball(tmp_path):
    surf = ct_surface(_ball(tmp_path / "ball.nii.gz"))
    centre = np.asarray(surf.points).mean(axis=0)
    r = np.linalg.norm(np.asarray(surf.points) - centre, axis=1)
    assert abs(np.median(r) - 16.0) < 1.0  # 8 voxels of 2 mm


def test_cli_ct_reads_a_volume_file_and_mesh_refuses_it(tmp_path):
    ball = _ball(tmp_path / "ball.nii.gz")
    out = tmp_path / "ct.png"
    proc = run_cli(["ct", ball, "-o", out, "--size", "96x96", "--supersample", "1"])
    assert proc.returncode == 0, proc.stderr
    assert out.is_file()
    bad = tmp_path / "m.png"
    proc = run_cli(["mesh", ball, "-o", bad])
    line = assert_clean_failure(proc, names=ball.name, outputs=[bad])
    assert "volume" in line and "ct" in line


def test_cli_mesh_reads_an_off_file(tmp_path):
    off = tmp_path / "tetra.off"
    off.write_text("OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n")
    out = tmp_path / "t.png"
    proc = run_cli(["mesh", off, "-o", out, "--size", "120x90", "--supersample", "1"])
    assert proc.returncode == 0, proc.stderr
    assert out.is_file()


@settings(
    max_examples=80, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(data=st.data(), which=st.sampled_from(["nrrd", "mha"]))
def test_corrupted_headers_give_a_volume_or_an_input_error(tmp_path, data, which):
    src = tmp_path / f"src.{which}"
    (_write_nrrd if which == "nrrd" else _write_meta)(src)
    blob = bytearray(src.read_bytes())
    head = blob.index(b"\n\n") if which == "nrrd" else blob.index(b"LOCAL\n")
    for _ in range(data.draw(st.integers(1, 4))):
        at = data.draw(st.integers(0, head))
        blob[at] = data.draw(st.sampled_from(b"0123456789 -.:=()\nx\x00\xff"))
    path = tmp_path / f"bad.{which}"
    path.write_bytes(bytes(blob))
    try:
        ds = read_volume(path)
    except InputError as exc:
        assert "bad." in str(exc)
        return
    assert ds.n_points == len(ds["HU"]) and np.isfinite(ds.points).all()


def test_explorer_shows_a_volume_file_as_its_bone_surface(tmp_path):
    from sciviz_gbuf.apps.explorer import Explorer

    e = Explorer.from_file(_ball(tmp_path / "ball.nii.gz"), window_size=(120, 90))
    assert e.kind == "dicom"  # a CT volume: its bone surface, seen as DICOM is
    e.render_image({"style": "toon"})
    assert e.gbuffer.mask.mean() > 0.1
