"""The sciviz-gbuf command line and the mesh reader, on real data."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import pyvista as pv
from PIL import Image

import sciviz_gbuf as sg
from sciviz_gbuf.cli import main
from sciviz_gbuf.readers import read_mesh


def test_capture_and_info_on_the_cad_part(shared_data, tmp_path, capsys):
    stl = shared_data / "meshes" / "vtkdata_42400-IDGH.stl"
    before = stl.read_bytes()
    out = tmp_path / "part.npz"
    assert (
        main(
            ["capture", str(stl), "-o", str(out), "--size", "200x150", "--view", "xy", "--parallel"]
        )
        == 0
    )
    g = sg.GBuffer.load(out)
    assert g.shape == (150, 200) and g.camera.parallel_projection
    mesh = read_mesh(stl)
    assert g.cell_id[g.mask].max() < mesh.n_cells
    # looking down -z in parallel projection: world x/y of a pixel is its position on screen
    xs = g.world[..., 0][g.mask]
    assert xs.min() >= mesh.bounds[0] - 1e-3 and xs.max() <= mesh.bounds[1] + 1e-3
    assert stl.read_bytes() == before  # input file untouched
    assert main(["info", str(out)]) == 0
    assert "cell_id" in capsys.readouterr().out


def test_cli_errors_are_clear(tmp_path, capsys):
    assert main(["capture", str(tmp_path / "none.stl"), "-o", str(tmp_path / "x.npz")]) == 2
    assert "none.stl: no such mesh file" in capsys.readouterr().err
    bad = tmp_path / "bad.stl"
    bad.write_text("solid nothing\nendsolid nothing\n")
    assert main(["capture", str(bad), "-o", str(tmp_path / "x.npz")]) == 2
    assert "bad.stl" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["capture", "a.stl", "-o", "x.npz", "--size", "12by4"])


def test_read_mesh_rejects_unknown_format(tmp_path):
    f = tmp_path / "mesh.xyz123"
    f.write_text("1 2 3\n")
    with pytest.raises(sg.InputError, match=r"mesh\.xyz123"):
        read_mesh(f)


def test_python_m_entry_point():
    r = subprocess.run(
        [sys.executable, "-m", "sciviz_gbuf", "--version"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert r.returncode == 0 and sg.__version__ in r.stdout


def test_read_mesh_returns_the_points(shared_data):
    m = read_mesh(shared_data / "meshes" / "vtkdata_42400-IDGH.stl")
    assert m.n_cells == 11036
    assert np.isfinite(np.asarray(m.points)).all()


# ---------------------------------------------------------------------------- edges
def _png(path):
    with Image.open(path) as im:
        return im.mode, im.size, np.asarray(im)


def test_edges_on_the_cad_part(shared_data, tmp_path, capsys):
    stl = shared_data / "meshes" / "vtkdata_42400-IDGH.stl"
    before = stl.read_bytes()
    out = tmp_path / "part.png"
    assert main(["edges", str(stl), "-o", str(out), "--size", "320x240"]) == 0
    assert "wrote" in capsys.readouterr().out
    mode, size, px = _png(out)
    assert (mode, size) == ("RGB", (320, 240))
    grey = px.mean(axis=2)
    assert (grey == 255).mean() > 0.3  # white paper around the part
    assert (grey < 40).sum() > 200  # black profile lines
    assert len(np.unique(grey)) > 50  # and a shade in between
    assert stl.read_bytes() == before


@pytest.mark.parametrize(
    ("suffix", "options", "mode"),
    [
        (".vtp", [], "RGB"),
        (".vtp", ["--style", "fig7", "--operator", "c1", "--width", "1.5"], "RGB"),
        (".ply", ["--style", "lines", "--view", "xz", "--parallel", "--supersample", "1"], "RGB"),
        (".ply", ["--style", "edgemap", "--crease-angle", "20", "--depth-jump", "2"], "RGBA"),
    ],
)
def test_edges_on_written_meshes(tmp_path, suffix, options, mode):
    mesh = (
        pv.Cube(x_length=2.0, y_length=1.0, z_length=0.5)
        .triangulate()
        .merge(pv.Sphere(radius=0.4, center=(0.0, 0.0, 0.6)))
    )
    path = tmp_path / f"shape{suffix}"
    mesh.save(path)
    out = tmp_path / "shape.png"
    assert main(["edges", str(path), "-o", str(out), "--size", "200x150", *options]) == 0
    got_mode, size, px = _png(out)
    assert (got_mode, size) == (mode, (200, 150))
    if mode == "RGBA":  # the edge map: profile in alpha, inner edges (the cube's) in RGB
        assert px[..., 3].max() == 255 and px[..., 0].max() == 255
        assert (px[..., 3] == 0).mean() > 0.5
    else:
        assert len(np.unique(px)) > 2


def test_edges_lines_follow_the_sphere_silhouette(tmp_path):
    """Black lines on white: ink on the projected outline of a sphere and nowhere else."""
    centre, radius = np.array([0.3, -0.2, 0.5]), 1.0
    sphere = pv.Sphere(radius=radius, center=centre, theta_resolution=96, phi_resolution=96)
    path = tmp_path / "sphere.ply"
    sphere.save(path)
    w, h = 240, 200
    out = tmp_path / "sphere.png"
    args = ["edges", str(path), "-o", str(out), "--size", f"{w}x{h}", "--view", "xy"]
    assert main([*args, "--parallel", "--style", "lines"]) == 0
    _, size, px = _png(out)
    assert size == (w, h)
    ink = 1.0 - px.astype(float).mean(axis=2) / 255.0
    # The camera of that view (fitted to the bounds, looking down -z at their centre): the
    # sphere's outline is a circle about the image centre, radius R / (2 parallel_scale / h).
    cam = sg.capture(sphere, window_size=(w, h), camera="xy", parallel_projection=True).camera
    assert np.allclose(cam.focal_point, centre, atol=1e-6)
    r_px = radius * h / (2.0 * cam.parallel_scale)
    assert 40 < r_px < 100
    rows, cols = np.mgrid[:h, :w]
    dist = np.hypot(cols + 0.5 - w / 2, rows + 0.5 - h / 2)
    # (an antialiased line one output pixel wide may fall on two pixels with half the ink each)
    lines = ink >= 0.45
    assert np.abs(dist[ink > 0.1] - r_px).max() <= 1.5
    assert ink[np.abs(dist - r_px) > 2.0].max() < 0.05  # no facet or other lines anywhere else
    # and the outline is closed: ink in every 5 degree sector
    angles = np.degrees(np.arctan2(rows + 0.5 - h / 2, cols + 0.5 - w / 2))[lines]
    assert len(np.unique(np.floor((angles + 180) / 5))) == 72


@pytest.mark.parametrize(
    ("options", "word"),
    [
        (["--size", "12by4"], "--size"),
        (["--size", "0x100"], "--size"),
        (["--width", "0.5"], "--width"),
        (["--width", "wide"], "--width"),
        (["--crease-angle", "200"], "--crease-angle"),
        (["--crease-angle", "nan"], "--crease-angle"),
        (["--depth-jump", "-1"], "--depth-jump"),
        (["--supersample", "0"], "--supersample"),
        (["--supersample", "1.5"], "--supersample"),
        (["--view", "top"], "--view"),
        (["--style", "sketch"], "--style"),
        (["--operator", "sobel"], "--operator"),
    ],
)
def test_edges_bad_options_exit_2(tmp_path, capsys, options, word):
    mesh = tmp_path / "cube.vtp"
    pv.Cube().save(mesh)
    with pytest.raises(SystemExit) as info:
        main(["edges", str(mesh), "-o", str(tmp_path / "x.png"), *options])
    assert info.value.code == 2
    assert word in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


def test_edges_bad_files_exit_2(tmp_path, capsys):
    out = str(tmp_path / "x.png")
    assert main(["edges", str(tmp_path / "none.stl"), "-o", out]) == 2
    assert "none.stl: no such mesh file" in capsys.readouterr().err
    bad = tmp_path / "bad.stl"
    bad.write_text("solid nothing\nendsolid nothing\n")
    assert main(["edges", str(bad), "-o", out]) == 2
    assert "bad.stl" in capsys.readouterr().err
    mesh = tmp_path / "cube.vtp"
    pv.Cube().save(mesh)
    assert main(["edges", str(mesh), "-o", str(tmp_path / "x.jpg")]) == 2
    assert "--output" in capsys.readouterr().err
    assert main(["edges", str(mesh), "-o", str(tmp_path / "no" / "x.png")]) == 2
    assert "--output" in capsys.readouterr().err
    too_big = ["--size", "9000x100", "--supersample", "2"]
    assert main(["edges", str(mesh), "-o", out, *too_big]) == 2
    assert "supersample" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


def test_topo_geographic_and_projected_flags(tmp_path, capsys):
    """A grid without a CRS whose cells look like degrees: taken as degrees with one warning
    line naming the CLI's own switch; --geographic / --projected decide without a warning,
    and metres give another relief than degrees (cells 1000x smaller)."""
    y, x = np.mgrid[0:40, 0:50]
    z = 1500 + 40 * np.sin(x / 6.0) * np.cos(y / 7.0)
    asc = tmp_path / "deg.asc"
    body = "\n".join(" ".join(f"{v:.2f}" for v in row) for row in z)
    asc.write_text(
        "ncols 50\nnrows 40\nxllcorner -105.5\nyllcorner 40.1\ncellsize 0.000833333\n"
        f"NODATA_value -9999\n{body}\n"
    )
    outs = {}
    for flag in (None, "--geographic", "--projected"):
        out = tmp_path / f"{flag or 'auto'}.png"
        assert main(["topo", str(asc), "-o", str(out), *([flag] if flag else [])]) == 0
        err = capsys.readouterr().err
        lines = [ln for ln in err.splitlines() if ln.strip()]
        if flag is None:
            assert len(lines) == 1 and "warning" in lines[0] and "--projected" in lines[0]
        else:
            assert lines == [], err
        outs[flag] = np.asarray(Image.open(out))
    np.testing.assert_array_equal(outs[None], outs["--geographic"])
    assert not np.array_equal(outs["--geographic"], outs["--projected"])
    with pytest.raises(SystemExit):
        main(["topo", str(asc), "-o", str(tmp_path / "x.png"), "--geographic", "--projected"])


def test_the_command_line_loads_no_heavy_library_before_its_first_line():
    # The first line of a long command comes before VTK, PyVista and numba load (they take
    # seconds): importing the CLI and the package imports none of them.
    code = (
        "import sys, sciviz_gbuf, sciviz_gbuf.cli\n"
        "print(sorted(m for m in ('vtk', 'pyvista', 'numba', 'matplotlib') if m in sys.modules))"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert r.stdout.strip() == "[]"


def test_a_long_command_says_it_is_starting_first(capsys, tmp_path):
    a_file = tmp_path / "a_file"
    a_file.write_text("not a folder")
    assert main(["demo", "--progress", "-o", str(a_file)]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == "sciviz-gbuf demo: starting (loading VTK, PyVista and numba) ..."
    assert lines[-1] == (
        f"sciviz-gbuf demo: error: output: {str(a_file)!r} is a file; expected a folder "
        "(new or existing)"
    )
    assert len(lines) == 2 and a_file.read_text() == "not a folder"
    assert main(["demo", "--no-progress", "-o", str(a_file)]) == 2
    assert "starting" not in capsys.readouterr().err


def test_the_package_exports_resolve_lazily():
    import sciviz_gbuf as sg

    for name in sg.__all__:
        assert getattr(sg, name) is not None
    assert sg.filters.contour_lines is not None and "capture" in dir(sg)
    with pytest.raises(AttributeError):
        _ = sg.no_such_name


_LOADED = """
import sys
from sciviz_gbuf.cli import main
try:
    main(sys.argv[1:])
except SystemExit:  # --help
    pass
heavy = sorted(m for m in ("pyvista", "vtkmodules", "distributed", "trame", "numba", "dask")
               if m in sys.modules)
print("LOADED", ",".join(heavy))
"""


def _heavy_modules_of(args: list[str]) -> list[str]:
    r = subprocess.run([sys.executable, "-c", _LOADED, *args], capture_output=True, text=True,
                       check=False, timeout=600)  # fmt: skip
    line = next((t for t in r.stdout.splitlines() if t.startswith("LOADED")), None)
    assert line is not None, r.stderr
    return [m for m in line.removeprefix("LOADED").strip().split(",") if m]


def test_plan_view_maps_do_not_load_vtk(tmp_path):
    """``topo --help`` imports none of the libraries of the work (numba, dask, VTK): the
    command line builds only the named command's parser, and the command's work is a module
    of its own. A topographic map of a GeoTIFF imports neither PyVista nor VTK (nor
    dask.distributed): the packages import their names on first use."""
    rasterio = pytest.importorskip("rasterio")
    from rasterio.transform import from_origin

    dem = tmp_path / "dem.tif"
    z = np.add.outer(np.arange(64.0), np.arange(48.0)).astype(np.float32) * 5.0
    profile = {"driver": "GTiff", "width": 48, "height": 64, "count": 1, "dtype": "float32",
               "crs": "EPSG:32613", "transform": from_origin(4e5, 4.5e6, 10.0, 10.0)}  # fmt: skip
    with rasterio.open(dem, "w", **profile) as f:
        f.write(z, 1)
    assert _heavy_modules_of(["topo", "--help"]) == []
    assert _heavy_modules_of(["birdseye", "--help"]) == []
    out = tmp_path / "map.png"
    loaded = _heavy_modules_of(["topo", str(dem), "-o", str(out), "--no-progress"])
    assert not {"pyvista", "vtkmodules", "distributed", "trame"} & set(loaded), loaded
    assert out.exists()
