"""GBuffer save/load round trips and to_pyvista."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv

import sciviz_gbuf as sg


@pytest.fixture(scope="module")
def gbuf():
    nut = pv.examples.load_nut()
    nut.point_data["height"] = np.asarray(nut.points[:, 2])
    nut.cell_data["cid"] = np.arange(nut.n_cells, dtype=np.int32)
    plane = pv.Plane(center=(80, -80, -110), i_size=80, j_size=80)  # has texture coordinates
    return sg.capture([nut, plane], window_size=(96, 72), scalars=["height", "cid"], supersample=2)


def _assert_identical(a: sg.GBuffer, b: sg.GBuffer) -> None:
    ca, cb = a.channels(), b.channels()
    assert list(ca) == list(cb)
    for name in ca:
        assert ca[name].dtype == cb[name].dtype, name
        assert ca[name].shape == cb[name].shape, name
        # bit-identical, NaN payloads included
        assert ca[name].tobytes() == cb[name].tobytes(), name
    assert a.camera == b.camera
    assert a.supersample == b.supersample
    assert a.object_names == b.object_names


@pytest.mark.parametrize("suffix", [".npz", ".vti"])
def test_save_load_round_trip_is_bit_identical(gbuf, tmp_path, suffix):
    assert gbuf.uv is not None and set(gbuf.scalars) == {"height", "cid"}
    path = gbuf.save(tmp_path / f"g{suffix}")
    again = sg.GBuffer.load(path)
    _assert_identical(gbuf, again)
    # and a second generation too (nothing drifts)
    _assert_identical(again, sg.GBuffer.load(again.save(tmp_path / f"h{suffix}")))


def test_to_pyvista_orientation_and_arrays(gbuf):
    img = gbuf.to_pyvista()
    h, w = gbuf.shape
    assert img.dimensions == (w, h, 1)
    # VTK's first point is the bottom-left pixel
    assert np.array_equal(img.point_data["depth"][:w], gbuf.depth[-1], equal_nan=True)
    assert np.array_equal(
        img.point_data["normal"].reshape(h, w, 3)[::-1], gbuf.normal, equal_nan=True
    )
    assert "scalars:height" in img.point_data
    back = sg.GBuffer.from_pyvista(img)
    _assert_identical(gbuf, back)


def test_camera_record_recreates_the_view(gbuf):
    cam = gbuf.camera.to_vtk()
    assert cam.GetPosition() == pytest.approx(gbuf.camera.position)
    g2 = sg.capture(pv.examples.load_nut(), window_size=(96, 72), camera=gbuf.camera)
    # the same camera reproduces the nut's pixels (object 0) where the plane did not occlude
    both = (gbuf.downsample(gbuf.object_id.astype(np.float32)) == 0) & g2.mask
    assert both.sum() > 100


def test_load_rejects_bad_files(tmp_path):
    with pytest.raises(sg.InputError, match="no such"):
        sg.GBuffer.load(tmp_path / "missing.npz")
    bad = tmp_path / "other.npz"
    np.savez(bad, x=np.zeros(3))
    with pytest.raises(sg.InputError, match=r"other\.npz"):
        sg.GBuffer.load(bad)
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"not a zip")
    with pytest.raises(sg.InputError, match=r"junk\.npz"):
        sg.GBuffer.load(junk)
    with pytest.raises(sg.InputError, match=r"\.png"):
        sg.GBuffer.load(_touch(tmp_path / "x.png"))
    img = pv.ImageData(dimensions=(3, 3, 1))
    img.save(tmp_path / "plain.vti")
    with pytest.raises(sg.InputError, match=r"plain\.vti"):
        sg.GBuffer.load(tmp_path / "plain.vti")


def test_save_rejects_unknown_suffix(gbuf, tmp_path):
    with pytest.raises(sg.InputError, match=r"\.npz or \.vti"):
        gbuf.save(tmp_path / "g.h5")


def _touch(p):
    p.write_bytes(b"")
    return p
