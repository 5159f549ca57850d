"""Numba kernels that classify neighbouring G-buffer pixel pairs into profile / crease edges.

The depth test works on Saito's ``sz`` (1990 Eq. 6), which is an affine function of the screen
position on any plane (for both projections), so a plane at any angle has exactly zero second
difference. A step ``J = sz(Y) - sz(X)`` between neighbours is a 0th-order discontinuity only
if neither the slope on X's side nor the slope on Y's side, nor a crease anywhere between the
two pixels (any value between those two predictions), explains it: the *unexplained jump* is
the distance of ``J`` from the interval spanned by the one-sided slopes. It is converted from
``sz`` units to pixel footprints at the nearer pixel (factor ``z / d`` in perspective, 1 in
parallel projection), so the threshold reads "a step of so many pixel widths".
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..core.bands import run_bands

__all__ = [
    "MODE_C1",
    "MODE_DIAGONAL",
    "MODE_PAIRS",
    "clean_lines",
    "dilate_kernel",
    "edge_map_finish",
    "edge_map_kernel",
    "edge_pass",
    "enhance_kernel",
    "finish_lines",
    "id_edge_kernel",
    "pair_edge_kernel",
]

# The four 4-neighbour directions (dr, dc): right, left, down, up.
_DR4 = np.array([0, 0, 1, -1], dtype=np.int64)
_DC4 = np.array([1, -1, 0, 0], dtype=np.int64)
# Largest turn of the surface next to a depth crease, relative to the crease's own turn.
_FLANK = 0.25
# Largest turn of the buffer normals beside a normal crease, relative to the crease's turn.
_NORMAL_FLANK = 0.3
# Rows per parallel task. A task carries the pairs between consecutive rows over in a row
# buffer, so each pair is classified once instead of once from each of its pixels; only the
# pairs above a task's first row are classified twice.
_ROWS = 32
# Cosines at least this far above cos(threshold) are angles certainly below the threshold
# (far beyond acos round-off), so their ink is 0 without evaluating acos.
_COS_MARGIN = 1e-9
# Pairs per block of the scan for jumps above the threshold (:func:`_kind_row`).
_SCAN = 64


@njit(cache=True)
def _valid(sz, m, r, c):
    h, w = sz.shape
    if r < 0 or r >= h or c < 0 or c >= w:
        return False
    v = sz[r, c]
    return m[r, c] and (v - v == 0.0)


@njit(cache=True)
def _inside(sz, r, c):
    h, w = sz.shape
    return r >= 0 and r < h and c >= 0 and c < w


@njit(cache=True)
def _unexplained(jump, s_left, ok_left, s_right, ok_right):
    """Distance of ``jump`` from the interval of the two one-sided predictions.

    A side without a slope (background or image border next to it, e.g. the last pixel
    before a smooth object's silhouette, where the surface may be arbitrarily steep) leaves
    the step unconstrained: no evidence of a discontinuity, so 0.
    """
    if not (ok_left and ok_right):
        return 0.0
    lo = min(s_left, s_right)
    hi = max(s_left, s_right)
    if jump < lo:
        return lo - jump
    if jump > hi:
        return jump - hi
    return 0.0


@njit(cache=True)
def _pair_gap(sz, depth, m, r, c, dr, dc, steps, parallel, inv_d):
    """Unexplained jump, in pixel footprints, between (r, c) and (r + steps dr, c + steps dc).

    Both pixels must be valid. One-sided slopes come from the pixels ``steps`` further out.
    """
    r2, c2 = r + steps * dr, c + steps * dc
    x = np.float64(sz[r, c])
    y = np.float64(sz[r2, c2])
    ok_l = _valid(sz, m, r - dr, c - dc)
    ok_r = _valid(sz, m, r2 + dr, c2 + dc)
    s_l = (x - sz[r - dr, c - dc]) * steps if ok_l else 0.0
    s_r = (sz[r2 + dr, c2 + dc] - y) * steps if ok_r else 0.0
    gap = _unexplained(y - x, s_l, ok_l, s_r, ok_r)
    if gap == 0.0:
        return 0.0
    scale = 1.0 if parallel else min(np.float64(depth[r, c]), np.float64(depth[r2, c2])) * inv_d
    # Relative to the grazing angle: a surface displaced by noise (a scan, the facets of a
    # decimated shape) by e along its normal moves by e / cos(theta) along the view ray, and
    # the slope in footprints per pixel is tan(theta), so depth noise grows as sqrt(1 + s^2)
    # with the gentler of the two slopes. A real occlusion has at least one side that is not
    # grazing (or a gap far larger than the noise) and keeps its jump.
    s = min(abs(s_l), abs(s_r)) * scale / steps
    return gap * scale / math.sqrt(1.0 + s * s)


@njit(cache=True)
def _ramp(value, start, width):
    t = (value - start) / width
    return min(1.0, max(0.0, t))


@njit(cache=True)
def _eye(depth, r, c, h, w, parallel, inv_d, inv_w):
    """Eye-space position of pixel (r, c) in units of the focal-plane pixel size."""
    z = np.float64(depth[r, c])
    k = 1.0 if parallel else z * inv_d
    return (c + 0.5 - 0.5 * w) * k, (0.5 * h - r - 0.5) * k, -z * inv_w


@njit(cache=True)
def _turn(ax, ay, az, bx, by, bz):
    """Angle in degrees between two 3-vectors (atan2 form: exact near 0); 0 if one is null."""
    cx = ay * bz - az * by
    cy = az * bx - ax * bz
    cz = ax * by - ay * bx
    cross = math.sqrt(cx * cx + cy * cy + cz * cz)
    dot = ax * bx + ay * by + az * bz
    if cross == 0.0 and dot == 0.0:
        return 0.0
    return math.degrees(math.atan2(cross, dot))


@njit(cache=True)
def _section_turn(depth, r0, c0, r1, c1, r2, c2, r3, c3, h, w, parallel, inv_d, inv_w):
    """Angle between the eye-space segments P0 -> P1 and P2 -> P3."""
    x0, y0, z0 = _eye(depth, r0, c0, h, w, parallel, inv_d, inv_w)
    x1, y1, z1 = _eye(depth, r1, c1, h, w, parallel, inv_d, inv_w)
    x2, y2, z2 = _eye(depth, r2, c2, h, w, parallel, inv_d, inv_w)
    x3, y3, z3 = _eye(depth, r3, c3, h, w, parallel, inv_d, inv_w)
    return _turn(x1 - x0, y1 - y0, z1 - z0, x3 - x2, y3 - y2, z3 - z2)


@njit(cache=True)
def _depth_crease(sz, depth, m, r, c, dr, dc, h, w, parallel, inv_d, inv_w, jump, cos_min):
    """Signed 1st-order discontinuity of the depth between X = (r, c) and Y = X + d, degrees.

    The surface's section through the four pixels X - d, X, Y, Y + d (eye-space positions
    from the depth) turns by the angle between the segments (X - d -> X) and (Y -> Y + d);
    that is exact for two planes meeting anywhere between X and Y. Non-maximum suppression
    against the neighbouring pairs keeps the one pair that straddles the crease, so the line
    is one pixel wide, and the flanks on either side must be nearly straight. The sign is
    that of the change of ``sz`` slope: a projective map keeps convexity, and ``sz`` is affine
    on planes, so a convex edge has ``s_right < s_left``. Returns 0 when a pixel of the
    stencil is missing or across a depth discontinuity, and (early, as most pairs are) when
    the turn's cosine is at least ``cos_min``: such a turn could not reach the threshold.
    """
    rm, cm = r - dr, c - dc
    r2, c2 = r + dr, c + dc
    rp, cp = r2 + dr, c2 + dc
    if not (_valid(sz, m, rm, cm) and _valid(sz, m, rp, cp)):
        return 0.0
    x0, y0, z0 = _eye(depth, rm, cm, h, w, parallel, inv_d, inv_w)
    x1, y1, z1 = _eye(depth, r, c, h, w, parallel, inv_d, inv_w)
    x2, y2, z2 = _eye(depth, r2, c2, h, w, parallel, inv_d, inv_w)
    x3, y3, z3 = _eye(depth, rp, cp, h, w, parallel, inv_d, inv_w)
    ax, ay, az = x1 - x0, y1 - y0, z1 - z0
    bx, by, bz = x3 - x2, y3 - y2, z3 - z2
    dot = ax * bx + ay * by + az * bz
    norms = math.sqrt((ax * ax + ay * ay + az * az) * (bx * bx + by * by + bz * bz))
    if dot >= cos_min * norms:
        return 0.0
    if _pair_gap(sz, depth, m, rm, cm, dr, dc, 1, parallel, inv_d) > jump:
        return 0.0
    if _pair_gap(sz, depth, m, r2, c2, dr, dc, 1, parallel, inv_d) > jump:
        return 0.0
    rmm, cmm = rm - dr, cm - dc
    rpp, cpp = rp + dr, cp + dc
    if not (_valid(sz, m, rmm, cmm) and _valid(sz, m, rpp, cpp)):
        return 0.0
    ang = _turn(ax, ay, az, bx, by, bz)
    left = _section_turn(depth, rmm, cmm, rm, cm, r, c, r2, c2, h, w, parallel, inv_d, inv_w)
    right = _section_turn(depth, r, c, r2, c2, rp, cp, rpp, cpp, h, w, parallel, inv_d, inv_w)
    if ang < left or ang <= right:
        return 0.0
    # A crease turns within one pixel between flat flanks; a smooth surface near its
    # silhouette turns steadily over many pixels (and so do facets seen edge-on there).
    flank_l = _section_turn(depth, rmm, cmm, rm, cm, rm, cm, r, c, h, w, parallel, inv_d, inv_w)
    flank_r = _section_turn(depth, r2, c2, rp, cp, rp, cp, rpp, cpp, h, w, parallel, inv_d, inv_w)
    if max(flank_l, flank_r) > _FLANK * ang:
        return 0.0
    # The section angle magnifies small dihedral angles on surfaces seen at grazing angles
    # (it is the angle between the normals projected onto the section plane, and the normals
    # of a grazing surface lie nearly along that plane's normal), so the facets of a
    # decimated smooth shape there would read as creases. The flanks' own normals, from the
    # section tangent and a tangent across it, give the dihedral angle itself.
    dih = _flank_dihedral(sz, depth, m, rm, cm, rp, cp, dr, dc, h, w, parallel, inv_d, inv_w, jump)
    if dih >= 0.0:
        ang = min(ang, dih)
    s_left = np.float64(sz[r, c]) - np.float64(sz[rm, cm])
    s_right = np.float64(sz[rp, cp]) - np.float64(sz[r2, c2])
    return ang if s_right <= s_left else -ang


@njit(cache=True)
def _flank_normal(sz, depth, m, r, c, ax, ay, az, pr, pc, h, w, parallel, inv_d, inv_w, jump):
    """Eye-space normal at (r, c) from the section tangent ``a`` and the central tangent
    across it (direction ``p``); ``(0, 0, 0, False)`` if a pixel across is missing or beyond
    a depth discontinuity."""
    if not (_valid(sz, m, r - pr, c - pc) and _valid(sz, m, r + pr, c + pc)):
        return 0.0, 0.0, 0.0, False
    if _pair_gap(sz, depth, m, r - pr, c - pc, pr, pc, 1, parallel, inv_d) > jump:
        return 0.0, 0.0, 0.0, False
    if _pair_gap(sz, depth, m, r, c, pr, pc, 1, parallel, inv_d) > jump:
        return 0.0, 0.0, 0.0, False
    x0, y0, z0 = _eye(depth, r - pr, c - pc, h, w, parallel, inv_d, inv_w)
    x1, y1, z1 = _eye(depth, r + pr, c + pc, h, w, parallel, inv_d, inv_w)
    tx, ty, tz = x1 - x0, y1 - y0, z1 - z0
    return ay * tz - az * ty, az * tx - ax * tz, ax * ty - ay * tx, True


@njit(cache=True)
def _flank_dihedral(sz, depth, m, rm, cm, rp, cp, dr, dc, h, w, parallel, inv_d, inv_w, jump):
    """Angle in degrees between the surface normals at X - d = (rm, cm) and Y + d = (rp, cp),
    from the depth alone; -1 where one of them cannot be estimated."""
    pr, pc = dc, dr  # the direction across d
    x0, y0, z0 = _eye(depth, rm - dr, cm - dc, h, w, parallel, inv_d, inv_w)
    x1, y1, z1 = _eye(depth, rm, cm, h, w, parallel, inv_d, inv_w)
    x2, y2, z2 = _eye(depth, rp, cp, h, w, parallel, inv_d, inv_w)
    x3, y3, z3 = _eye(depth, rp + dr, cp + dc, h, w, parallel, inv_d, inv_w)
    lx, ly, lz, ok_l = _flank_normal(
        sz, depth, m, rm, cm, x1 - x0, y1 - y0, z1 - z0, pr, pc, h, w, parallel, inv_d, inv_w, jump
    )
    rx, ry, rz, ok_r = _flank_normal(
        sz, depth, m, rp, cp, x3 - x2, y3 - y2, z3 - z2, pr, pc, h, w, parallel, inv_d, inv_w, jump
    )
    if not (ok_l and ok_r):
        return -1.0
    return _turn(lx, ly, lz, rx, ry, rz)


@njit(cache=True)
def _dot(n, r, c, r2, c2):
    """float32 dot product of two normals, as the angle tests have always summed it."""
    return n[r, c, 0] * n[r2, c2, 0] + n[r, c, 1] * n[r2, c2, 1] + n[r, c, 2] * n[r2, c2, 2]


@njit(cache=True)
def _normal_flanks(sz, depth, normal, m, r, c, dr, dc, parallel, inv_d, jump, ang):
    """``ang`` (the turn of the buffer normals from X to Y = X + d), or 0 if the normals on
    either flank turn by more than ``_NORMAL_FLANK * ang`` over one pixel.

    A crease separates surfaces whose normals change slowly; the normals of a noisy scan or
    of a mesh with sub-pixel facets change at random from pixel to pixel, and so turn as
    much beside the pair as across it. A flank pixel that is missing or beyond a depth
    discontinuity (another surface) does not count.
    """
    r2, c2 = r + dr, c + dc
    limit = math.cos(math.radians(_NORMAL_FLANK * ang))
    rl, cl = r - dr, c - dc
    if (
        _valid(sz, m, rl, cl)
        and _pair_gap(sz, depth, m, rl, cl, dr, dc, 1, parallel, inv_d) <= jump
    ):
        if _dot(normal, rl, cl, r, c) < limit:
            return 0.0
    rr, cr = r2 + dr, c2 + dc
    if (
        _valid(sz, m, rr, cr)
        and _pair_gap(sz, depth, m, r2, c2, dr, dc, 1, parallel, inv_d) <= jump
    ):
        if _dot(normal, r2, c2, rr, cr) < limit:
            return 0.0
    return ang


@njit(cache=True)
def _down_gaps(sz, depth, m, r, parallel, inv_d, out):
    """``out[c]``: unexplained jump of the pair (r, c) -> (r + 1, c) where both are valid."""
    h, w = sz.shape
    for c in range(w):
        g = 0.0
        if r >= 0 and r + 1 < h and _valid(sz, m, r, c) and _valid(sz, m, r + 1, c):
            g = _pair_gap(sz, depth, m, r, c, 1, 0, 1, parallel, inv_d)
        out[c] = g


def pair_edge_kernel(
    sz, depth, normal, m, parallel, inv_d, inv_w, jump, crease, soft, do_crease, profile_out,
    crease_out,
):  # fmt: skip
    """Profile ink on the nearer pixel of each 4-neighbour pair with an unexplained jump
    (the covered pixel next to the background counts as an infinite jump), and signed crease
    ink (> 0 convex) on X for the pairs (X, right) and (X, down) whose depths are continuous
    and whose surface turns by more than ``crease`` degrees: the larger of the angle between
    the buffer's normals and the depth's own section angle (:func:`_depth_crease`), so data
    with normals smoothed across a real crease still shows it.

    Each pair's jump is computed once and read from both of its pixels: it is symmetric bit
    for bit (swapping X and Y negates the step and both slopes exactly).
    """
    run_bands(
        _pair_edge_blocks, (sz.shape[0] + _ROWS - 1) // _ROWS, sz, depth, normal, m, parallel,
        inv_d, inv_w, jump, crease, soft, do_crease, profile_out, crease_out,
        scratch=lambda: (np.empty((2, sz.shape[1]), dtype=np.float64),),
    )  # fmt: skip


# error_model="numpy" in the band kernels, as numba compiled the prange loop bodies they
# replace (a division by zero gives inf / NaN, it does not raise); _edge_pass_tasks keeps
# the default, as the task function the old loop called had it.
@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _pair_edge_blocks(
    b0, b1, sz, depth, normal, m, parallel, inv_d, inv_w, jump, crease, soft, do_crease,
    profile_out, crease_out, rows,
):  # fmt: skip
    """Row blocks ``b0 .. b1`` (of ``_ROWS`` rows) of :func:`pair_edge_kernel`; ``rows``
    (2, W) float64 is the band's scratch (the gaps down from the row above and from this row)."""
    h, w = sz.shape
    cos_min = math.cos(math.radians(crease))
    cos_skip = cos_min + _COS_MARGIN
    up, down = rows[0], rows[1]
    for b in range(b0, b1):
        r0 = np.int64(b) * _ROWS
        r1 = min(h, r0 + _ROWS)
        _down_gaps(sz, depth, m, r0 - 1, parallel, inv_d, up)
        for r in range(r0, r1):
            _down_gaps(sz, depth, m, r, parallel, inv_d, down)
            left = 0.0  # the jump of the pair (r, c - 1) -> (r, c)
            for c in range(w):
                profile_out[r, c] = 0.0
                crease_out[r, c] = 0.0
                if not _valid(sz, m, r, c):
                    continue
                prof = 0.0
                best = 0.0
                right = 0.0
                for k in range(4):
                    dr, dc = _DR4[k], _DC4[k]
                    r2, c2 = r + dr, c + dc
                    if not _inside(sz, r2, c2):
                        continue
                    if not _valid(sz, m, r2, c2):
                        prof = 1.0
                        continue
                    if k == 0:
                        gap = _pair_gap(sz, depth, m, r, c, 0, 1, 1, parallel, inv_d)
                        right = gap
                    elif k == 1:
                        gap = left
                    elif k == 2:
                        gap = down[c]
                    else:
                        gap = up[c]
                    if sz[r, c] > sz[r2, c2]:
                        prof = max(prof, _ramp(gap, jump, jump))
                    if k == 1 or k == 3 or gap > jump or not do_crease:
                        continue
                    geo = _depth_crease(
                        sz, depth, m, r, c, dr, dc, h, w, parallel, inv_d, inv_w, jump, cos_min
                    )
                    d = _dot(normal, r, c, r2, c2)
                    # Both turns below the threshold: no ink, and no acos (NaN still takes it).
                    if geo == 0.0 and d >= cos_skip:
                        continue
                    ang = math.degrees(math.acos(min(1.0, max(-1.0, np.float64(d)))))
                    if ang > abs(geo) and ang > crease:
                        ang = _normal_flanks(
                            sz, depth, normal, m, r, c, dr, dc, parallel, inv_d, jump, ang
                        )
                    if ang > abs(geo):
                        # Convex iff (nY - nX) . (PY - PX) > 0 (monotone normal map).
                        x1, y1, z1 = _eye(depth, r, c, h, w, parallel, inv_d, inv_w)
                        x2, y2, z2 = _eye(depth, r2, c2, h, w, parallel, inv_d, inv_w)
                        s = (
                            (normal[r2, c2, 0] - normal[r, c, 0]) * (x2 - x1)
                            + (normal[r2, c2, 1] - normal[r, c, 1]) * (y2 - y1)
                            + (normal[r2, c2, 2] - normal[r, c, 2]) * (z2 - z1)
                        )
                        geo = ang if s >= 0.0 else -ang
                    ink = _ramp(abs(geo), crease, soft)
                    if ink > abs(best):
                        best = ink if geo >= 0.0 else -ink
                left = right
                profile_out[r, c] = prof
                # A full profile pixel belongs to the outline; the depth there (e.g. along a
                # smooth silhouette) says nothing reliable about creases.
                crease_out[r, c] = best if prof < 1.0 else 0.0
            up, down = down, up


def id_edge_kernel(ids, depth, out):
    """1 on covered pixels X (``ids >= 0``) with a 4-neighbour Y of another id: the nearer of
    the two carries the line (ties: the upper / left one), and a background neighbour counts."""
    run_bands(_id_edge_rows, ids.shape[0], ids, depth, out)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _id_edge_rows(r0, r1, ids, depth, out):
    """Rows ``r0 .. r1`` of :func:`id_edge_kernel`."""
    h, w = ids.shape
    for r in range(r0, r1):
        r = np.int64(r)
        for c in range(w):
            a = ids[r, c]
            v = 0.0
            if a >= 0:
                for k in range(4):
                    r2, c2 = r + _DR4[k], c + _DC4[k]
                    if not (0 <= r2 < h and 0 <= c2 < w):
                        continue
                    b = ids[r2, c2]
                    if b == a:
                        continue
                    if (
                        b < 0
                        or depth[r, c] < depth[r2, c2]
                        or (depth[r, c] == depth[r2, c2] and (k == 0 or k == 2))
                    ):
                        v = 1.0
            out[r, c] = v


@njit(cache=True)
def _pair_jump(sz, depth, m, r, c, dr, dc, steps, parallel, inv_d, jump):
    """Depth discontinuity strength in [0, 1] of the pair (r, c) -> (r + steps d)."""
    r2, c2 = r + steps * dr, c + steps * dc
    if not (_inside(sz, r, c) and _inside(sz, r2, c2)):
        return 0.0  # the image border is not an edge
    a = _valid(sz, m, r, c)
    b = _valid(sz, m, r2, c2)
    if a != b:
        return 1.0
    if not a:
        return 0.0
    return _ramp(_pair_gap(sz, depth, m, r, c, dr, dc, steps, parallel, inv_d), jump, jump)


@njit(cache=True)
def _row_jumps(sz, depth, m, r, parallel, inv_d, jump, use_c1, out):
    """Jumps of the pairs from row ``r``: ``out[k, c + 1]`` from (r, c) to (r + 1, c - 1),
    (r + 1, c), (r + 1, c + 1) and (r, c + 1) for k = 0 to 3 (1 and 3 only if ``use_c1``);
    columns 0 and ``w + 1`` stand for the pairs outside the image (no edge)."""
    w = sz.shape[1]
    for k in range(4):
        if not use_c1 and (k == 1 or k == 3):
            continue
        dr = 1 if k < 3 else 0
        dc = k - 1 if k < 3 else 1
        out[k, 0] = 0.0
        out[k, w + 1] = 0.0
        for c in range(w):
            out[k, c + 1] = _pair_jump(sz, depth, m, r, c, dr, dc, 1, parallel, inv_d, jump)


def edge_map_kernel(sz, depth, normal, m, parallel, inv_d, jump, crease, soft, use_c1, out):
    """The 2003 edge map: RGB = inner (normal) intensity, A = profile (depth) intensity.

    Inner: the 2003 diagonal pairs (A, H) and (C, F) around X, from the pair with the smaller
    cosine (the pair that crosses an edge running along a diagonal). Profile: the diagonal
    ``1 - I_Z`` with ``|A - H|`` the larger unexplained jump of A -> X and X -> H scaled to
    [0, 2], or the C1 sum over the 8 neighbours of X (``use_c1``) scaled so a straight step
    gives 1. Each pair's jump is computed once, from its upper (or left) pixel.
    """
    run_bands(
        _edge_map_blocks, (sz.shape[0] + _ROWS - 1) // _ROWS, sz, depth, normal, m, parallel,
        inv_d, jump, crease, soft, use_c1, out,
        scratch=lambda: (np.empty((2, 4, sz.shape[1] + 2), dtype=np.float64),),
    )  # fmt: skip


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _edge_map_blocks(b0, b1, sz, depth, normal, m, parallel, inv_d, jump, crease, soft, use_c1,
                     out, rows):  # fmt: skip
    """Row blocks ``b0 .. b1`` (of ``_ROWS`` rows) of :func:`edge_map_kernel`; ``rows``
    (2, 4, W + 2) float64 is the band's scratch (the pairs of the row above and of this row)."""
    h, w = sz.shape
    cos_skip = math.cos(math.radians(crease)) + _COS_MARGIN
    up, cur = rows[0], rows[1]
    for b in range(b0, b1):
        r0 = np.int64(b) * _ROWS
        r1 = min(h, r0 + _ROWS)
        _row_jumps(sz, depth, m, r0 - 1, parallel, inv_d, jump, use_c1, up)
        for r in range(r0, r1):
            _row_jumps(sz, depth, m, r, parallel, inv_d, jump, use_c1, cur)
            for c in range(w):
                inner = 0.0
                if _valid(sz, m, r, c):
                    cmin = 1.0
                    for dc in range(-1, 2, 2):
                        r1_, c1_, r2_, c2_ = r - 1, c + dc, r + 1, c - dc
                        if _valid(sz, m, r1_, c1_) and _valid(sz, m, r2_, c2_):
                            cmin = min(cmin, np.float64(_dot(normal, r1_, c1_, r2_, c2_)))
                    # Below the threshold the ramp is 0: skip acos (NaN still takes it).
                    if not cmin >= cos_skip:
                        ang = math.degrees(math.acos(min(1.0, max(-1.0, cmin))))
                        inner = _ramp(ang, crease, soft)
                if use_c1:
                    # The 8 neighbours in the order (and so with the round-off) of the sum over
                    # dr, dc in (-1, 0, 1), weight 2 on the 4-neighbours; a pair read from its
                    # other pixel has the same jump bit for bit.
                    total = 0.0
                    total += 1.0 * up[2, c]
                    total += 2.0 * up[1, c + 1]
                    total += 1.0 * up[0, c + 2]
                    total += 2.0 * cur[3, c]
                    total += 2.0 * cur[3, c + 1]
                    total += 1.0 * cur[0, c + 1]
                    total += 2.0 * cur[1, c + 1]
                    total += 1.0 * cur[2, c + 1]
                    prof = min(1.0, 2.0 * total / 8.0)
                else:
                    # |A - H| (or |C - F|): a jump on either half of the diagonal through X.
                    # Two one-pixel tests, not one two-pixel one: curved walls seen edge-on
                    # bend within two pixels and would read as jumps.
                    iz = 1.0
                    for i in range(2):
                        if i == 0:
                            j = 2.0 * max(up[2, c], cur[2, c + 1])  # A -> X, X -> H
                        else:
                            j = 2.0 * max(up[0, c + 2], cur[0, c + 1])  # C -> X, X -> F
                        s = 1.0 - 0.5 * j
                        iz *= s * s
                    prof = 1.0 - iz
                out[r, c, 0] = inner
                out[r, c, 1] = inner
                out[r, c, 2] = inner
                out[r, c, 3] = prof
            up, cur = cur, up


# --------------------------------------------------------------------------- the fused pass
#
# ``edge_pass`` computes what ``pair_edge_kernel`` and ``edge_map_kernel`` compute, bit for bit,
# in one traversal and much faster. The speed comes from three things:
#
# - every pair's unexplained jump (4-neighbour and diagonal) is computed once, into row buffers
#   that both the pair classification and the 2003 operators read;
# - the depth-crease test, which needs the eye-space positions of four pixels per pair, reads
#   them from a ring of per-row eye positions (each position computed once, not ~8 times) and
#   runs the full :func:`_depth_crease` only for the few pairs whose section turn can reach the
#   threshold (the same floating-point test it starts with, so the same pairs pass);
# - spans of background (columns and rows with no covered pixel within two pixels) are skipped:
#   every output there is 0.

# Pair kinds of the row buffers, from (r, c) to: (r + 1, c - 1), (r + 1, c), (r + 1, c + 1),
# (r, c + 1); index c + 1 (columns 0 and w + 1 stand for pairs outside the image).
_KIND_DR = np.array([1, 1, 1, 0], dtype=np.int64)
_KIND_DC = np.array([-1, 0, 1, 1], dtype=np.int64)
#: Modes of :func:`edge_pass`.
MODE_PAIRS = 0
MODE_DIAGONAL = 1
MODE_C1 = 2


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _valid_spans(r0, r1, sz, m, lo, hi):
    """``lo[r]`` / ``hi[r]``: first / last valid column of row r (``w`` / ``-1`` if none), for
    the rows ``r0 .. r1``."""
    w = sz.shape[1]
    for r in range(r0, r1):
        r = np.int64(r)
        a = w
        for c in range(w):
            if _valid(sz, m, r, c):
                a = c
                break
        b = np.int64(-1)
        for c in range(w - 1, a - 1, -1):
            if _valid(sz, m, r, c):
                b = c
                break
        lo[r] = a
        hi[r] = b


@njit(cache=True)
def _ring_fill(sz, depth, m, row, a, b, h, w, parallel, inv_d, inv_w, eyes, S, D, V, EX, EY, EZ):
    """Ring slot ``row & 3`` of the row buffers over columns ``[a, b)`` (index ``c + 2``):
    ``S`` = sz and ``D`` = depth as float64, ``V`` = validity (:func:`_valid`) and, if
    ``eyes``, the eye-space positions (:func:`_eye`). Two columns on either side of the span
    (and rows outside the image) are invalid."""
    s = row & 3
    for i in (a, a + 1, b + 2, b + 3):
        V[s, i] = False
        S[s, i] = 0.0
        D[s, i] = 0.0
    if row < 0 or row >= h:
        for c in range(a, b):
            V[s, c + 2] = False
            S[s, c + 2] = 0.0
            D[s, c + 2] = 0.0
        return
    n = b - a
    _fill_row(
        sz[row, a:], depth[row, a:], m[row, a:], n, S[s, a + 2 :], D[s, a + 2 :], V[s, a + 2 :]
    )
    if eyes:
        _eye_row(
            depth[row, a:], a, n, 0.5 * h - row - 0.5, w, parallel, inv_d, inv_w,
            EX[s, a + 2 :], EY[s, a + 2 :], EZ[s, a + 2 :],
        )  # fmt: skip


@njit(cache=True, error_model="numpy")
def _fill_row(szr, dr, mr, n, S, D, V):
    """sz, depth (as float64) and validity (:func:`_valid`) of ``n`` pixels of a row."""
    for i in range(n):
        v = szr[i]
        V[i] = mr[i] & (v - v == 0.0)
        S[i] = np.float64(v)
        D[i] = np.float64(dr[i])


@njit(cache=True, error_model="numpy")
def _eye_row(dr, c0, n, y_row, w, parallel, inv_d, inv_w, EX, EY, EZ):
    """:func:`_eye` of ``n`` pixels of a row from column ``c0``, the same arithmetic
    (``y_row`` is its ``0.5 * h - r - 0.5``)."""
    for i in range(n):
        z = np.float64(dr[i])
        k = 1.0 if parallel else z * inv_d
        EX[i] = ((c0 + i) + 0.5 - 0.5 * w) * k
        EY[i] = y_row * k
        EZ[i] = -z * inv_w


@njit(cache=True, error_model="numpy")
def _kind_row(Sx, Sy, Sm, Sp, Vx, Vy, Vm, Vp, Dx, Dy, n, parallel, inv_d, jump, gap, pj):
    """One kind of :func:`_pair_rows`: ``n`` pairs from ``X = Sx[i]`` to ``Y = Sy[i]``, the
    one-sided slopes from ``Sm[i]`` (before X) and ``Sp[i]`` (after Y); the views start at
    the span, so every index is the loop's own (no negative-index wraparound: vectorised).

    Every use of a jump ``g`` (``g > jump`` and ``_ramp(g, jump, jump)``) is the same for all
    ``g <= jump``, and ``_pair_gap`` is ``G / sqrt(1 + s^2) <= G`` with ``G = gap * scale``
    (IEEE division by a number >= 1 never rounds above the dividend). So a first loop, without
    branches, stores ``G``; the root and the division are taken only where ``G > jump``, in a
    second loop over the few such pairs, with ``_pair_gap``'s arithmetic.
    """
    for i in range(n):
        vx = Vx[i]
        vy = Vy[i]
        ok = vx & vy & Vm[i] & Vp[i]
        x = Sx[i]
        y = Sy[i]
        jmp = y - x
        s_l = x - Sm[i]
        s_r = Sp[i] - y
        g = max(min(s_l, s_r) - jmp, jmp - max(s_l, s_r))
        scale = 1.0 if parallel else min(Dx[i], Dy[i]) * inv_d
        gap[i] = g * scale if (ok & (g > 0.0)) else 0.0
        pj[i] = 1.0 if vx != vy else 0.0
    # Blocks without such a pair (almost all) are passed over after one vectorised test:
    # a scalar test of every pair costs more than the first loop.
    for b0 in range(0, n, _SCAN):
        b1 = min(n, b0 + _SCAN)
        hit = False
        for i in range(b0, b1):
            hit |= gap[i] > jump  # (NaN: no hit, as in the test below)
        if hit:
            _kind_hits(Sx, Sy, Sm, Sp, Dx, Dy, b0, b1, parallel, inv_d, jump, gap, pj)


@njit(cache=True, error_model="numpy")
def _kind_hits(Sx, Sy, Sm, Sp, Dx, Dy, b0, b1, parallel, inv_d, jump, gap, pj):
    """The second loop of :func:`_kind_row` over pairs ``[b0, b1)``."""
    for i in range(b0, b1):
        if not gap[i] > jump:
            continue
        x = Sx[i]
        y = Sy[i]
        s_l = x - Sm[i]
        s_r = Sp[i] - y
        scale = 1.0 if parallel else min(Dx[i], Dy[i]) * inv_d
        sl = min(abs(s_l), abs(s_r)) * scale
        gg = gap[i] / math.sqrt(1.0 + sl * sl)
        gap[i] = gg
        pj[i] = _ramp(gg, jump, jump)


@njit(cache=True)
def _pair_rows(S, D, V, r, a, b, h, w, parallel, inv_d, jump, gap, pj):
    """Row buffers of the pairs from row ``r``, columns ``[a, b)``, from the ring buffers:
    ``gap[k, c + 1]`` the unexplained jump (:func:`_pair_gap`, same arithmetic) where both
    pixels are valid and it exceeds ``jump`` (else a number <= ``jump``), ``pj[k, c + 1]``
    the 2003 jump strength (:func:`_pair_jump`); the columns just outside the span are 0."""
    for k in range(4):
        gap[k, a] = 0.0
        gap[k, b + 1] = 0.0
        pj[k, a] = 0.0
        pj[k, b + 1] = 0.0
        dr = 1 if k < 3 else 0
        dc = k - 1 if k < 3 else 1
        if r < 0 or r + dr >= h:
            for c in range(a, b):
                gap[k, c + 1] = 0.0
                pj[k, c + 1] = 0.0
            continue
        sx, sy, sm, sp = r & 3, (r + dr) & 3, (r - dr) & 3, (r + 2 * dr) & 3
        o = a + 2  # ring index of column a
        _kind_row(
            S[sx, o:],
            S[sy, o + dc :],
            S[sm, o - dc :],
            S[sp, o + 2 * dc :],
            V[sx, o:],
            V[sy, o + dc :],
            V[sm, o - dc :],
            V[sp, o + 2 * dc :],
            D[sx, o:],
            D[sy, o + dc :],
            b - a,
            parallel,
            inv_d,
            jump,
            gap[k, a + 1 :],
            pj[k, a + 1 :],
        )
        # A pair leaving the image sideways is no pair (the border is not an edge).
        if dc < 0 and a == 0:
            pj[k, 1] = 0.0
        if dc > 0 and b == w:
            pj[k, w] = 0.0


@njit(cache=True)
def _pair_crease(
    sz,
    depth,
    normal,
    m,
    r,
    c,
    dr,
    dc,
    h,
    w,
    parallel,
    inv_d,
    inv_w,
    jump,
    crease,
    soft,
    cos_min,
    cos_skip,
    may_turn,
):
    """(ink, sign) of the crease of the pair (r, c) -> (r + dr, c + dc), as in
    :func:`pair_edge_kernel`; ``may_turn`` is :func:`_turn_row`'s test of the pair."""
    r2, c2 = r + dr, c + dc
    geo = 0.0
    if may_turn:
        geo = _depth_crease(sz, depth, m, r, c, dr, dc, h, w, parallel, inv_d, inv_w, jump, cos_min)
    d = _dot(normal, r, c, r2, c2)
    if geo == 0.0 and d >= cos_skip:
        return 0.0, 1.0
    ang = math.degrees(math.acos(min(1.0, max(-1.0, np.float64(d)))))
    if ang > abs(geo) and ang > crease:
        ang = _normal_flanks(sz, depth, normal, m, r, c, dr, dc, parallel, inv_d, jump, ang)
    if ang > abs(geo):
        x1, y1, z1 = _eye(depth, r, c, h, w, parallel, inv_d, inv_w)
        x2, y2, z2 = _eye(depth, r2, c2, h, w, parallel, inv_d, inv_w)
        s = (
            (normal[r2, c2, 0] - normal[r, c, 0]) * (x2 - x1)
            + (normal[r2, c2, 1] - normal[r, c, 1]) * (y2 - y1)
            + (normal[r2, c2, 2] - normal[r, c, 2]) * (z2 - z1)
        )
        geo = ang if s >= 0.0 else -ang
    return _ramp(abs(geo), crease, soft), geo


@njit(cache=True, error_model="numpy")
def _profile_row(Vc, Vl, Vr, Vu, Vd, Sc, Sl, Sr, Su, Sd, gl, gr, gu, gd, n, ins, jump, prof):
    """The profile ink of :func:`pair_edge_kernel` for ``n`` pixels of a row (views start at
    the span): 1 next to an invalid neighbour inside the image, else the largest ramp of the
    jumps towards farther neighbours. ``ins``: (left, right, up, down) neighbours inside the
    image for every pixel of the row (the first / last column are fixed by the caller)."""
    il, ir, iu, idn = ins[0], ins[1], ins[2], ins[3]
    for i in range(n):
        x = Sc[i]
        p = 0.0
        p = max(p, (1.0 if not Vl[i] else (_ramp(gl[i], jump, jump) if x > Sl[i] else 0.0)) * il)
        p = max(p, (1.0 if not Vr[i] else (_ramp(gr[i], jump, jump) if x > Sr[i] else 0.0)) * ir)
        p = max(p, (1.0 if not Vu[i] else (_ramp(gu[i], jump, jump) if x > Su[i] else 0.0)) * iu)
        p = max(p, (1.0 if not Vd[i] else (_ramp(gd[i], jump, jump) if x > Sd[i] else 0.0)) * idn)
        prof[i] = p if Vc[i] else 0.0


@njit(cache=True)
def _profile_at(V, S, cur_g, up_g, r, c, h, w, jump):
    """The profile ink of :func:`_profile_row` at one pixel, image borders respected."""
    s_r = r & 3
    ic = c + 2
    if not V[s_r, ic]:
        return 0.0
    p = 0.0
    for k in range(4):
        dr, dc = _DR4[k], _DC4[k]
        r2, c2 = r + dr, c + dc
        if not (r2 >= 0 and r2 < h and c2 >= 0 and c2 < w):
            continue
        s2 = (r2) & 3
        if not V[s2, ic + dc]:
            p = 1.0
            continue
        if k == 0:
            g = cur_g[3, c + 1]
        elif k == 1:
            g = cur_g[3, c]
        elif k == 2:
            g = cur_g[1, c + 1]
        else:
            g = up_g[1, c + 1]
        if S[s_r, ic] > S[s2, ic + dc]:
            p = max(p, _ramp(g, jump, jump))
    return p


@njit(cache=True, error_model="numpy")
def _turn_row(V0, V3, X0, Y0, Z0, X1, Y1, Z1, X2, Y2, Z2, X3, Y3, Z3, n, cos_min, may):
    """The first test of :func:`_depth_crease` for ``n`` pairs of a row, without its root:
    False only where the segments P0 -> P1 and P2 -> P3 (eye positions; P0 and P3 valid)
    certainly turn by less than the threshold. ``dot >= cos_min |a| |b|`` is implied by
    ``dot^2 >= cos_min^2 |a|^2 |b|^2 (1 + 1e-9)`` for ``dot > 0`` (the margin is far beyond
    round-off), and by ``dot >= 0`` if ``cos_min <= 0``; pairs between the two forms are
    candidates, which :func:`_depth_crease` then tests exactly."""
    c2 = cos_min * cos_min * (1.0 + 1e-9)
    wide = cos_min <= 0.0
    for i in range(n):
        ax = X1[i] - X0[i]
        ay = Y1[i] - Y0[i]
        az = Z1[i] - Z0[i]
        bx = X3[i] - X2[i]
        by = Y3[i] - Y2[i]
        bz = Z3[i] - Z2[i]
        dot = ax * bx + ay * by + az * bz
        prod = (ax * ax + ay * ay + az * az) * (bx * bx + by * by + bz * bz)
        straight = (dot >= 0.0) if wide else ((dot > 0.0) & (dot * dot >= c2 * prod))
        may[i] = V0[i] & V3[i] & (not straight)


@njit(cache=True, error_model="numpy")
def _dot_row(N0, N1, n, out):
    """float32 dot products of the normals of two rows (as :func:`_dot` sums them)."""
    for i in range(n):
        out[i] = N0[i, 0] * N1[i, 0] + N0[i, 1] * N1[i, 1] + N0[i, 2] * N1[i, 2]


@njit(cache=True, error_model="numpy")
def _candidates_row(
    Vc, Vr, Vd, gr, gd, may_h, may_v, dot_h, dot_v, n, jump, cos_skip, last_col, has_down, cand
):
    """Bit 1 / 2 of ``cand[i]``: the pair to the right / below may be a crease (both pixels
    valid, depth continuous, and the section or the normals turn enough); the tests of
    :func:`pair_edge_kernel` before its exact evaluation, in the same floating-point form."""
    for i in range(n):
        ch = Vc[i] & Vr[i] & (not gr[i] > jump) & (may_h[i] | (not dot_h[i] >= cos_skip))
        cv = Vc[i] & Vd[i] & (not gd[i] > jump) & (may_v[i] | (not dot_v[i] >= cos_skip))
        cand[i] = (1 if ch else 0) + (2 if cv and has_down else 0)
    if last_col:
        cand[n - 1] &= 2  # the last column has no right neighbour


@njit(cache=True)
def _store_row(prof, cre, n, out_a, out_b):
    for i in range(n):
        out_a[i] = prof[i]
        out_b[i] = cre[i]


@njit(cache=True, error_model="numpy")
def _inner_row(Vc, Vul, Vdr, Vur, Vdl, d1, d2, n, cos_skip, out):
    """The smaller cosine of the two diagonal normal pairs around each valid pixel (1 where
    none), as :func:`edge_map_kernel` takes it; ``d1``/``d2`` from :func:`_dot_row`."""
    for i in range(n):
        cmin = 1.0
        if Vul[i] & Vdr[i]:
            cmin = min(cmin, np.float64(d1[i]))
        if Vur[i] & Vdl[i]:
            cmin = min(cmin, np.float64(d2[i]))
        out[i] = cmin if Vc[i] else 1.0


@njit(cache=True, error_model="numpy")
def _c1_row(ul, u, ur, x_l, x_r, x_dl, x_d, x_dr, n, out):
    """The C1 profile of :func:`edge_map_kernel` from the pair rows."""
    for i in range(n):
        total = 0.0
        total += 1.0 * ul[i]
        total += 2.0 * u[i]
        total += 1.0 * ur[i]
        total += 2.0 * x_l[i]
        total += 2.0 * x_r[i]
        total += 1.0 * x_dl[i]
        total += 2.0 * x_d[i]
        total += 1.0 * x_dr[i]
        out[i] = min(1.0, 2.0 * total / 8.0)


@njit(cache=True, error_model="numpy")
def _diagonal_row(ax, xh, cx, xf, n, out):
    """The diagonal profile ``1 - I_Z`` of :func:`edge_map_kernel` from the pair rows."""
    for i in range(n):
        s = 1.0 - 0.5 * (2.0 * max(ax[i], xh[i]))
        iz = 1.0 * (s * s)
        s = 1.0 - 0.5 * (2.0 * max(cx[i], xf[i]))
        iz *= s * s
        out[i] = 1.0 - iz


@njit(cache=True, error_model="numpy")
def _combine_row(inner, cre, prof, n, out_a, out_b):
    """``max(inner, |crease|)`` of the float32 images (NaN kept, as ``np.maximum``) and the
    profile, into the output rows."""
    for i in range(n):
        fi = np.float32(inner[i])
        fc = np.float32(abs(np.float32(cre[i])))
        v = fi if fi >= fc else fc
        out_a[i] = np.float32(np.nan) if (fi != fi) | (fc != fc) else v
        out_b[i] = prof[i]


@njit(cache=True)
def _best_crease(
    sz, depth, normal, m, r, c, bits, may_h, may_v, h, w, parallel, inv_d, inv_w, jump,
    crease, soft, cos_min, cos_skip,
):  # fmt: skip
    """The signed crease ink of pixel (r, c) in :func:`pair_edge_kernel`: the stronger of its
    pairs to the right (``bits & 1``) and below (``bits & 2``) that are candidates."""
    best = 0.0
    # Typed steps, not literals: numba compiles a callee once per literal value it is given.
    zero, one = np.int64(0), np.int64(1)
    if bits & 1:
        ink, geo = _pair_crease(
            sz, depth, normal, m, r, c, zero, one, h, w, parallel, inv_d, inv_w, jump, crease, soft,
            cos_min, cos_skip, may_h,
        )  # fmt: skip
        if ink > abs(best):
            best = ink if geo >= 0.0 else -ink
    if bits & 2:
        ink, geo = _pair_crease(
            sz, depth, normal, m, r, c, one, zero, h, w, parallel, inv_d, inv_w, jump, crease, soft,
            cos_min, cos_skip, may_v,
        )  # fmt: skip
        if ink > abs(best):
            best = ink if geo >= 0.0 else -ink
    return best


@njit(cache=True)
def _crease_row(
    sz, depth, normal, m, r, a, n, cand, prof, may_h, may_v, h, w, parallel, inv_d, inv_w,
    jump, crease, soft, cos_min, cos_skip, two, crease2, soft2, cos_min2, cos_skip2,
    cre_row, cre_row2,
):  # fmt: skip
    """The exact crease ink of the candidate pixels of row ``r`` (``cand[i] != 0``), at one
    or two angles (:func:`_best_crease`). Candidates are few: blocks without one are passed
    over after one vectorised test (a scalar test of every pixel costs more)."""
    for b0 in range(0, n, _SCAN):
        b1 = min(n, b0 + _SCAN)
        hit = False
        for i in range(b0, b1):
            hit |= cand[i] != 0
        if not hit:
            continue
        for i in range(b0, b1):
            if cand[i] == 0:
                continue
            c = a + i
            if prof[i] >= 1.0:
                continue  # a full profile pixel carries no crease ink
            cre_row[i] = _best_crease(
                sz, depth, normal, m, r, c, cand[i], may_h[i], may_v[i], h, w,
                parallel, inv_d, inv_w, jump, crease, soft, cos_min, cos_skip,
            )  # fmt: skip
            if two:
                cre_row2[i] = _best_crease(
                    sz, depth, normal, m, r, c, cand[i], may_h[i], may_v[i], h, w,
                    parallel, inv_d, inv_w, jump, crease2, soft2, cos_min2, cos_skip2,
                )  # fmt: skip


@njit(cache=True, nogil=True, _nrt=False)
def _edge_pass_tasks(
    t0, t1, sz, depth, normal, m, parallel, inv_d, inv_w, jump, crease, soft, do_crease, mode,
    out_a, out_b, two, crease2, soft2, out_c, lo, hi, cos_min, cos_skip, cos_min_c, cos_skip_c,
    cos_min2, cos_skip2, gj, ring, vring, rows, mays, dots, ins, cand,
):  # fmt: skip
    """Tasks ``t0 .. t1`` of :func:`edge_pass` (a band of :func:`.run_bands`): task ``t`` is the
    rows ``t * _ROWS`` to ``(t + 1) * _ROWS``, as when each task was one ``prange`` iteration
    (the outputs do not depend on how tasks are grouped). ``gj`` ... ``cand`` are the band's
    row buffers (:func:`edge_pass`), set up again for each task as if it had made its own."""
    h, w = sz.shape
    for t in range(t0, t1):
        r0 = t * _ROWS
        r1 = min(h, r0 + _ROWS)
        # The task's span: columns within two pixels of a valid one in rows r0 - 2 .. r1 + 1.
        a = w
        b = np.int64(0)
        for r in range(max(0, r0 - 2), min(h, r1 + 2)):
            a = min(a, lo[r])
            b = max(b, hi[r] + 1)
        if a >= b:
            a = b = 0
        else:
            a = max(0, a - 2)
            b = min(w, b + 2)
        for r in range(r0, r1):
            for c in range(a):
                out_a[r, c] = 0.0
                out_b[r, c] = 0.0
            for c in range(b, w):
                out_a[r, c] = 0.0
                out_b[r, c] = 0.0
            if two:
                for c in range(a):
                    out_c[r, c] = 0.0
                for c in range(b, w):
                    out_c[r, c] = 0.0
        if a >= b:
            continue
        # The task's buffers (a kernel without reference counting cannot allocate): the
        # swapped row pairs from their first rows again, and the ones it may read before
        # writing with the values it used to allocate them with.
        up_g, up_j, cur_g, cur_j = gj[0], gj[1], gj[2], gj[3]
        S, D, EX, EY, EZ = ring[0], ring[1], ring[2], ring[3], ring[4]
        V = vring
        prof, cre_row, cre_row2, inner_row = rows[0], rows[1], rows[2], rows[3]
        may_h, may_v = mays[0], mays[1]
        dot_h, dot_v, dot_d1, dot_d2 = dots[0], dots[1], dots[2], dots[3]
        one32 = np.float32(1.0)
        for i in range(w):
            may_h[i] = False
            may_v[i] = False
            dot_h[i] = one32
            dot_v[i] = one32
            dot_d1[i] = one32
            dot_d2[i] = one32
            cand[i] = 0
        for r in range(r0 - 2, r0 + 2):
            _ring_fill(
                sz, depth, m, r, a, b, h, w, parallel, inv_d, inv_w, do_crease, S, D, V, EX, EY, EZ
            )
        _pair_rows(S, D, V, r0 - 1, a, b, h, w, parallel, inv_d, jump, up_g, up_j)
        for r in range(r0, r1):
            _ring_fill(
                sz,
                depth,
                m,
                r + 2,
                a,
                b,
                h,
                w,
                parallel,
                inv_d,
                inv_w,
                do_crease,
                S,
                D,
                V,
                EX,
                EY,
                EZ,
            )
            _pair_rows(S, D, V, r, a, b, h, w, parallel, inv_d, jump, cur_g, cur_j)
            s_up, s_r, s_dn, s_dn2 = (r - 1) & 3, r & 3, (r + 1) & 3, (r + 2) & 3
            n = b - a
            o = a + 2  # ring index of column a
            ins[0] = 1.0
            ins[1] = 1.0
            ins[2] = 1.0 if r > 0 else 0.0
            ins[3] = 1.0 if r + 1 < h else 0.0
            _profile_row(
                V[s_r, o:],
                V[s_r, o - 1 :],
                V[s_r, o + 1 :],
                V[s_up, o:],
                V[s_dn, o:],
                S[s_r, o:],
                S[s_r, o - 1 :],
                S[s_r, o + 1 :],
                S[s_up, o:],
                S[s_dn, o:],
                cur_g[3, a:],
                cur_g[3, a + 1 :],
                up_g[1, a + 1 :],
                cur_g[1, a + 1 :],
                n,
                ins,
                jump,
                prof,
            )
            # The image border is not an edge: the first / last column has no neighbour there.
            for c in (0, w - 1):
                if a <= c < b:
                    prof[c - a] = _profile_at(V, S, cur_g, up_g, r, c, h, w, jump)
            rn = min(r + 1, h - 1)  # (a row that exists; unused where the row below does not)
            ru = max(r - 1, 0)
            if do_crease:
                _turn_row(
                    V[s_r, o - 1 :],
                    V[s_r, o + 2 :],
                    EX[s_r, o - 1 :],
                    EY[s_r, o - 1 :],
                    EZ[s_r, o - 1 :],
                    EX[s_r, o:],
                    EY[s_r, o:],
                    EZ[s_r, o:],
                    EX[s_r, o + 1 :],
                    EY[s_r, o + 1 :],
                    EZ[s_r, o + 1 :],
                    EX[s_r, o + 2 :],
                    EY[s_r, o + 2 :],
                    EZ[s_r, o + 2 :],
                    n,
                    cos_min_c,
                    may_h,
                )
                _turn_row(
                    V[s_up, o:],
                    V[s_dn2, o:],
                    EX[s_up, o:],
                    EY[s_up, o:],
                    EZ[s_up, o:],
                    EX[s_r, o:],
                    EY[s_r, o:],
                    EZ[s_r, o:],
                    EX[s_dn, o:],
                    EY[s_dn, o:],
                    EZ[s_dn, o:],
                    EX[s_dn2, o:],
                    EY[s_dn2, o:],
                    EZ[s_dn2, o:],
                    n,
                    cos_min_c,
                    may_v,
                )
                _dot_row(
                    normal[r, a:], normal[r, min(a + 1, w - 1) :], n - (1 if b == w else 0), dot_h
                )
                _dot_row(normal[r, a:], normal[rn, a:], n, dot_v)
            # The diagonal pairs of pixel c = a + i, at index i: (r - 1, c - 1) . (r + 1, c + 1)
            # and (r - 1, c + 1) . (r + 1, c - 1), for the columns that have both.
            c_lo, c_hi = max(a, 1), min(b, w - 1)
            if mode != MODE_PAIRS and c_hi > c_lo:
                nd = c_hi - c_lo
                _dot_row(normal[ru, c_lo - 1 :], normal[rn, c_lo + 1 :], nd, dot_d1[c_lo - a :])
                _dot_row(normal[ru, c_lo + 1 :], normal[rn, c_lo - 1 :], nd, dot_d2[c_lo - a :])
            if do_crease:
                _candidates_row(
                    V[s_r, o:],
                    V[s_r, o + 1 :],
                    V[s_dn, o:],
                    cur_g[3, a + 1 :],
                    cur_g[1, a + 1 :],
                    may_h,
                    may_v,
                    dot_h,
                    dot_v,
                    n,
                    jump,
                    cos_skip_c,
                    1 if b == w else 0,
                    1 if r + 1 < h else 0,
                    cand,
                )
            for i in range(n):
                cre_row[i] = 0.0
                cre_row2[i] = 0.0
            if do_crease:
                _crease_row(
                    sz, depth, normal, m, r, a, n, cand, prof, may_h, may_v, h, w, parallel,
                    inv_d, inv_w, jump, crease, soft, cos_min, cos_skip, two, crease2, soft2,
                    cos_min2, cos_skip2, cre_row, cre_row2,
                )  # fmt: skip
            if mode == MODE_PAIRS:
                _store_row(prof, cre_row, n, out_a[r, a:], out_b[r, a:])
                if two:
                    # A loop, not a slice assignment: numba's shape check of that
                    # compiles its error message, seconds of a first run.
                    for i in range(n):
                        out_c[r, a + i] = cre_row2[i]
            else:
                _edge_map_row(
                    V,
                    S,
                    dot_d1,
                    dot_d2,
                    up_j,
                    cur_j,
                    r,
                    a,
                    n,
                    mode,
                    crease,
                    soft,
                    cos_skip,
                    prof,
                    cre_row,
                    inner_row,
                    out_a[r, a:],
                    out_b[r, a:],
                )
            up_g, cur_g = cur_g, up_g
            up_j, cur_j = cur_j, up_j


def edge_pass(
    sz,
    depth,
    normal,
    m,
    parallel,
    inv_d,
    inv_w,
    jump,
    crease,
    soft,
    do_crease,
    mode,
    out_a,
    out_b,
    crease2,
    soft2,
    out_c,
):
    """Profile and crease ink of :func:`pair_edge_kernel` (``mode`` 0: ``out_a`` = profile,
    ``out_b`` = signed crease), or the one-pixel 2003 edge map of :func:`edge_map_kernel`
    with the depth's creases added to its inner edges (``mode`` 1 diagonal, 2 C1: ``out_a``
    = ``max(inner, |crease|)``, ``out_b`` = profile), in one pass (see the section comment).
    With ``crease2 > 0`` (mode 0), ``out_c`` gets the signed crease ink at that second angle
    (``soft2``) too: the same as a second pass at it, for the price of one.
    """
    h = sz.shape[0]
    cos_min = math.cos(math.radians(crease))
    cos_skip = cos_min + _COS_MARGIN
    two = crease2 > 0.0 and mode == MODE_PAIRS
    cos_min2 = math.cos(math.radians(crease2)) if two else cos_min
    cos_skip2 = cos_min2 + _COS_MARGIN
    # The candidate tests at the smaller angle pass every pair the larger one passes; each
    # candidate is then evaluated exactly at each angle (the same ink as one pass per angle).
    cos_min_c = max(cos_min, cos_min2)
    cos_skip_c = cos_min_c + _COS_MARGIN
    lo = np.empty(h, dtype=np.int64)
    hi = np.empty(h, dtype=np.int64)
    run_bands(_valid_spans, h, sz, m, lo, hi)
    w = sz.shape[1]
    run_bands(
        _edge_pass_tasks, (h + _ROWS - 1) // _ROWS, sz, depth, normal, m, parallel, inv_d,
        inv_w, jump, crease, soft, do_crease, mode, out_a, out_b, two, crease2, soft2, out_c, lo,
        hi, cos_min, cos_skip, cos_min_c, cos_skip_c, cos_min2, cos_skip2,
        scratch=lambda: _edge_pass_buffers(w),
    )  # fmt: skip


def _edge_pass_buffers(w: int) -> tuple[np.ndarray, ...]:
    """One band's row buffers of :func:`_edge_pass_tasks`: the pair gaps and jumps of two rows
    (``gj`` up_g, up_j, cur_g, cur_j), the ring of four rows (``ring`` S, D, EX, EY, EZ and
    ``vring`` V), the row results (prof, cre_row, cre_row2, inner_row), the crease flags
    (may_h, may_v), the normals' dot products (dot_h, dot_v, dot_d1, dot_d2), ``ins`` and
    ``cand``."""
    return (
        np.empty((4, 4, w + 2), dtype=np.float64),
        np.empty((5, 4, w + 4), dtype=np.float64),
        np.empty((4, w + 4), dtype=np.bool_),
        np.empty((4, w), dtype=np.float64),
        np.empty((2, w), dtype=np.bool_),
        np.empty((4, w), dtype=np.float32),
        np.empty(4, dtype=np.float64),
        np.empty(w, dtype=np.uint8),
    )


@njit(cache=True)
def _edge_map_row(
    V,
    S,
    dot_d1,
    dot_d2,
    up_j,
    cur_j,
    r,
    a,
    n,
    mode,
    crease,
    soft,
    cos_skip,
    prof,
    cre_row,
    inner_row,
    out_a,
    out_b,
):
    """The 2003 operators of :func:`edge_map_kernel` on one row of the span, combined with the
    crease row into the output rows (``prof`` is overwritten)."""
    s_up, s_r, s_dn = (r - 1) & 3, r & 3, (r + 1) & 3
    o = a + 2
    _inner_row(
        V[s_r, o:],
        V[s_up, o - 1 :],
        V[s_dn, o + 1 :],
        V[s_up, o + 1 :],
        V[s_dn, o - 1 :],
        dot_d1,
        dot_d2,
        n,
        cos_skip,
        inner_row,
    )
    for i in range(n):
        cm = inner_row[i]
        if not cm >= cos_skip:
            ang = math.degrees(math.acos(min(1.0, max(-1.0, cm))))
            inner_row[i] = _ramp(ang, crease, soft)
        else:
            inner_row[i] = 0.0
    if mode == MODE_C1:
        _c1_row(
            up_j[2, a:],
            up_j[1, a + 1 :],
            up_j[0, a + 2 :],
            cur_j[3, a:],
            cur_j[3, a + 1 :],
            cur_j[0, a + 1 :],
            cur_j[1, a + 1 :],
            cur_j[2, a + 1 :],
            n,
            prof,
        )
    else:
        _diagonal_row(up_j[2, a:], cur_j[2, a + 1 :], up_j[0, a + 2 :], cur_j[0, a + 1 :], n, prof)
    _combine_row(inner_row, cre_row, prof, n, out_a, out_b)


@njit(cache=True, error_model="numpy")
def _block_row(src, k, ow, acc, cnt):
    """Sums and counts of the non-NaN samples of ``k`` rows of ``src`` over blocks of ``k``
    columns (the first ``ow`` blocks), in the order ``GBuffer.downsample`` adds them."""
    for j in range(ow):
        acc[j] = 0.0
        cnt[j] = 0
    for i in range(k):
        row = src[i]
        for q in range(k):
            for j in range(ow):
                v = row[j * k + q]
                ok = v == v
                acc[j] += np.float64(v) if ok else 0.0
                cnt[j] += 1 if ok else 0


def edge_map_finish(inner, alpha, k, out):
    """``out`` (h, w, 4): the ``k x k`` block means of ``inner`` (into R, G, B) and ``alpha``
    (into A), NaN samples left out as in ``GBuffer.downsample``, clipped to [0, 1]: the
    downsample, stack and clip of the edge map in one pass."""
    ow = out.shape[1]
    run_bands(
        _edge_map_finish_rows, out.shape[0], inner, alpha, k, out,
        scratch=lambda: (np.empty(ow, dtype=np.float64), np.empty(ow, dtype=np.int64)),
    )  # fmt: skip


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _edge_map_finish_rows(r0, r1, inner, alpha, k, out, acc, cnt):
    """Output rows ``r0 .. r1`` of :func:`edge_map_finish`; ``acc``, ``cnt`` (W_out,) are the
    band's scratch (rewritten for every row)."""
    ow = out.shape[1]
    for r in range(r0, r1):
        r = np.int64(r)
        for ch in range(2):
            _block_row((inner if ch == 0 else alpha)[r * k : r * k + k], k, ow, acc, cnt)
            for col in range(ow):
                n = cnt[col]
                v = np.float32(acc[col] / n) if n > 0 else np.float32(np.nan)
                if v < 0.0:
                    v = np.float32(0.0)
                elif v > 1.0:
                    v = np.float32(1.0)
                if ch == 0:
                    out[r, col, 0] = v
                    out[r, col, 1] = v
                    out[r, col, 2] = v
                else:
                    out[r, col, 3] = v


# --------------------------------------------------------------------------- line cleaning
#
# The speck removal and hysteresis of ``edges._clean``, on the ink pixels only: lines cover a few
# per cent of a picture, so two connected-component labellings of the whole image (and their
# label images) cost far more than union-find over a list of the ink pixels.


@njit(cache=True)
def _find(parent, i):
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True)
def _union(parent, i, j):
    a = _find(parent, i)
    b = _find(parent, j)
    if a < b:
        parent[b] = a
    elif b < a:
        parent[a] = b


@njit(cache=True)
def clean_lines(profile, crease, mask, length, ids):
    """Zero, in place, the ink of ``profile`` / ``crease`` that ``edges._clean`` drops; returns
    whether anything was dropped.

    Strong ink (>= 0.5 in either image) forms 8-connected pieces; a piece stays if it has at
    least ``length`` pixels (``length > 0``; else every piece stays) or a pixel on the outline
    of ``mask`` (covered, with an uncovered 4-neighbour inside the image). All ink except the
    strong pixels of dropped pieces forms 8-connected lines; a line stays if it holds a strong
    pixel of a piece that stays. ``ids``: an int32 image of the buffer's shape, all 0 on entry
    and on return (scratch: the ink pixels' numbers + 1 while it runs).
    """
    h, w = profile.shape
    n = 0
    for r in range(h):
        for c in range(w):
            if profile[r, c] > 0.0 or crease[r, c] != 0.0:
                n += 1
    pix = np.empty(n, dtype=np.int64)
    strong = np.empty(n, dtype=np.bool_)
    i = 0
    for r in range(h):
        for c in range(w):
            if profile[r, c] > 0.0 or crease[r, c] != 0.0:
                pix[i] = r * w + c
                strong[i] = profile[r, c] >= 0.5 or abs(crease[r, c]) >= 0.5
                ids[r, c] = i + 1
                i += 1
    # The strong pieces.
    parent = np.arange(n)
    for i in range(n):
        if not strong[i]:
            continue
        r, c = pix[i] // w, pix[i] % w
        for dr, dc in ((-1, -1), (-1, 0), (-1, 1), (0, -1)):
            r2, c2 = r + dr, c + dc
            if 0 <= r2 < h and 0 <= c2 < w:
                j = ids[r2, c2] - 1
                if j >= 0 and strong[j]:
                    _union(parent, i, j)
    size = np.zeros(n, dtype=np.int64)
    edge = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        if not strong[i]:
            continue
        root = _find(parent, i)
        size[root] += 1
        r, c = pix[i] // w, pix[i] % w
        if mask[r, c] and (
            (c + 1 < w and not mask[r, c + 1])
            or (c > 0 and not mask[r, c - 1])
            or (r + 1 < h and not mask[r + 1, c])
            or (r > 0 and not mask[r - 1, c])
        ):
            edge[root] = True
    kept = np.zeros(n, dtype=np.bool_)  # strong pixels of pieces that stay
    node = np.empty(n, dtype=np.bool_)  # the pixels of the lines
    for i in range(n):
        if strong[i]:
            root = _find(parent, i)
            kept[i] = length <= 0 or size[root] >= length or edge[root]
        node[i] = kept[i] or not strong[i]
    # The lines, anchored on the kept pieces.
    for i in range(n):
        parent[i] = i
    for i in range(n):
        if not node[i]:
            continue
        r, c = pix[i] // w, pix[i] % w
        for dr, dc in ((-1, -1), (-1, 0), (-1, 1), (0, -1)):
            r2, c2 = r + dr, c + dc
            if 0 <= r2 < h and 0 <= c2 < w:
                j = ids[r2, c2] - 1
                if j >= 0 and node[j]:
                    _union(parent, i, j)
    anchored = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        if kept[i]:
            anchored[_find(parent, i)] = True
    dropped = False
    for i in range(n):
        r, c = pix[i] // w, pix[i] % w
        ids[r, c] = 0
        if not (node[i] and anchored[_find(parent, i)]):
            profile[r, c] = 0.0
            crease[r, c] = 0.0
            dropped = True
    return dropped


def finish_lines(ink, k, signed, out):
    """``out`` (h, w): the ``k x k`` block means of ``ink`` clipped to [0, 1], NaN samples left
    out (``GBuffer.downsample``); with ``signed``, the clipped mean of the positive part
    minus that of the negative part (as ``edges._finish_signed`` takes them)."""
    ow = out.shape[1]
    run_bands(
        _finish_lines_rows, out.shape[0], ink, k, signed, out,
        scratch=lambda: (np.empty((2, ow), dtype=np.float64), np.empty(ow, dtype=np.int64)),
    )  # fmt: skip


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _finish_lines_rows(r0, r1, ink, k, signed, out, sums, cnt):
    """Output rows ``r0 .. r1`` of :func:`finish_lines`; ``sums`` (2, W_out) and ``cnt``
    (W_out,) are the band's scratch (zeroed for every row)."""
    ow = out.shape[1]
    tp, tn = sums[0], sums[1]
    for r in range(r0, r1):
        r = np.int64(r)
        for j in range(ow):
            tp[j] = 0.0
            tn[j] = 0.0
            cnt[j] = 0
        for i in range(r * k, r * k + k):
            row = ink[i]
            for q in range(k):
                for j in range(ow):
                    v = row[j * k + q]
                    ok = v == v
                    cnt[j] += 1 if ok else 0
                    if signed:
                        tp[j] += np.float64(max(v, np.float32(0.0))) if ok else 0.0
                        tn[j] += np.float64(max(-v, np.float32(0.0))) if ok else 0.0
                    else:
                        tp[j] += np.float64(v) if ok else 0.0
        for col in range(ow):
            n = cnt[col]
            if n == 0:
                out[r, col] = np.float32(np.nan)
                continue
            p = np.float32(tp[col] / n)
            p = min(max(p, np.float32(0.0)), np.float32(1.0))
            if signed:
                q = np.float32(tn[col] / n)
                q = min(max(q, np.float32(0.0)), np.float32(1.0))
                out[r, col] = p - q
            else:
                out[r, col] = p


def enhance_kernel(img, em, inner_c, prof_c, out):
    """``edges.enhance`` per pixel: the shade (NaN -> 1, clipped; ``img`` (H, W, 1) is grey,
    (H, W, 3) RGB), then ``lerp`` to ``inner_c`` by R and to ``prof_c`` by A of the edge map
    (NaN -> 0, clipped), in float32 as the array expressions take them."""
    run_bands(_enhance_rows, out.shape[0], img, em, inner_c, prof_c, out)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _enhance_rows(r0, r1, img, em, inner_c, prof_c, out):
    """Rows ``r0 .. r1`` of :func:`enhance_kernel`."""
    w = out.shape[1]
    grey = img.shape[2] == 1
    one = np.float32(1.0)
    zero = np.float32(0.0)
    for r in range(r0, r1):
        for c in range(w):
            i = em[r, c, 0]
            i = zero if np.isnan(i) else min(max(i, zero), one)
            a = em[r, c, 3]
            a = zero if np.isnan(a) else min(max(a, zero), one)
            for ch in range(3):
                v = img[r, c, 0 if grey else ch]
                v = one if np.isnan(v) else min(max(v, zero), one)
                v += (inner_c[ch] - v) * i
                v += (prof_c[ch] - v) * a
                out[r, c, ch] = v


@njit(cache=True, error_model="numpy")
def _max_row(src, n, out):
    """``out[c] = np.maximum(out[c], src[c])`` for ``n`` columns (NaN propagates)."""
    for c in range(n):
        m = out[c]
        v = src[c]
        out[c] = v if (v > m) | (v != v) else m


def dilate_kernel(ink, sign, lo, runs_a, runs_b, pad, out):
    """``out``: the grey dilation of ``ink`` (of its part ``max(sign * ink, 0)`` if ``sign`` is
    not 0) by the footprint whose row ``i`` is the run of columns ``runs_a[i]..runs_b[i]``,
    centred at ``lo`` as ``scipy.ndimage.grey_dilation`` centres it, 0 outside the image; NaN
    propagates as in ``np.maximum``. The input is copied into ``pad`` ((h + size - 1,
    w + size - 1), its border 0), so the maxima run over whole rows without a test per pixel."""
    h = ink.shape[0]
    run_bands(_dilate_pad_rows, h, ink, sign, lo, pad)
    run_bands(_dilate_max_rows, h, ink, runs_a, runs_b, pad, out)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _dilate_pad_rows(r0, r1, ink, sign, lo, pad):
    """Rows ``r0 .. r1`` of :func:`dilate_kernel`'s input, into ``pad``."""
    w = ink.shape[1]
    for r in range(r0, r1):
        r = np.int64(r)
        src = ink[r]
        dst = pad[r + lo, lo:]
        for c in range(w):
            v = src[c]
            if sign != 0:
                v = max(sign * v, np.float32(0.0)) if v == v else v
            dst[c] = v


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _dilate_max_rows(r0, r1, ink, runs_a, runs_b, pad, out):
    """Rows ``r0 .. r1`` of :func:`dilate_kernel`'s output, from the filled ``pad``."""
    w = ink.shape[1]
    size = runs_a.size
    for r in range(r0, r1):
        r = np.int64(r)
        row = out[r]
        for c in range(w):
            row[c] = np.float32(-np.inf)
        for i in range(size):
            prow = pad[r + i]
            for j in range(runs_a[i], runs_b[i] + 1):
                _max_row(prow[j:], w, row)
