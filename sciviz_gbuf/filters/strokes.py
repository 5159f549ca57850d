"""Strokes: lines of a picture as vector polylines (for SVG and PDF output).

A :class:`Stroke` is one drawn line: its centre-line vertices in the picture's pixel
coordinates (``x`` the column, ``y`` the row, pixel centres at integers, row 0 at the top, as
:class:`~sciviz_gbuf.filters.ContourPolyline`), its width in pixels, its kind (what line of the
picture it is: ``"contour"``, ``"contour-major"``, ...), its colour and, for contours, its
level. :func:`simplify` drops vertices within a tolerance of the line (Ramer-Douglas-Peucker),
so that a stroke keeps its shape with few vertices.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from .. import _validate
from ..core.gbuffer import GBuffer
from ..errors import InputError
from .edges import buffer_lines, profile_and_crease_edges

__all__ = [
    "Stroke",
    "bridge",
    "dash_pieces",
    "draw_strokes",
    "edge_strokes",
    "paint_strokes",
    "simplify",
    "vectorize",
]

#: Default simplification tolerance, pixels.
TOLERANCE = 0.25


class Stroke(NamedTuple):
    """One vector line of a picture."""

    points: np.ndarray
    """(N, 2) float64 ``(x, y)`` centre-line vertices in pixels (column, row; pixel centres at
    integers, row 0 at the top)."""
    width: float
    """Line width in pixels."""
    kind: str
    """What line it is (``"contour"``, ``"contour-major"``, ``"profile"``, ...): the SVG class."""
    color: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """RGB in [0, 1]."""
    level: float | None = None
    """The field value along a contour line (None for other lines)."""
    closed: bool = False
    """True for a ring (the last vertex joins the first)."""
    dash: tuple[float, float] | None = None
    """``(on, off)`` lengths in pixels of a dashed stroke, the pattern running on along the
    whole stroke from its first vertex (through its vertices); None for a solid line."""


def simplify(points: np.ndarray, tolerance: float = TOLERANCE) -> np.ndarray:
    """The vertices of ``points`` (N, 2) that keep the polyline within ``tolerance`` pixels of
    the original (Ramer-Douglas-Peucker): a subset of the original vertices, first and last
    kept, so every vertex kept lies on the original line.

    Raises
    ------
    InputError
        ``points`` not (N, 2) finite, or ``tolerance`` not finite and >= 0.
    """
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2 or not np.isfinite(pts).all():
        raise InputError(f"points: expected finite (N, 2) coordinates, got shape {pts.shape}")
    tol = _validate.finite(tolerance, "tolerance")
    if tol < 0:
        raise InputError(f"tolerance: expected a distance >= 0, got {tolerance!r}")
    n = len(pts)
    if n <= 2:
        return pts.copy()
    keep = np.zeros(n, bool)
    keep[0] = keep[-1] = True
    stack = [(0, n - 1)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        seg = pts[b] - pts[a]
        rel = pts[a + 1 : b] - pts[a]
        # the distance to the segment (not its line: a vertex beyond an end, where the line
        # folds back, is off the simplified line)
        seg2 = float(seg @ seg)
        t = np.clip(rel @ seg / seg2, 0.0, 1.0) if seg2 > 0 else np.zeros(len(rel))
        dist = np.hypot(rel[:, 0] - t * seg[0], rel[:, 1] - t * seg[1])
        k = int(np.argmax(dist))
        if dist[k] > tol:
            m = a + 1 + k
            keep[m] = True
            stack += [(a, m), (m, b)]
    return pts[keep]


# --------------------------------------------------------------------------- vectorisation
#: A continuation through a junction turns by at most this much (degrees) to be one stroke.
_JOIN_TURN = 45.0
#: Vertices back from an end that give its direction at a junction.
_END_SPAN = 4
#: Largest sub-pixel shift of a vertex across its line, in half-widths (at least one pixel).
_MAX_SHIFT = 0.75
#: Smoothing along the paths: [1, 2, 1] / 4 passes, each vertex kept within a box of
#: +-_TUBE px (per axis) of its measured position. On aliased ink (0 or 1, a one-pixel
#: staircase: the line lies anywhere within half a pixel of the pixel centres) the vertices
#: relax towards the straightest line through the pixels, the "minimum-length polygon" of a
#: digital curve; on antialiased ink the measured centroids are better than that and held
#: closer.
_PASSES = {False: 80, True: 12}
_TUBE = {False: 0.5, True: 0.25}

#: ``taper``: a stroke is cut where its ink width changes by this factor ...
_TAPER_STEP = 1.3
#: ... over at least this many vertices (pixels along it).
_TAPER_RUN = 9

_OFFSETS4 = ((0, 1), (1, 0), (0, -1), (-1, 0))
_OFFSETS_DIAG = ((1, 1), (1, -1), (-1, 1), (-1, -1))


def _neighbours(skel: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows, columns and (N, 8) neighbour indices (-1 for none) of the pixels of a thin
    line mask: 4-neighbours, and diagonal ones unless a 4-neighbour in the mask bridges them
    (a staircase step is one link, not a triangle, so a thin line has degree 2 throughout)."""
    rr, cc = np.nonzero(skel)
    h, w = skel.shape
    idx = np.full((h + 2, w + 2), -1, np.int64)
    idx[rr + 1, cc + 1] = np.arange(len(rr))
    on = idx >= 0
    nbr = np.full((len(rr), 8), -1, np.int64)
    for k, (dr, dc) in enumerate(_OFFSETS4):
        nbr[:, k] = idx[rr + 1 + dr, cc + 1 + dc]
    for k, (dr, dc) in enumerate(_OFFSETS_DIAG):
        bridged = on[rr + 1 + dr, cc + 1] | on[rr + 1, cc + 1 + dc]
        nbr[:, 4 + k] = np.where(bridged, -1, idx[rr + 1 + dr, cc + 1 + dc])
    return rr, cc, nbr


def _trace(skel: np.ndarray) -> tuple[list[np.ndarray], list[bool]]:
    """The simple paths and rings of a line mask whose pixels have degree <= 2: each as
    (n,) pixel indices into ``np.nonzero(skel)`` order, in walking order."""
    _rr, _cc, nbr = _neighbours(skel)
    links = [[int(j) for j in row if j >= 0] for row in nbr]
    seen = np.zeros(len(links), bool)
    paths: list[np.ndarray] = []
    closed: list[bool] = []

    def walk(start: int) -> tuple[list[int], bool]:
        seq, prev, cur = [start], -1, start
        seen[start] = True
        while True:
            nxt = [j for j in links[cur] if j != prev and not seen[j]]
            if not nxt:
                ring = len(seq) > 2 and start in links[cur]
                return seq, ring
            prev, cur = cur, nxt[0]
            seen[cur] = True
            seq.append(cur)

    degree = np.array([len(x) for x in links], np.int64)
    for start in np.flatnonzero(degree <= 1):
        if not seen[start]:
            seq, _ = walk(int(start))
            paths.append(np.array(seq, np.int64))
            closed.append(False)
    for start in range(len(links)):
        if not seen[start]:
            seq, ring = walk(start)
            paths.append(np.array(seq, np.int64))
            closed.append(ring)
    return paths, closed


def _refine(
    ink: np.ndarray,
    pts: np.ndarray,
    prev: np.ndarray,
    nxt: np.ndarray,
    reach: float,
    soft: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """Centre-line positions and widths of the traced paths (all paths at once: ``pts`` (M, 2)
    their pixels, ``prev`` / ``nxt`` each vertex's neighbours along its path, an open end its
    own): each pixel moved across the line to the centroid of the ink along its normal
    (bilinear samples within ``reach`` px), then smoothed within a tube (``_PASSES``,
    ``_TUBE``). The width is the ink integrated across the line: a line of full ink ``w`` px
    wide, antialiased or not, integrates to ``w``."""
    from scipy import ndimage

    tangent = pts[nxt[nxt]] - pts[prev[prev]]
    length = np.hypot(tangent[:, 0], tangent[:, 1])
    tangent = tangent / np.where(length > 0, length, 1.0)[:, None]
    tangent[length == 0] = (1.0, 0.0)
    normal = np.column_stack([-tangent[:, 1], tangent[:, 0]])
    step = 0.5
    t = np.arange(-reach, reach + step / 2, step)
    xs = pts[:, :1] + t[None, :] * normal[:, :1]
    ys = pts[:, 1:] + t[None, :] * normal[:, 1:]
    v = ndimage.map_coordinates(ink, [ys.ravel(), xs.ravel()], order=1, mode="constant")
    v = v.reshape(xs.shape).astype(np.float64)
    total = v.sum(axis=1)
    safe = np.where(total > 0, total, 1.0)
    shift = np.where(total > 0, (v * t[None, :]).sum(axis=1) / safe, 0.0)
    limit = _MAX_SHIFT * max(1.0, reach - 1.0)
    base = pts + np.clip(shift, -limit, limit)[:, None] * normal
    held = (prev == np.arange(len(pts))) | (nxt == np.arange(len(pts)))
    tube = _TUBE[soft]
    lo, hi = base - tube, base + tube
    out = base.copy()
    for _ in range(_PASSES[soft]):
        new = 0.25 * (out[prev] + 2.0 * out + out[nxt])
        new[held] = out[held]
        out = np.clip(new, lo, hi)
    # an end pixel's ink is cut by the line's cap, so its centroid is off the line: it goes to
    # the line continued from the vertices before it (onto their tangent)
    index = np.arange(len(pts))
    for end, step_in in ((prev == index, nxt), (nxt == index, prev)):
        e = np.flatnonzero(end & (step_in != index))
        if len(e) == 0:
            continue
        n1 = step_in[e]
        n3 = step_in[step_in[n1]]
        u = out[n1] - out[n3]
        uu = (u * u).sum(axis=1)
        ok = uu > 0
        rel = out[e] - out[n1]
        along = (rel * u).sum(axis=1) / np.where(ok, uu, 1.0)
        out[e[ok]] = out[n1[ok]] + along[ok, None] * u[ok]
    return out, total * step


def _width_runs(wid: np.ndarray, closed: bool) -> list[tuple[int, int, float]]:
    """``(first, last, width)`` vertex runs of a stroke whose ink width (median over
    ``_TAPER_RUN`` vertices) stays within one step of ``_TAPER_STEP``; runs shorter than
    ``_TAPER_RUN`` join the run before them."""
    from scipy import ndimage

    mode = "wrap" if closed else "nearest"
    smooth = ndimage.median_filter(wid, size=_TAPER_RUN, mode=mode)
    level = np.round(np.log(np.maximum(smooth, 0.05)) / np.log(_TAPER_STEP)).astype(np.int64)
    cuts = [0, *(np.flatnonzero(np.diff(level)) + 1).tolist()]
    runs: list[list[int]] = []
    for a, b in zip(cuts, [*cuts[1:], len(wid)], strict=True):
        if runs and b - a < _TAPER_RUN:
            runs[-1][1] = b
        else:
            runs.append([a, b])
    if len(runs) > 1 and runs[0][1] - runs[0][0] < _TAPER_RUN:
        runs[1][0] = runs[0][0]
        runs.pop(0)
    return [(a, b - 1, float(np.median(smooth[a:b]))) for a, b in runs]


def _direction_in(pts: np.ndarray, end: int) -> np.ndarray:
    """Unit direction along a path towards its ``end`` (0 first vertex, 1 last)."""
    a = pts if end == 1 else pts[::-1]
    d = a[-1] - a[max(0, len(a) - 1 - _END_SPAN)]
    n = float(np.hypot(*d))
    return d / n if n > 0 else d


def _arc_length(pts: np.ndarray, closed: bool) -> float:
    p = np.vstack([pts, pts[:1]]) if closed else pts
    return float(np.hypot(*np.diff(p, axis=0).T).sum()) if len(p) > 1 else 0.0


def vectorize(
    lines: np.ndarray,
    *,
    kind: str = "line",
    width: float | None = None,
    threshold: float = 0.3,
    tolerance: float = TOLERANCE,
    min_length: float = 3.0,
    color: tuple[float, float, float] = (0.0, 0.0, 0.0),
    taper: bool = False,
) -> list[Stroke]:
    """Centre-line strokes of a line image (profile, crease, id edges, contours, hatching...).

    The image-space lines of 1990 §3 (e.g. Eq. 2's profile lines) become vector polylines:
    the ink at or above ``threshold`` is thinned to its skeleton, the skeleton traced into
    paths between junctions, each vertex moved to the centroid of the ink across the line
    (sub-pixel positions from the antialiased ink), paths joined through junctions where one
    continues the other within 45 degrees (the others end at the junction's centre), and
    each stroke simplified within ``tolerance`` (:func:`simplify`).

    Parameters
    ----------
    lines : (H, W) array
        Ink in [0, 1] (a signed image such as :func:`~sciviz_gbuf.filters.internal_edges`
        is taken by magnitude: vectorise ``np.maximum(lines, 0)`` and ``-lines`` apart to keep
        the sign); NaN is no ink. At most ``LIMITS["image_side"] x LIMITS["supersample"]``
        pixels a side.
    kind : str, default: "line"
        The strokes' kind (their SVG class).
    width : float in (0, 64], optional
        Stroke width in pixels; by default each stroke's median ink integrated across it.
    threshold : float in (0, 1], default: 0.3
        Ink that counts as line.
    tolerance : float in [0, 64], default: 0.25
        Simplification tolerance, pixels.
    min_length : float in [0, 16384], default: 3
        Strokes shorter than this (pixels along them) are dropped.
    color : RGB in [0, 1], default: black
    taper : bool, default: False
        Cut strokes where their ink width changes (by a factor 1.3, over 9 px or more), each
        piece as wide as its ink: tone-modulated lines (1990 Eq. 20's enhanced hatching)
        keep their tone. Without it (or with ``width``) a stroke has one width.

    Returns
    -------
    list of Stroke
        Longest first; ``points`` in the image's pixel coordinates (x the column, y the row).
    """
    from scipy import ndimage
    from skimage.morphology import skeletonize

    a = np.asarray(lines)
    if a.ndim != 2 or a.size == 0:
        raise InputError(f"lines: expected a non-empty (H, W) image, got shape {a.shape}")
    if not (a.dtype == np.bool_ or np.issubdtype(a.dtype, np.number)):
        raise InputError(f"lines: expected numbers or booleans, got dtype {a.dtype}")
    side = _validate.LIMITS["image_side"] * _validate.LIMITS["supersample"]
    if max(a.shape) > side:
        raise InputError(f"lines: expected at most {side:g} pixels a side, got {a.shape}")
    kind = str(kind)
    thr = _validate.number_in(threshold, "threshold", 0.0, 1.0)
    if thr <= 0:
        raise InputError(f"threshold: expected a number in (0, 1], got {threshold!r}")
    tol = _validate.size(tolerance, "tolerance", "line_width", closed=True)
    min_len = _validate.size(min_length, "min_length", "image_side", closed=True)
    fixed = None if width is None else _validate.size(width, "width", "line_width")
    rgb = tuple(float(c) for c in _validate.rgb(color, "color"))
    tapered = _validate.boolean(taper, "taper")

    with np.errstate(invalid="ignore"):
        ink = np.abs(np.nan_to_num(a.astype(np.float32), nan=0.0, posinf=1.0, neginf=1.0))
    ink = np.clip(ink, 0.0, 1.0)
    mask = ink >= thr
    if not mask.any():
        return []
    skel = skeletonize(mask)
    half = ndimage.distance_transform_edt(mask)
    reach = float(np.ceil(np.median(half[skel]))) + 1.0
    # antialiased ink (a supersampled capture, a smooth field) has partial pixels beside the
    # lines; aliased ink is 0 or 1 and its staircase needs a longer smoothing
    near = ndimage.binary_dilation(mask) & ~mask
    soft = bool(near.any() and float(np.mean(ink[near] > 0.05)) > 0.2)

    # junctions: pixels of degree >= 3 and their neighbours, one node per connected cluster
    _rr, _cc, nbr = _neighbours(skel)
    junction = np.zeros_like(skel)
    hub = (nbr >= 0).sum(axis=1) >= 3
    junction[_rr[hub], _cc[hub]] = True
    cluster = skel & ndimage.binary_dilation(junction, np.ones((3, 3), bool))
    rest = skel & ~cluster
    for _ in range(4):  # removing clusters can leave a pixel of degree 3 (rare); absorb it
        rr, cc, nb = _neighbours(rest)
        extra = (nb >= 0).sum(axis=1) >= 3
        if not extra.any():
            break
        cluster[rr[extra], cc[extra]] = True
        rest[rr[extra], cc[extra]] = False
    labels, n_clusters = ndimage.label(cluster, np.ones((3, 3), bool))
    centres = np.zeros((n_clusters + 1, 2))
    if n_clusters:
        cy, cx = np.nonzero(cluster)
        lab = labels[cy, cx]
        counts = np.bincount(lab, minlength=n_clusters + 1).astype(np.float64)
        counts[0] = 1.0
        centres[:, 0] = np.bincount(lab, cx, minlength=n_clusters + 1) / counts
        centres[:, 1] = np.bincount(lab, cy, minlength=n_clusters + 1) / counts
    padded = np.pad(labels, 1)

    def touching(r: int, c: int) -> list[int]:
        win = padded[r : r + 3, c : c + 3]
        return [int(v) for v in np.unique(win[win > 0])]

    rr, cc = np.nonzero(rest)
    raw, rings = _trace(rest)
    sizes = np.array([len(q) for q in raw], np.int64)
    first = np.concatenate([[0], np.cumsum(sizes)[:-1]]) if len(raw) else np.zeros(0, np.int64)
    order = np.concatenate(raw) if raw else np.zeros(0, np.int64)
    m = len(order)
    prev, nxt = np.arange(m) - 1, np.arange(m) + 1
    for f, n, ring in zip(first, sizes, rings, strict=True):
        prev[f] = f + n - 1 if ring else f
        nxt[f + n - 1] = f if ring else f + n - 1
    pixels = np.column_stack([cc[order], rr[order]]).astype(np.float64)
    refined, vertex_width = _refine(ink, pixels, prev, nxt, reach, soft)
    paths: list[np.ndarray] = []
    widths: list[np.ndarray] = []
    ends: list[list[int]] = []  # per path: the cluster at its start and at its end (0: none)
    is_ring: list[bool] = []
    for seq, ring, f, n in zip(raw, rings, first, sizes, strict=True):
        at = [0, 0]
        if not ring:
            head = touching(int(rr[seq[0]]), int(cc[seq[0]]))
            tail = touching(int(rr[seq[-1]]), int(cc[seq[-1]]))
            if head:
                at[0] = head[0]
            if tail:
                at[1] = tail[-1] if n > 1 or len(tail) == 1 else tail[1]
        paths.append(refined[f : f + n])
        widths.append(vertex_width[f : f + n])
        ends.append(at)
        is_ring.append(ring)

    # spurs: short paths from a free end into a junction of >= 3 lines go
    degree = np.zeros(n_clusters + 1, np.int64)
    for at in ends:
        for c in at:
            degree[c] += 1
    spur = 2.0 * reach + 1.0
    alive = [True] * len(paths)
    for i, at in enumerate(ends):
        free = [c == 0 for c in at]
        if is_ring[i] or free[0] == free[1]:
            continue
        hub_c = at[1] if free[0] else at[0]
        if degree[hub_c] >= 3 and _arc_length(paths[i], False) < spur:
            alive[i] = False
            degree[hub_c] -= 1

    # joins: at each junction pair the straightest continuations (any two when only two)
    at_cluster: dict[int, list[tuple[int, int]]] = {}
    for i, at in enumerate(ends):
        if alive[i] and not is_ring[i]:
            for e, c in enumerate(at):
                if c:
                    at_cluster.setdefault(c, []).append((i, e))
    link: dict[tuple[int, int], tuple[int, int]] = {}
    cos_join = np.cos(np.radians(_JOIN_TURN))
    for members in at_cluster.values():
        if len(members) == 2:
            pairs = [(members[0], members[1])]
        else:
            d = [_direction_in(paths[i], e) for i, e in members]
            scored = sorted(
                ((-float(d[p] @ d[q]), p, q)
                 for p in range(len(members)) for q in range(p + 1, len(members))),
                reverse=True,
            )  # fmt: skip
            pairs, taken = [], set()
            for score, p, q in scored:
                if score >= cos_join and p not in taken and q not in taken:
                    taken |= {p, q}
                    pairs.append((members[p], members[q]))
        for u, v in pairs:
            link[u] = v
            link[v] = u

    def oriented(i: int, enter: int) -> np.ndarray:
        return paths[i] if enter == 0 else paths[i][::-1]

    strokes: list[Stroke] = []
    used = [not x for x in alive]

    def piece(pts: np.ndarray, w: float, closed: bool) -> None:
        keep = simplify(np.vstack([pts, pts[:1]]), tol)[:-1] if closed else simplify(pts, tol)
        if len(keep) < 2:
            return  # a ring within the tolerance of one point (a hole of one pixel): a dot
        width = fixed if fixed is not None else round(float(np.clip(w, 0.25, 64.0)), 2)
        strokes.append(Stroke(keep, width, kind, rgb, None, closed))

    def emit(pts: np.ndarray, wid: np.ndarray, closed: bool) -> None:
        if _arc_length(pts, closed) < min_len or len(pts) < 2:
            return
        wid = np.where(np.isnan(wid), np.nanmedian(wid) if np.isfinite(wid).any() else 1.0, wid)
        if fixed is not None or not tapered or len(pts) < 2 * _TAPER_RUN:
            piece(pts, float(np.median(wid)), closed)
            return
        for a, b, w in _width_runs(wid, closed):
            if a == 0 and b == len(pts) - 1:
                piece(pts, w, closed)
            else:  # a run and the first vertex of the next, so the pieces join
                idx = np.arange(a, b + 2) % len(pts)
                if not closed and b == len(pts) - 1:
                    idx = np.arange(a, b + 1)
                piece(pts[idx], w, False)

    def chain(i: int, enter: int) -> None:
        start = (i, enter)
        pieces, wids = [], []
        c0 = ends[i][enter]
        if c0 and start not in link:
            pieces.append(centres[c0][None, :])
            wids.append(np.array([np.nan]))
        closed = False
        while True:
            used[i] = True
            pieces.append(oriented(i, enter))
            wids.append(widths[i] if enter == 0 else widths[i][::-1])
            c = ends[i][1 - enter]
            nxt = link.get((i, 1 - enter))
            if c:  # the junction, between this path and the next one (or as the end)
                pieces.append(centres[c][None, :])
                wids.append(np.array([np.nan]))
            if nxt is None:
                break
            if nxt == start:
                closed = True
                break
            if used[nxt[0]]:
                break
            i, enter = nxt
        emit(np.vstack(pieces), np.concatenate(wids), closed)

    for i in range(len(paths)):
        if used[i] or is_ring[i]:
            continue
        for e in (0, 1):
            if (i, e) not in link:
                chain(i, e)
                break
    for i in range(len(paths)):
        if used[i]:
            continue
        if is_ring[i]:
            used[i] = True
            emit(paths[i], widths[i], True)
        else:
            chain(i, 0)  # a loop of paths through junctions
    strokes.sort(key=lambda s: -_arc_length(s.points, s.closed))
    return strokes


def edge_strokes(
    gb: GBuffer,
    *,
    crease_angle: float = 30.0,
    depth_jump: float = 1.0,
    width: float = 1.0,
    min_length: float = 5.0,
    tolerance: float = TOLERANCE,
    profile_color: tuple[float, float, float] = (0.0, 0.0, 0.0),
    crease_color: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> list[Stroke]:
    """Profile and crease lines of a G-buffer (1990 §3.2, Eq. 2 and the 1st-order edges) as
    vector strokes of kinds ``"profile"`` and ``"crease"``, ``width`` output pixels wide.

    The lines are found as :func:`~sciviz_gbuf.filters.profile_and_crease_edges` finds them
    (same ``crease_angle``, ``depth_jump`` and ``min_length``) and traced by
    :func:`vectorize`: one pixel wide at the output size or, when the G-buffer was
    supersampled by ``k``, at the buffer's (:func:`~sciviz_gbuf.filters.edges.buffer_lines`:
    lines a pixel apart in the picture stay apart, positions are ``k`` times finer).
    Points are in output pixels of ``gb``.
    """
    w = _validate.size(width, "width", "line_width")
    tol = _validate.size(tolerance, "tolerance", "line_width", closed=True)
    k = int(getattr(gb, "supersample", 1) or 1)
    if k == 1:
        profile, crease = profile_and_crease_edges(
            gb, crease_angle=crease_angle, depth_jump=depth_jump, width=1.0,
            min_length=min_length, signed=False,
        )  # fmt: skip
    else:
        # the one-pixel lines of the supersampled buffer: two lines a pixel apart in the
        # output are still apart there, and their positions are k times finer
        profile, crease = buffer_lines(
            gb, crease_angle=crease_angle, depth_jump=depth_jump, min_length=min_length
        )
    out = []
    for ink, name, colour in (
        (profile, "profile", profile_color),
        (crease, "crease", crease_color),
    ):
        traced = vectorize(
            ink, kind=name, width=1.0, tolerance=min(tol * k, 64.0), min_length=2.0 * k,
            color=colour,
        )  # fmt: skip
        for s in traced:
            # buffer pixel centre i sits at output position (i + 0.5) / k - 0.5
            out.append(s._replace(points=(s.points + 0.5) / k - 0.5, width=w))
    return out


def bridge(
    strokes: Sequence[Stroke], *, gap: float, turn: float = 15.0, tolerance: float = TOLERANCE
) -> list[Stroke]:
    """Open strokes joined across gaps: two ends at most ``gap`` px apart, each stroke's end
    direction and the gap's own direction within ``turn`` degrees, become one stroke (the
    nearest pairs first; strokes of one kind only). For a line interrupted where another
    crosses it (a hidden edge behind a visible one), so that it is one stroke again and its
    dash pattern runs on across the crossing. A joined stroke is simplified again within
    ``tolerance`` px (:func:`simplify`)."""
    g = _validate.size(gap, "gap", "spacing")
    cos_turn = np.cos(np.radians(_validate.number_in(turn, "turn", 0.0, 90.0)))
    tol = _validate.size(tolerance, "tolerance", "line_width", closed=True)
    items = [list(s) for s in strokes]
    alive = [True] * len(items)

    def ends(i: int):
        pts = np.asarray(items[i][0], np.float64)
        return [(pts[0], _direction_in(pts, 0)), (pts[-1], _direction_in(pts, 1))]

    while True:
        best = None
        for i in range(len(items)):
            if not alive[i] or items[i][5] or len(items[i][0]) < 2:
                continue
            for j in range(i + 1, len(items)):
                if (
                    not alive[j]
                    or items[j][5]
                    or len(items[j][0]) < 2
                    or items[j][2] != items[i][2]
                ):
                    continue
                for ei, (pi, di) in enumerate(ends(i)):
                    for ej, (pj, dj) in enumerate(ends(j)):
                        v = pj - pi
                        dist = float(np.hypot(*v))
                        if dist > g or (best is not None and dist >= best[0]):
                            continue
                        # di points out of stroke i at its end, dj out of stroke j at its end
                        if float(di @ -dj) < cos_turn:
                            continue
                        if dist > 0 and float(di @ (v / dist)) < cos_turn:
                            continue
                        best = (dist, i, ei, j, ej)
        if best is None:
            break
        _, i, ei, j, ej = best
        a = np.asarray(items[i][0], np.float64)
        b = np.asarray(items[j][0], np.float64)
        a = a if ei == 1 else a[::-1]  # a ends at the gap
        b = b if ej == 0 else b[::-1]  # b starts at it
        items[i][0] = simplify(np.vstack([a, b]), tol)
        alive[j] = False
    return [Stroke(*it) for it, ok in zip(items, alive, strict=True) if ok]


# --------------------------------------------------------------------------- drawing
def _polyline(s: Stroke) -> np.ndarray:
    pts = np.asarray(s.points, np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2 or not np.isfinite(pts).all():
        raise InputError(f"strokes: expected finite (N, 2) points, got shape {pts.shape}")
    return np.vstack([pts, pts[:1]]) if s.closed and len(pts) > 2 else pts


def _check_dash(dash: object) -> tuple[float, float]:
    if np.ndim(dash) != 1 or len(dash) != 2:
        raise InputError(f"dash: expected (on, off) lengths in pixels, got {_validate.brief(dash)}")
    on = _validate.size(dash[0], "dash", "spacing")
    off = _validate.size(dash[1], "dash", "spacing")
    return on, off


def dash_pieces(stroke: Stroke) -> list[np.ndarray]:
    """The polylines a stroke is drawn as: itself (closed: its first vertex repeated at the
    end) or, dashed, its pieces ``[k p, k p + on]`` along its arc length (``p = on + off``),
    so the pattern runs on through the vertices as SVG's ``stroke-dasharray`` does."""
    pts = _polyline(stroke)
    if stroke.dash is None or len(pts) < 2:
        return [pts]
    on, off = _check_dash(stroke.dash)
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
    total = float(cum[-1])
    if total <= 0:
        return []
    pieces = []
    for a in np.arange(0.0, total, on + off):
        b = min(a + on, total)
        inner = (cum > a) & (cum < b)
        at = np.concatenate([[a], cum[inner], [b]])
        pieces.append(
            np.column_stack([np.interp(at, cum, pts[:, 0]), np.interp(at, cum, pts[:, 1])])
        )
    return pieces


def draw_strokes(strokes: Sequence[Stroke], shape: tuple[int, int]) -> np.ndarray:
    """Antialiased ink (H, W) float32 in [0, 1] of ``strokes`` on an image of ``shape``: each
    stroke (or each of its dashes, :func:`dash_pieces`) ``width`` px wide, butt ends and round
    joints, as an SVG viewer draws it (:func:`~sciviz_gbuf.writers.write_svg`)."""
    from . import _stroke_kernels

    if np.ndim(shape) != 1 or len(shape) != 2:
        raise InputError(f"shape: expected (H, W), got {_validate.brief(shape)}")
    h, w = (int(_validate.size(v, "shape", "image_side", buffer=True)) for v in shape)
    segs, widths, caps = [], [], []
    for s in strokes:
        width = _validate.size(s.width, "strokes: width", "line_width")
        ring = s.closed and s.dash is None
        for piece in dash_pieces(s):
            n = len(piece) - 1
            if n < 1:
                continue
            segs.append(np.column_stack([piece[:-1], piece[1:]]))
            widths.append(np.full(n, width))
            cap = np.ones((n, 2), bool)
            if not ring:
                cap[0, 0] = cap[-1, 1] = False
            caps.append(cap)
    out = np.zeros((h, w), np.float32)
    if segs:
        _stroke_kernels.draw_segments(
            np.ascontiguousarray(np.concatenate(segs)), np.concatenate(widths),
            np.ascontiguousarray(np.concatenate(caps)), out,
        )  # fmt: skip
    return out


def paint_strokes(strokes: Sequence[Stroke], background: np.ndarray) -> np.ndarray:
    """``background`` (H, W) or (H, W, 3) float in [0, 1] with ``strokes`` painted over it in
    their colours (in order of their kinds' first appearance), float32 (H, W, 3)."""
    bg = np.asarray(background, dtype=np.float32)
    if bg.ndim == 2:
        bg = np.repeat(bg[..., None], 3, axis=2)
    if bg.ndim != 3 or bg.shape[2] != 3:
        raise InputError(f"background: expected (H, W) or (H, W, 3), got shape {bg.shape}")
    img = np.clip(bg, 0.0, 1.0).copy()
    groups: dict[tuple, list[Stroke]] = {}
    for s in strokes:
        groups.setdefault((str(s.kind), tuple(float(c) for c in s.color)), []).append(s)
    for (_kind, color), group in groups.items():
        ink = draw_strokes(group, img.shape[:2])[..., None]
        img = img * (1.0 - ink) + np.asarray(color, np.float32) * ink
    return img.astype(np.float32, copy=False)
