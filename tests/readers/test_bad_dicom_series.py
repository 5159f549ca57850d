"""DICOM series that lie or are damaged, through the ``ct`` command: one line naming the file,
exit 2, nothing written, before any large allocation (issue 20)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pydicom.uid import JPEG2000Lossless, generate_uid

from sciviz_gbuf.readers import read_dicom_series
from sciviz_gbuf.readers.dicom import DicomSeriesError
from tests.helpers.cli import assert_clean_failure, checksums, run_cli
from tests.helpers.dicom_factory import make_slice

N = 32


def _series(folder: Path, n: int = 6, *, edit=None, compress: str | None = None) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    uid = generate_uid()
    yy, xx = np.mgrid[0:N, 0:N]
    for k in range(n):
        ball = ((xx - N / 2) ** 2 + (yy - N / 2) ** 2 + (4.0 * (k - n / 2)) ** 2) < (N / 3) ** 2
        raw = np.where(ball, 1024 + 900, 1024 - 1000).astype(np.uint16)
        ds = make_slice(raw, ipp=(0.0, 0.0, 2.0 * k), series_uid=uid, instance=k + 1)
        if compress is not None:
            ds.compress(compress)
        if edit is not None:
            edit(ds, k)
        ds.save_as(folder / f"slice{k:03d}.dcm", enforce_file_format=True)
    return folder


def _rows(value):
    def edit(ds, k):
        ds.Rows = value

    return edit


def _truncate_j2k(ds, k):
    if k == 2:  # one damaged slice in the middle of the series
        from pydicom.encaps import encapsulate, generate_frames

        frame = next(generate_frames(ds.PixelData, number_of_frames=1))
        ds.PixelData = encapsulate([frame[: len(frame) * 2 // 3]])


def _garble_j2k(ds, k):
    if k == 1:
        from pydicom.encaps import encapsulate, generate_frames

        frame = bytearray(next(generate_frames(ds.PixelData, number_of_frames=1)))
        frame[:2] = b"\x00\x00"  # no start-of-codestream marker
        ds.PixelData = encapsulate([bytes(frame)])


CASES = {
    "rows_lie_65535": {"edit": _rows(65535)},
    "rows_lie_small": {"edit": _rows(N - 3)},
    "j2k_truncated": {"compress": JPEG2000Lossless, "edit": _truncate_j2k},
    "j2k_garbled": {"compress": JPEG2000Lossless, "edit": _garble_j2k},
    "single_slice": {"n": 1},
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_bad_series_is_one_clean_line(tmp_path, case):
    folder = _series(tmp_path / case, **CASES[case])
    before = checksums([folder])
    out = tmp_path / "ct.png"
    proc = run_cli(["ct", folder, "-o", out, "--size", "64x64", "--no-progress"], cwd=tmp_path)
    names = [folder.name] if case == "single_slice" else [f"slice{k:03d}" for k in range(6)]
    line = assert_clean_failure(proc, names=[*names, "volume"], outputs=[out], inputs=before)
    if case.startswith("j2k"):
        assert "JPEG 2000" in line
    if case == "single_slice":
        assert "slice" in line


def test_compressed_series_still_reads(tmp_path):
    """The JPEG 2000 check passes whole codestreams: the same series reads equal to native."""
    native = read_dicom_series(_series(tmp_path / "native"))
    j2k = read_dicom_series(_series(tmp_path / "j2k", compress=JPEG2000Lossless))
    assert np.array_equal(native["HU"], j2k["HU"])


def test_lying_rows_fail_before_the_volume_is_allocated(tmp_path):
    folder = _series(tmp_path / "lie", edit=_rows(65535))
    with pytest.raises(DicomSeriesError, match="pixel data holds"):
        read_dicom_series(folder)
