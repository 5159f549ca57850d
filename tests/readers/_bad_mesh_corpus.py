"""A corpus of bad mesh files, one per way a file can be broken, in every format users have.

Each case is ``(case_id, file_name, content)``: the content is built from a small valid sphere
written by PyVista itself, then truncated, bit-flipped, given a lying header, connectivity past
the vertex array or below zero, NaN/inf coordinates, only zero-area triangles, only lines or
vertices, or nothing at all. Built in memory (deterministic), written to ``tmp_path`` by tests.
"""

from __future__ import annotations

import re
import struct
import tempfile
from pathlib import Path

import numpy as np
import pyvista as pv

__all__ = ["CASES", "build_corpus", "valid_files"]


def _sphere() -> pv.PolyData:
    s = pv.Sphere(theta_resolution=6, phi_resolution=5)
    s.clear_data()
    return s


def _save(mesh: pv.DataSet, name: str, **kwargs) -> bytes:
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / name
        mesh.save(p, **kwargs)
        return p.read_bytes()


def valid_files() -> dict[str, bytes]:
    """A good small sphere in each format: ``file name -> bytes``."""
    s = _sphere()
    return {
        "stl_bin.stl": _save(s, "a.stl", binary=True),
        "stl_ascii.stl": _save(s, "a.stl", binary=False),
        "ply_bin.ply": _save(s, "a.ply", binary=True),
        "ply_ascii.ply": _save(s, "a.ply", binary=False),
        "obj.obj": _save(s, "a.obj"),
        "vtp_bin.vtp": _save(s, "a.vtp", binary=True),
        "vtp_ascii.vtp": _save(s, "a.vtp", binary=False),
        "vtu_bin.vtu": _save(s.cast_to_unstructured_grid(), "a.vtu", binary=True),
        "vtk_ascii.vtk": _save(s, "a.vtk", binary=False),
        "vtk_bin.vtk": _save(s, "a.vtk", binary=True),
        "vtk_ug_ascii.vtk": _save(s.cast_to_unstructured_grid(), "a.vtk", binary=False),
    }


def _flip(data: bytes, fraction: float, count: int = 16) -> bytes:
    """``count`` bytes inverted from ``fraction`` of the file on (after any text header)."""
    b = bytearray(data)
    start = int(len(b) * fraction)
    for i in range(start, min(start + count, len(b))):
        b[i] ^= 0xFF
    return bytes(b)


def _ascii_ply(vertices: np.ndarray, faces: list[list[int]], extra_header: str = "") -> bytes:
    head = (
        f"ply\nformat ascii 1.0\nelement vertex {len(vertices)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\n{extra_header}"
        "end_header\n"
    )
    body = "".join(" ".join(repr(float(c)) for c in v) + "\n" for v in vertices)
    body += "".join(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in faces)
    return (head + body).encode()


def _binary_ply(vertices: np.ndarray, faces: list[list[int]], n_vertex_header: int | None = None):
    n_v = len(vertices) if n_vertex_header is None else n_vertex_header
    head = (
        f"ply\nformat binary_little_endian 1.0\nelement vertex {n_v}\n"
        "property float x\nproperty float y\nproperty float z\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    ).encode()
    body = np.asarray(vertices, dtype="<f4").tobytes()
    for f in faces:
        body += struct.pack("<B", len(f)) + np.asarray(f, dtype="<i4").tobytes()
    return head + body


def _obj(vertices: np.ndarray, faces: list[list[int]], lines: list[list[int]] = ()) -> bytes:
    text = "".join("v " + " ".join(repr(float(c)) for c in v) + "\n" for v in vertices)
    text += "".join("f " + " ".join(map(str, f)) + "\n" for f in faces)
    text += "".join("l " + " ".join(map(str, ln)) + "\n" for ln in lines)
    return text.encode()


def _legacy_vtk(vertices: np.ndarray, cells: dict[str, list[list[int]]]) -> bytes:
    """Legacy ASCII polydata in the classic (pre-5.1) cell layout: ``n size`` then ``k i j``."""
    out = ["# vtk DataFile Version 4.2", "bad", "ASCII", "DATASET POLYDATA"]
    out.append(f"POINTS {len(vertices)} float")
    out += [" ".join(repr(float(c)) for c in v) for v in vertices]
    for kind, cs in cells.items():
        out.append(f"{kind} {len(cs)} {sum(len(c) + 1 for c in cs)}")
        out += [f"{len(c)} " + " ".join(map(str, c)) for c in cs]
    return ("\n".join(out) + "\n").encode()


def _ascii_stl(triangles: np.ndarray) -> bytes:
    out = ["solid bad"]
    for t in triangles:
        out += ["facet normal 0 0 0", "outer loop"]
        out += ["vertex " + " ".join(repr(float(c)) for c in v) for v in t]
        out += ["endloop", "endfacet"]
    out.append("endsolid bad")
    return ("\n".join(out) + "\n").encode()


def _vtp(points: np.ndarray, conn: list[int], offsets: list[int], kind: str = "Polys") -> bytes:
    """An ASCII VTP with the given connectivity (numbers written as given, no checks)."""
    n = {k: 0 for k in ("Verts", "Lines", "Strips", "Polys")}
    n[kind] = len(offsets)
    attrs = " ".join(f'NumberOf{k}="{v}"' for k, v in n.items())
    pts = " ".join(repr(float(c)) for c in np.ravel(points))
    return (
        '<?xml version="1.0"?>\n'
        '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">\n'
        f'<PolyData><Piece NumberOfPoints="{len(points)}" {attrs}>\n'
        '<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">'
        f"{pts}</DataArray></Points>\n"
        f"<{kind}>"
        '<DataArray type="Int64" Name="connectivity" format="ascii">'
        f"{' '.join(map(str, conn))}</DataArray>"
        '<DataArray type="Int64" Name="offsets" format="ascii">'
        f"{' '.join(map(str, offsets))}</DataArray>"
        f"</{kind}>\n</Piece></PolyData></VTKFile>\n"
    ).encode()


def _vtu(points: np.ndarray, conn: list[int], offsets: list[int], types: list[int]) -> bytes:
    pts = " ".join(repr(float(c)) for c in np.ravel(points))
    return (
        '<?xml version="1.0"?>\n'
        '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
        'header_type="UInt64">\n'
        f'<UnstructuredGrid><Piece NumberOfPoints="{len(points)}" NumberOfCells="{len(types)}">\n'
        '<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">'
        f"{pts}</DataArray></Points>\n<Cells>"
        '<DataArray type="Int64" Name="connectivity" format="ascii">'
        f"{' '.join(map(str, conn))}</DataArray>"
        '<DataArray type="Int64" Name="offsets" format="ascii">'
        f"{' '.join(map(str, offsets))}</DataArray>"
        '<DataArray type="UInt8" Name="types" format="ascii">'
        f"{' '.join(map(str, types))}</DataArray>"
        "</Cells>\n</Piece></UnstructuredGrid></VTKFile>\n"
    ).encode()


def _replace(data: bytes, pattern: bytes, new: bytes) -> bytes:
    out, n = re.subn(pattern, new, data, count=1)
    assert n == 1, pattern
    return out


def build_corpus() -> list[tuple[str, str, bytes]]:
    """Every bad file: ``(case_id, file_name, content)``."""
    good = valid_files()
    s = _sphere()
    v = np.asarray(s.points, dtype=np.float64)
    f = [list(map(int, c)) for c in s.faces.reshape(-1, 4)[:, 1:]]
    n = len(v)
    tri = v[np.array(f)]
    cases: list[tuple[str, str, bytes]] = []

    # Every format: empty, truncated at several points, bytes inverted.
    for name, data in good.items():
        stem, suffix = name.rsplit(".", 1)
        cases.append((f"{stem}-empty", f"empty.{suffix}", b""))
        for frac in (0.05, 0.3, 0.6, 0.97):
            cases.append(
                (f"{stem}-cut{int(frac * 100)}", f"cut.{suffix}", data[: int(len(data) * frac)])
            )
        for frac in (0.4, 0.8):
            cases.append((f"{stem}-flip{int(frac * 100)}", f"flip.{suffix}", _flip(data, frac)))

    # Lying headers / huge declared counts.
    stl = good["stl_bin.stl"]
    cases.append(("stl-count-1e9", "huge.stl", stl[:80] + struct.pack("<I", 10**9) + stl[84:]))
    cases.append(("stl-count-short", "short.stl", stl[:80] + struct.pack("<I", 3) + stl[84:]))
    cases.append(("ply_bin-vertex-1e9", "huge.ply", _binary_ply(v, f, n_vertex_header=10**9)))
    cases.append(
        (
            "ply_ascii-vertex-1e9",
            "huge.ply",
            _replace(good["ply_ascii.ply"], rb"element vertex \d+", b"element vertex 1000000000"),
        )
    )
    cases.append(
        (
            "ply_bin-face-1e9",
            "huge.ply",
            _replace(good["ply_bin.ply"], rb"element face \d+", b"element face 1000000000"),
        )
    )
    cases.append(
        (
            "vtk_ascii-points-1e9",
            "huge.vtk",
            _replace(good["vtk_ascii.vtk"], rb"POINTS \d+", b"POINTS 1000000000"),
        )
    )
    cases.append(
        (
            "vtk_bin-points-1e9",
            "huge.vtk",
            _replace(good["vtk_bin.vtk"], rb"POINTS \d+", b"POINTS 1000000000"),
        )
    )
    cases.append(
        (
            "vtk_bin-polygons-1e9",
            "huge.vtk",
            _replace(good["vtk_bin.vtk"], rb"POLYGONS \d+ \d+", b"POLYGONS 1000000000 3000000000"),
        )
    )
    cases.append(
        (
            "vtp-points-1e9",
            "huge.vtp",
            _replace(
                good["vtp_ascii.vtp"], rb'NumberOfPoints="\d+"', b'NumberOfPoints="1000000000"'
            ),
        )
    )
    cases.append(
        (
            "vtp-polys-1e9",
            "huge.vtp",
            _replace(good["vtp_ascii.vtp"], rb'NumberOfPolys="\d+"', b'NumberOfPolys="1000000000"'),
        )
    )
    cases.append(("ply-not-ply", "text.ply", b"this is not a ply file\n"))
    cases.append(("vtk-not-vtk", "text.vtk", b"# not a vtk file\nat all\n"))
    cases.append(("vtp-not-xml", "text.vtp", b"<?xml version='1.0'?><nothing/>\n"))
    cases.append(("stl-random", "noise.stl", np.random.default_rng(1).bytes(2000)))

    # Connectivity past the vertex array, and negative.
    far, neg = [f[0][0], f[0][1], n + 5], [f[0][0], f[0][1], -5]
    for tag, bad in (("past", far), ("negative", neg)):
        faces = [bad, *f[1:]]
        cases.append((f"ply_ascii-{tag}", f"{tag}.ply", _ascii_ply(v, faces)))
        cases.append((f"ply_bin-{tag}", f"{tag}.ply", _binary_ply(v, faces)))
        conn = [i for c in faces for i in c]
        offsets = list(range(3, 3 * len(faces) + 1, 3))
        cases.append((f"vtp-{tag}", f"{tag}.vtp", _vtp(v, conn, offsets)))
        cases.append((f"vtu-{tag}", f"{tag}.vtu", _vtu(v, conn, offsets, [5] * len(faces))))
        cases.append((f"vtk-{tag}", f"{tag}.vtk", _legacy_vtk(v, {"POLYGONS": faces})))
    # OBJ indices are 1-based; negative ones count back from the last vertex, so -(n+5) is out.
    cases.append(
        ("obj-past", "past.obj", _obj(v, [[1, 2, n + 5], *[[i + 1 for i in c] for c in f[1:]]]))
    )
    cases.append(
        (
            "obj-negative",
            "negative.obj",
            _obj(v, [[1, 2, -(n + 5)], *[[i + 1 for i in c] for c in f[1:]]]),
        )
    )
    cases.append(("obj-zero-index", "zero.obj", _obj(v, [[0, 1, 2]])))
    # Offsets that do not describe the connectivity array.
    conn = [i for c in f for i in c]
    offsets = list(range(3, 3 * len(f) + 1, 3))
    cases.append(("vtp-offsets-past", "offs.vtp", _vtp(v, conn, [*offsets[:-1], len(conn) + 40])))
    cases.append(("vtp-offsets-decreasing", "offs.vtp", _vtp(v, conn, [6, 3, *offsets[2:]])))
    cases.append(("vtu-type-mismatch", "type.vtu", _vtu(v, conn, offsets, [12] * len(f))))
    cases.append(("vtu-type-unknown", "type.vtu", _vtu(v, conn, offsets, [200] * len(f))))

    # NaN / inf coordinates.
    for tag, val in (("nan", np.nan), ("inf", np.inf)):
        w = v.copy()
        w[2, 1] = val
        cases.append((f"ply_ascii-{tag}", f"{tag}.ply", _ascii_ply(w, f)))
        cases.append((f"ply_bin-{tag}", f"{tag}.ply", _binary_ply(w, f)))
        cases.append((f"obj-{tag}", f"{tag}.obj", _obj(w, [[i + 1 for i in c] for c in f])))
        cases.append((f"vtk-{tag}", f"{tag}.vtk", _legacy_vtk(w, {"POLYGONS": f})))
        cases.append((f"stl_ascii-{tag}", f"{tag}.stl", _ascii_stl(w[np.array(f)])))
        cases.append((f"vtp-{tag}", f"{tag}.vtp", _vtp(w, conn, offsets)))

    # Only zero-area triangles: all corners on one point, or on one line.
    same = np.repeat(v[:1], n, axis=0)
    line = np.outer(np.linspace(0, 1, n), [1.0, 2.0, 3.0])
    for tag, w in (("point", same), ("collinear", line)):
        cases.append((f"ply_ascii-zeroarea-{tag}", f"flat-{tag}.ply", _ascii_ply(w, f)))
        cases.append(
            (f"obj-zeroarea-{tag}", f"flat-{tag}.obj", _obj(w, [[i + 1 for i in c] for c in f]))
        )
        cases.append((f"stl_ascii-zeroarea-{tag}", f"flat-{tag}.stl", _ascii_stl(w[np.array(f)])))
        cases.append(
            (
                f"stl_bin-zeroarea-{tag}",
                f"flat-{tag}.stl",
                _save(pv.PolyData(w, s.faces), "a.stl", binary=True),
            )
        )
    del tri

    # Only lines or only vertices: nothing to draw.
    cases.append(("vtk-lines-only", "lines.vtk", _legacy_vtk(v, {"LINES": [[0, 1, 2], [3, 4]]})))
    cases.append(
        ("vtk-verts-only", "verts.vtk", _legacy_vtk(v, {"VERTICES": [[i] for i in range(n)]}))
    )
    cases.append(("obj-lines-only", "lines.obj", _obj(v, [], [[1, 2, 3], [4, 5]])))
    cases.append(("vtp-lines-only", "lines.vtp", _save(pv.Line(resolution=4), "a.vtp")))
    cases.append(("ply-points-only", "points.ply", _save(pv.PolyData(v), "a.ply", binary=False)))
    cases.append(
        ("vtu-points-only", "points.vtu", _vtu(v, list(range(n)), list(range(1, n + 1)), [1] * n))
    )
    # OFF is read by meshio (a dependency): its faults, as for the other formats
    cases.append(("off-cut", "mesh.off", b"OFF\n3 1 0\n0 0 0\n1 0\n"))
    cases.append(("off-past", "mesh.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"))
    return cases


CASES = build_corpus()
