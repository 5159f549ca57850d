"""Bezier patch sets (``.bpt``) -> :class:`PatchSet`: analytic positions, normals, curvatures.

Saito & Takahashi 1990 (§4.5) render curved surfaces from exact normals and curvatures; a
tensor-product Bezier patch gives both analytically. :func:`read_patches` reads the plain-text
``.bpt`` format used for the Utah teapot, :meth:`PatchSet.to_mesh` tessellates the patches with
analytic per-point normals, curvatures and ``(u, v)``, and :func:`parametric_mesh` prepares a
PyVista parametric surface (torus, ellipsoid, ...) the same way, with mesh-based curvature.

The ``.bpt`` format
-------------------
::

    <patch count>
    du dv                 # degrees of patch 1 (each >= 1)
    x y z                 # (du + 1) * (dv + 1) control points, one per line
    ...
    du dv                 # patch 2
    ...

Control points are listed row by row: ``P[0, 0], P[0, 1], ..., P[0, dv], P[1, 0], ...``, i.e.
the u index i (0..du) is the row and the v index j (0..dv) varies fastest (the classic Newell
teapot layout; ``du`` counts rows). For bicubic files the geometry does not tell the two orders
apart: the choice fixes which index is u and so the orientation ``Su x Sv``. With it, every
patch of the shared ``teapot.bpt`` and ``sphere.bpt`` faces inward (adjacent teapot patches are
consistently oriented; the lid tip's normal is (0, 0, -1), the bottom centre's (0, 0, 1)).
Separators are spaces, tabs or commas (``3,3``,
``0.0,0.0,-1.0``), numbers may use E-notation, and blank lines and ``#`` comments (to the end of
the line) are ignored. Anything after the last patch is an error.
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import _validate
from ..errors import InputError
from . import _bezier
from ._bezier import PatchEval

if TYPE_CHECKING:
    import pyvista

__all__ = ["PatchEval", "PatchSet", "parametric_mesh", "read_patches"]

_SEPARATORS = re.compile(r"[\s,]+")
# ASCII only: float() would also take "1_0", "nan", "infinity" and non-ASCII digits.
_INT = re.compile(r"\+?[0-9]{1,18}", re.ASCII)  # int() refuses > 4300 digits
_FLOAT = re.compile(r"[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?", re.ASCII)
_NONFINITE = re.compile(r"[+-]?(nan|inf|infinity)", re.IGNORECASE)
# Differences of control points times the degree must stay finite in float64.
_MAX_COORDINATE = 1e150


class PatchSet:
    """A set of tensor-product Bezier patches of any degrees (>= 1 in u and v).

    Build one with :func:`read_patches` or :meth:`from_control_nets`.

    Attributes
    ----------
    nets : list of numpy.ndarray
        float64 control nets of shape ``(du + 1, dv + 1, 3)``; ``nets[k][i, j]`` is the control
        point with u index i and v index j (read-only arrays).
    source : str or None
        The file read, or None for in-memory nets.
    """

    def __init__(self, nets: list[np.ndarray], source: str | None = None) -> None:
        self.nets = nets
        self.source = source

    @classmethod
    def from_control_nets(cls, nets: Sequence[Any], *, source: str | None = None) -> PatchSet:
        """A patch set from control nets, each array-like of shape ``(du + 1, dv + 1, 3)``.

        Raises
        ------
        InputError
            No nets, a net not numeric, of the wrong shape, of degree < 1, not finite, or with
        coordinates beyond +-1e150.
        """
        where = source or "control nets"
        try:
            items = list(nets)
        except TypeError as exc:
            raise InputError(f"{where}: expected a sequence of control nets ({exc})") from exc
        if not items:
            raise InputError(f"{where}: expected at least one control net, got none")
        out = []
        for k, net in enumerate(items):
            try:
                arr = np.array(net, dtype=np.float64)
            except (TypeError, ValueError) as exc:
                raise InputError(f"{where}: net {k} is not a numeric array ({exc})") from exc
            if arr.ndim != 3 or arr.shape[2] != 3:
                raise InputError(
                    f"{where}: net {k} must have shape (du + 1, dv + 1, 3), got {arr.shape}"
                )
            if arr.shape[0] < 2 or arr.shape[1] < 2:
                raise InputError(
                    f"{where}: net {k} has degrees {(arr.shape[0] - 1, arr.shape[1] - 1)};"
                    " each degree must be >= 1"
                )
            if not np.all(np.isfinite(arr)):
                raise InputError(f"{where}: net {k} holds NaN or infinite coordinates")
            if np.abs(arr).max() > _MAX_COORDINATE:
                raise InputError(
                    f"{where}: net {k} has coordinates beyond +-{_MAX_COORDINATE:g}"
                    " (derivatives would overflow)"
                )
            arr.flags.writeable = False
            out.append(arr)
        return cls(out, source)

    def __len__(self) -> int:
        return len(self.nets)

    def __repr__(self) -> str:
        return f"PatchSet({len(self)} patches, degrees {sorted(set(self.degrees))})"

    @property
    def degrees(self) -> list[tuple[int, int]]:
        """``(du, dv)`` of each patch."""
        return [(n.shape[0] - 1, n.shape[1] - 1) for n in self.nets]

    @property
    def bounds(self) -> tuple[float, float, float, float, float, float]:
        """``(xmin, xmax, ymin, ymax, zmin, zmax)`` of all control points.

        The surface lies inside (convex-hull property); it is tight where the net touches it.
        """
        pts = np.concatenate([n.reshape(-1, 3) for n in self.nets])
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        return (
            float(lo[0]),
            float(hi[0]),
            float(lo[1]),
            float(hi[1]),
            float(lo[2]),
            float(hi[2]),
        )

    # -- evaluation ---------------------------------------------------------------------------

    def _net(self, i: int) -> np.ndarray:
        if isinstance(i, bool) or not isinstance(i, (int, np.integer)):
            raise InputError(f"patch index must be an integer, got {i!r}")
        if not -len(self) <= i < len(self):
            raise InputError(f"patch index {i} out of range for {len(self)} patches")
        return self.nets[i]

    @staticmethod
    def _params(u: Any, v: Any) -> tuple[np.ndarray, np.ndarray, tuple[int, ...]]:
        """Broadcast u, v to flat float64 arrays, checked to lie in [0, 1]."""
        try:
            uu, vv = np.broadcast_arrays(np.asarray(u, np.float64), np.asarray(v, np.float64))
        except (TypeError, ValueError) as exc:
            raise InputError(f"u and v must be numeric and broadcastable ({exc})") from exc
        shape = uu.shape
        uu, vv = uu.ravel().copy(), vv.ravel().copy()
        for name, a in (("u", uu), ("v", vv)):
            if not np.all(np.isfinite(a)) or np.any((a < -1e-12) | (a > 1 + 1e-12)):
                raise InputError(f"{name} must lie in [0, 1]")
            np.clip(a, 0.0, 1.0, out=a)
        return uu, vv, shape

    def evaluate(self, i: int, u: Any, v: Any, derivatives: int = 2) -> PatchEval:
        """Position and partial derivatives of patch i at parameters (u, v).

        Parameters
        ----------
        i : int
            Patch index.
        u, v : array_like
            Parameters in [0, 1], broadcast together (any shape).
        derivatives : {0, 1, 2}
            Highest derivative order computed.

        Returns
        -------
        PatchEval
            Named tuple ``(S, Su, Sv, Suu, Suv, Svv)``, each ``shape + (3,)`` float64, from the
            Bernstein form; orders above ``derivatives`` are None.
        """
        net = self._net(i)
        if (
            isinstance(derivatives, bool)
            or not isinstance(derivatives, (int, np.integer))
            or derivatives not in (0, 1, 2)
        ):
            raise InputError(f"derivatives must be 0, 1 or 2, got {derivatives!r}")
        uu, vv, shape = self._params(u, v)
        ev = _bezier.evaluate(net, uu, vv, derivatives)
        return PatchEval(*(None if a is None else a.reshape((*shape, 3)) for a in ev))

    def normals(self, i: int, u: Any, v: Any) -> np.ndarray:
        """Unit analytic normals ``Su x Sv / |Su x Sv|`` of patch i, shape ``shape + (3,)``.

        Where ``Su x Sv`` vanishes (collapsed edges: the teapot's lid tip and bottom centre, the
        sphere's poles) the limit normal from the patch interior is returned, from the Taylor
        expansion of ``Su x Sv`` towards the patch centre (``Su x Suv`` on a collapsed u-edge),
        else the normal nudged inward. Always finite and unit; see :func:`_bezier.normals`.
        """
        net = self._net(i)
        uu, vv, shape = self._params(u, v)
        return _bezier.normals(net, uu, vv).reshape((*shape, 3))

    def curvatures(
        self, i: int, u: Any, v: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Gaussian K, mean H, principal k1 >= k2 of patch i at (u, v), each of shape ``shape``.

        Analytic, from the first (E, F, G) and second (L, M, N, with the unit normal
        ``Su x Sv``) fundamental forms; H > 0 where the patch bends towards its normal. At
        degenerate points (``|Su x Sv|`` < 1e-6 of the net's squared size) they are evaluated at
        the parameter nudged 1e-5 towards the patch centre, approximating the limit.
        """
        net = self._net(i)
        uu, vv, shape = self._params(u, v)
        return tuple(a.reshape(shape) for a in _bezier.curvatures(net, uu, vv))

    # -- tessellation -------------------------------------------------------------------------

    def to_mesh(self, resolution: int | tuple[int, int] = 16) -> pyvista.PolyData:
        """Tessellate every patch on a regular ``(nu + 1) x (nv + 1)`` grid of (u, v).

        Parameters
        ----------
        resolution : int or (int, int)
            Grid intervals per patch, ``n`` or ``(nu, nv)``, each in [1, 4096] (at most
            ``LIMITS["resolution"]``), and at most ``LIMITS["mesh_points"]`` = 2**24 grid
            points over all patches.

        Returns
        -------
        pyvista.PolyData
            Triangles, two per grid cell; patch k's points come in block k, u index outer and v
            inner. Points on shared patch edges are not merged (each patch keeps its own
            analytic values), and collapsed edges give zero-area triangles. Each patch keeps its
            own orientation: triangles wind so their normal follows ``Su x Sv``; orientations
            are not made consistent across patches (renderers flip normals towards the viewer).
            Point arrays: ``"Normals"`` (float64 (N, 3), unit, analytic), ``"uv"`` (float64
            (N, 2), also the active texture coordinates), ``"gaussian_curvature"``,
            ``"mean_curvature"``, ``"k1"``, ``"k2"`` (float64); cell array ``"patch_id"``
            (int32).
        """
        import pyvista

        nu, nv = _resolution(resolution)
        points = len(self) * (nu + 1) * (nv + 1)
        if points > _validate.LIMITS["mesh_points"]:
            raise InputError(
                f"resolution: {nu}x{nv} per patch gives {points} points over {len(self)} "
                f"patches; expected at most {_validate.LIMITS['mesh_points']:g} "
                "(LIMITS['mesh_points'])"
            )
        # ~ points, normals, curvatures, uv and two triangles per point in float64 / int64
        _validate.check_memory(points * _MESH_BYTES_PER_POINT, "resolution", "the tessellation")
        gu, gv = np.meshgrid(np.linspace(0, 1, nu + 1), np.linspace(0, 1, nv + 1), indexing="ij")
        uu, vv = gu.ravel(), gv.ravel()
        # Grid cell (a, b) -> corners in counter-clockwise (u, v) order, so winding ~ Su x Sv.
        a, b = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
        p00 = (a * (nv + 1) + b).ravel()
        p10, p01 = p00 + (nv + 1), p00 + 1
        p11 = p10 + 1
        tris = np.concatenate(
            [np.stack([p00, p10, p11], axis=1), np.stack([p00, p11, p01], axis=1)]
        )
        per_patch = (nu + 1) * (nv + 1)
        points, normals, curv, faces = [], [], [], []
        for k, net in enumerate(self.nets):
            points.append(_bezier.evaluate(net, uu, vv, 0).S)
            normals.append(_bezier.normals(net, uu, vv))
            curv.append(np.stack(_bezier.curvatures(net, uu, vv), axis=1))
            faces.append(tris + k * per_patch)
        faces_arr = np.concatenate(faces)
        cells = np.hstack([np.full((len(faces_arr), 1), 3), faces_arr]).astype(np.int64)
        mesh = pyvista.PolyData(np.concatenate(points), faces=cells.ravel())
        curvs = np.concatenate(curv)
        uv = np.tile(np.stack([uu, vv], axis=1), (len(self), 1))
        mesh.point_data["Normals"] = np.concatenate(normals)
        mesh.point_data["uv"] = uv
        for col, name in enumerate(("gaussian_curvature", "mean_curvature", "k1", "k2")):
            mesh.point_data[name] = curvs[:, col]
        mesh.cell_data["patch_id"] = np.repeat(np.arange(len(self), dtype=np.int32), len(tris))
        mesh.active_texture_coordinates = uv
        mesh.point_data.active_normals_name = "Normals"
        return mesh


# Bytes per grid point of a tessellation, its arrays and the PolyData copy of them.
_MESH_BYTES_PER_POINT = 400


def _resolution(resolution: Any) -> tuple[int, int]:
    pair = resolution if isinstance(resolution, (tuple, list)) else (resolution, resolution)
    bound = int(_validate.LIMITS["resolution"])
    if len(pair) != 2 or not all(
        isinstance(r, (int, np.integer)) and not isinstance(r, bool) and 1 <= r <= bound
        for r in pair
    ):
        raise InputError(
            f"resolution: expected an integer in [1, {bound}] (LIMITS['resolution']) or a "
            f"pair of them, got {_validate.brief(resolution)}"
        )
    return int(pair[0]), int(pair[1])


# -- the .bpt reader --------------------------------------------------------------------------


def read_patches(path: str | os.PathLike) -> PatchSet:
    """Read a ``.bpt`` Bezier patch file (format in the module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        The file; read only, never modified.

    Returns
    -------
    PatchSet
        One net per patch, shape ``(du + 1, dv + 1, 3)``, in file order.

    Raises
    ------
    InputError
        Missing or unreadable file, or malformed content: the message names the file and the
        line (1-based) and says what was expected (empty file, bad count, degree < 1,
        non-numeric token, NaN/inf coordinate, wrong number of values on a line, file ending
        before all points, extra data after the last patch).
    """
    path = Path(path)
    try:
        with open(path, encoding="utf-8-sig") as fh:
            text = fh.read()
    except (OSError, ValueError) as exc:  # ValueError: undecodable bytes, NUL in path
        raise InputError(f"{path}: cannot read as a Bezier patch text file ({exc})") from exc
    lines = _content_lines(text)
    if not lines:
        raise InputError(f"{path}: empty file; expected a patch count on the first line")
    cursor = iter(lines)

    def next_line(expected: str) -> tuple[int, list[str]]:
        try:
            return next(cursor)
        except StopIteration:
            raise InputError(
                f"{path}: file ends early after line {lines[-1][0]}; expected {expected}"
            ) from None

    lineno, tokens = next_line("the patch count")
    count = _integers(path, lineno, tokens, 1, "the patch count (one integer >= 1)")[0]
    if count < 1:
        raise InputError(f"{path}, line {lineno}: bad patch count {count}; expected >= 1")
    nets = []
    for k in range(count):
        what = f"the degrees 'du dv' of patch {k + 1} of {count}"
        lineno, tokens = next_line(what)
        du, dv = _integers(path, lineno, tokens, 2, f"{what} (two integers >= 1)")
        if du < 1 or dv < 1:
            raise InputError(
                f"{path}, line {lineno}: patch {k + 1} has degrees ({du}, {dv}); each must be >= 1"
            )
        n_points = (du + 1) * (dv + 1)
        pts = []
        for p in range(n_points):
            what = f"control point {p + 1} of {n_points} ('x y z') of patch {k + 1}"
            lineno, tokens = next_line(what)
            pts.append(_point(path, lineno, tokens, what))
        nets.append(np.array(pts, dtype=np.float64).reshape(du + 1, dv + 1, 3))
    extra = next(cursor, None)
    if extra is not None:
        raise InputError(
            f"{path}, line {extra[0]}: unexpected data after the last of {count} patches"
            f" ({' '.join(extra[1])[:40]!r}); expected the end of the file"
        )
    return PatchSet.from_control_nets(nets, source=str(path))


def _content_lines(text: str) -> list[tuple[int, list[str]]]:
    """(1-based line number, tokens) of each line that is not blank or a comment."""
    out = []
    # split("\n") rather than splitlines(): \x0b, \x1c, \u2028 ... must not shift line numbers.
    for number, line in enumerate(text.split("\n"), start=1):
        tokens = [t for t in _SEPARATORS.split(line.split("#", 1)[0]) if t]
        if tokens:
            out.append((number, tokens))
    return out


def _integers(path: Path, lineno: int, tokens: list[str], n: int, expected: str) -> list[int]:
    if len(tokens) != n or not all(_INT.fullmatch(t) for t in tokens):
        raise InputError(
            f"{path}, line {lineno}: got {' '.join(tokens)[:40]!r}; expected {expected}"
        )
    return [int(t) for t in tokens]


def _point(path: Path, lineno: int, tokens: list[str], expected: str) -> list[float]:
    if len(tokens) != 3:
        raise InputError(
            f"{path}, line {lineno}: {len(tokens)} values ({' '.join(tokens)[:40]!r});"
            f" expected 3 coordinates for {expected}"
        )
    for t in tokens:
        if _NONFINITE.fullmatch(t):
            raise InputError(f"{path}, line {lineno}: coordinate {t!r} is NaN or infinite")
        if not _FLOAT.fullmatch(t):
            raise InputError(
                f"{path}, line {lineno}: non-numeric token {t[:20]!r}; expected {expected}"
            )
    values = [float(t) for t in tokens]
    if not all(np.isfinite(values)):
        raise InputError(f"{path}, line {lineno}: coordinate overflows to infinity")
    if max(abs(x) for x in values) > _MAX_COORDINATE:
        raise InputError(
            f"{path}, line {lineno}: coordinate beyond +-{_MAX_COORDINATE:g}; expected {expected}"
        )
    return values


# -- PyVista parametric surfaces --------------------------------------------------------------


def parametric_mesh(surface: Any, resolution: int = 100) -> pyvista.PolyData:
    """A PyVista/VTK parametric surface with ``"uv"``, normals and (mesh-based) curvatures.

    Parameters
    ----------
    surface : pyvista.PolyData, vtkParametricFunction or callable
        One of: a mesh already carrying texture coordinates (``pv.ParametricTorus(
        texture_coordinates=True)``); a VTK parametric function (``vtk.vtkParametricTorus()``),
        tessellated with vtkParametricFunctionSource with texture coordinates on; or a PyVista
        factory such as ``pv.ParametricTorus``, called with ``texture_coordinates=True``.
        ``pv.ParametricTorus()`` itself cannot be used: PyVista does not keep the
        parametric function, nor generate (u, v), so they cannot be recovered from it.
    resolution : int in [1, 4096], default: 100
        u and v resolution when tessellating a vtkParametricFunction; at most
        ``LIMITS["resolution"]`` = 4096.

    Returns
    -------
    pyvista.PolyData
        A copy with point arrays ``"uv"`` (float64 (N, 2), VTK's texture coordinates: the
        parameters rescaled to [0, 1] over the function's (u, v) range; also the active texture
        coordinates), ``"Normals"`` (VTK's, normalised; where VTK's vanish, e.g. at an
        ellipsoid's poles, the cell-winding normals of ``compute_normals``, else the mean of
        the neighbours' normals), and ``"gaussian_curvature"``,
        ``"mean_curvature"`` from ``mesh.curvature`` (discrete, mesh-based: not analytic, and
        unreliable on mesh boundaries and at merged seams).

    Raises
    ------
    InputError
        A mesh without texture coordinates, or an object of another kind.
    """
    import pyvista
    from vtkmodules.vtkCommonComputationalGeometry import vtkParametricFunction

    if isinstance(surface, vtkParametricFunction):
        resolution = _validate.count(resolution, "resolution", "resolution")
        mesh = pyvista.surface_from_para(
            surface, u_res=resolution, v_res=resolution, texture_coordinates=True
        )
    elif isinstance(surface, pyvista.PolyData):
        mesh = surface.copy()
    elif callable(surface):
        mesh = surface(texture_coordinates=True)
        if not isinstance(mesh, pyvista.PolyData):
            raise InputError(f"{surface!r} did not return a pyvista.PolyData")
    else:
        raise InputError(
            f"expected a pyvista.PolyData, a vtkParametricFunction or a PyVista Parametric*"
            f" factory, got {type(surface).__name__}"
        )
    tcoords = mesh.active_texture_coordinates
    if tcoords is None:
        raise InputError(
            "parametric surface has no texture coordinates, so its (u, v) are lost: build it"
            " with texture_coordinates=True (pv.ParametricTorus(texture_coordinates=True)) or"
            " pass the vtkParametricFunction or the pv.Parametric* factory itself"
        )
    uv = np.asarray(tcoords, dtype=np.float64)
    # Winding-based normals: VTK's parametric normals follow the same side (checked for torus,
    # ellipsoid, Boy), so they can stand in where VTK's are missing or vanish (poles).
    winding = np.asarray(
        mesh.compute_normals(
            cell_normals=False,
            split_vertices=False,
            consistent_normals=False,
            auto_orient_normals=False,
        ).point_data["Normals"],
        dtype=np.float64,
    )
    normals = np.asarray(mesh.point_data.get("Normals", winding), dtype=np.float64)
    # vtkParametricFunctionSource leaves them unnormalised (torus: |n| in [0.25, 0.75]).
    length = np.linalg.norm(normals, axis=1)
    bad = ~np.isfinite(length) | (length <= 1e-6 * max(float(np.nanmax(length)), 1e-300))
    normals = np.where(bad[:, None], winding, normals / np.where(bad, 1.0, length)[:, None])
    mesh.point_data["Normals"] = _fill_vanishing_normals(mesh, normals)
    mesh.point_data["uv"] = uv
    mesh.point_data["gaussian_curvature"] = mesh.curvature("gaussian")
    mesh.point_data["mean_curvature"] = mesh.curvature("mean")
    mesh.active_texture_coordinates = uv
    return mesh


def _fill_vanishing_normals(mesh: pyvista.PolyData, normals: np.ndarray) -> np.ndarray:
    """Unit normals; zero ones (apex of collapsed fans) get the mean of their neighbours'."""
    normals = np.array(normals, dtype=np.float64)
    length = np.linalg.norm(normals, axis=1)
    good = np.isfinite(length) & (length > 1e-6)
    normals[good] /= length[good, None]
    normals[~good] = 0.0
    faces = mesh.regular_faces if mesh.n_cells and mesh.is_all_triangles else None
    for _ in range(3):
        if good.all() or faces is None:
            break
        # Each triangle hands the sum of its good vertices' normals to all three vertices.
        share = (normals[faces] * good[faces][..., None]).sum(axis=1)
        acc = np.zeros_like(normals)
        for k in range(faces.shape[1]):
            np.add.at(acc, faces[:, k], share)
        acc_len = np.linalg.norm(acc, axis=1)
        fill = ~good & (acc_len > 1e-12)
        normals[fill] = acc[fill] / acc_len[fill, None]
        good = good | fill
    normals[~good] = (0.0, 0.0, 1.0)
    return normals
