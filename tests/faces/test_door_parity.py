"""The same file and options give the same picture from every door (issue 46, point 1): the
dataset accessor (``mesh.gbuf``), the plotter component (``pl.gbuf``), ``sg.capture`` with the
recipes, the CLI and the explorer frame a y-up OFF and a z-up STL the same way, upright by
the file's convention, and ``up=`` is taken everywhere the CLI takes ``--up``.

The y-up model is a chair-like shape whose top must come out on top: a picture with the wrong
up axis differs from the right one by far more than antialiasing (checked, so the comparison
can fail).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import pyvista as pv
from PIL import Image

import sciviz_gbuf as sg
from sciviz_gbuf.apps.explorer import Explorer
from sciviz_gbuf.styles import illustrate
from tests.helpers.cli import run_cli

SIZE = (240, 180)


def _write_off(mesh: pv.PolyData, path: Path) -> None:
    """An OFF file as modelling tools write them (y up), by hand: no writer of ours involved."""
    tri = mesh.triangulate()
    faces = tri.faces.reshape(-1, 4)[:, 1:]
    lines = ["OFF", f"{tri.n_points} {len(faces)} 0"]
    lines += [f"{x:.6f} {y:.6f} {z:.6f}" for x, y, z in tri.points]
    lines += [f"3 {a} {b} {c}" for a, b, c in faces]
    path.write_text("\n".join(lines) + "\n")


def _chair(up: int) -> pv.PolyData:
    """A seat on four legs with a back rest, ``up`` the axis its legs stand along (1: y)."""
    parts = [pv.Box((-1, 1, -1, 1, 1.0, 1.2))]  # seat, z up
    parts += [pv.Box((x - 0.1, x + 0.1, y - 0.1, y + 0.1, 0, 1.0)) for x in (-0.9, 0.9)
              for y in (-0.9, 0.9)]  # fmt: skip
    parts.append(pv.Box((-1, 1, 0.8, 1.0, 1.2, 2.6)))  # back rest
    chair = pv.merge(parts).extract_surface(algorithm="dataset_surface").triangulate()
    if up == 1:  # z up -> y up: (x, y, z) -> (x, z, -y), a rotation
        pts = np.asarray(chair.points)
        chair.points = np.column_stack([pts[:, 0], pts[:, 2], -pts[:, 1]])
    return chair


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("doors")
    off = d / "chair.off"
    _write_off(_chair(1), off)
    stl = d / "chair.stl"
    _chair(2).save(stl)
    return {"off": off, "stl": stl}


def _cli_edges(path: Path, out: Path, *extra: str) -> np.ndarray:
    proc = run_cli(["edges", path, "-o", out, "--size", f"{SIZE[0]}x{SIZE[1]}", *extra])
    assert proc.returncode == 0, proc.stderr
    return np.asarray(Image.open(out).convert("RGB"))


def _rgb(img: pv.ImageData) -> np.ndarray:
    w, h, _ = img.dimensions
    return np.asarray(img.point_data["RGB"]).reshape(h, w, 3)[::-1]


def _u8(pic: np.ndarray) -> np.ndarray:
    """A picture as the PNG holds it (illustrate returns floats in [0, 1])."""
    if pic.dtype == np.uint8:
        return pic[..., :3]
    return np.round(np.clip(pic[..., :3], 0, 1) * 255).astype(np.uint8)


def _ink(pic: np.ndarray) -> np.ndarray:
    """The drawn object: pixels not of the background colour (the top-left one)."""
    return np.any(np.abs(pic.astype(int) - pic[0, 0].astype(int)) > 24, axis=-1)


def _close(a: np.ndarray, b: np.ndarray) -> None:
    """Same picture within antialiasing: the object covers the same pixels (IoU) and the
    colours differ on few of them."""
    a, b = _u8(a), _u8(b)
    ia, ib = _ink(a), _ink(b)
    iou = (ia & ib).sum() / max((ia | ib).sum(), 1)
    assert iou > 0.97, iou
    diff = np.abs(a.astype(int) - b.astype(int)).max(axis=-1)
    assert (diff > 64).mean() < 0.01, (diff > 64).mean()


def _top_heavy(pic: np.ndarray) -> float:
    """Rows of the object's upper half over its lower half (the back rest is on top)."""
    rows = np.flatnonzero(_ink(pic).any(axis=1))
    mid = (rows[0] + rows[-1]) // 2
    ink = _ink(pic)
    return ink[: mid + 1].sum() / max(ink[mid + 1 :].sum(), 1)


@pytest.mark.parametrize("kind", ["off", "stl"])
def test_every_door_draws_the_same_picture(files, kind, tmp_path):
    path = files[kind]
    up = "y" if kind == "off" else "z"
    cli = _cli_edges(path, tmp_path / "cli.png")
    assert _ink(cli).mean() > 0.05  # something drawn

    read = sg.readers.read_mesh(path)  # keeps the file: its convention is the default
    _close(_rgb(read.gbuf.edges(window_size=SIZE)), cli)
    # pv.read does not record the file: up= says what the CLI reads from the suffix
    _close(_rgb(pv.read(path).gbuf.edges(window_size=SIZE, up=up)), cli)
    # sg.capture + the style, the recipe route
    gb = sg.capture(read, window_size=SIZE, supersample=2, camera="iso")
    _close(illustrate(gb, style="enhance"), cli)
    # the plotter component with the named view and the file's up axis
    pl = pv.Plotter(off_screen=True, window_size=list(SIZE))
    pl.add_mesh(pv.read(path))
    img = pl.gbuf.capture(camera="iso", up=up, supersample=2)
    pl.close()
    _close(illustrate(img.gbuf.gbuffer(), style="enhance"), cli)
    # the accessor's capture takes up= as sg.capture does
    same = pv.read(path).gbuf.capture(window_size=SIZE, supersample=2, up=up)
    _close(illustrate(same.gbuf.gbuffer(), style="enhance"), cli)


def test_the_wrong_up_axis_is_caught_by_the_comparison(files, tmp_path):
    cli = _cli_edges(files["off"], tmp_path / "cli.png")
    wrong = _rgb(pv.read(files["off"]).gbuf.edges(window_size=SIZE, up="z"))
    with pytest.raises(AssertionError):
        _close(wrong, cli)
    assert _top_heavy(cli) > 1.0  # upright: the back rest is in the upper half


def test_up_overrides_the_file_convention_on_every_door(files, tmp_path):
    # --up z on the OFF: the CLI, the accessor and sg.capture turn it the same way
    cli = _cli_edges(files["off"], tmp_path / "cli.png", "--up", "z")
    _close(_rgb(sg.readers.read_mesh(files["off"]).gbuf.edges(window_size=SIZE, up="z")), cli)
    gb = sg.capture(sg.readers.read_mesh(files["off"]), window_size=SIZE, supersample=2, up="z")
    _close(illustrate(gb, style="enhance"), cli)


def test_explorer_orbits_around_the_files_up_axis(files):
    for kind, axis in (("off", 1), ("stl", 2)):
        ex = Explorer.from_file(files[kind], window_size=SIZE)
        view_up = np.asarray(ex.camera_tuple()[2], float)
        assert np.argmax(np.abs(view_up)) == axis, (kind, view_up)
        ex.close() if hasattr(ex, "close") else None


def test_accessor_refuses_a_view_on_a_captured_image(files):
    img = sg.readers.read_mesh(files["stl"]).gbuf.capture(window_size=SIZE)
    with pytest.raises(sg.InputError, match="up"):
        img.gbuf.edges(up="y")
    with pytest.raises(sg.InputError, match="up: expected"):
        pv.read(files["stl"]).gbuf.edges(up="w")
