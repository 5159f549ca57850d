"""Tensor-product Bezier patch math: Bernstein bases, derivatives, normals, curvatures.

Pure numpy, vectorised over parameter arrays (no per-point Python loops). A patch is a control
net ``P`` of shape ``(du + 1, dv + 1, 3)``; ``S(u, v) = sum_ij B_i^du(u) B_j^dv(v) P[i, j]``.

Degenerate points (``Su x Sv = 0``: collapsed patch edges such as the Utah teapot's lid tip and
bottom centre, where a whole row of control points coincides) have no first-order normal.
There the normal is the limit from the patch interior (Taylor expansion of ``Su x Sv`` along the
direction towards the patch centre, then a nudge inward as a fallback), and curvatures are
evaluated at a parameter nudged slightly inward (Saito & Takahashi 1990, §4.5 need normals and
curvature-like quantities everywhere on the surface).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = [
    "PatchEval",
    "bernstein",
    "bernstein_derivative",
    "curvatures",
    "evaluate",
    "normals",
]

# |Su x Sv| below this fraction of the net's squared size counts as degenerate for normals:
# rounding leaves ~1e-16 there, and a true interior value this small is still O(1e-10) off.
_NORMAL_DEGENERATE = 1e-10
# Curvature divides by |Su x Sv|^2, so it is evaluated nudged inward below a larger threshold.
_CURVATURE_DEGENERATE = 1e-6
# Parameter distances tried, in order, when nudging a degenerate point towards the patch centre.
_NUDGES = (1e-5, 1e-3, 1e-2, 0.1, 0.5)


class PatchEval(NamedTuple):
    """Position and partial derivatives of a patch, each of shape ``(..., 3)``.

    Entries not requested (``derivatives`` < 1 or < 2 in :func:`evaluate`) are None.
    """

    S: np.ndarray
    Su: np.ndarray | None
    Sv: np.ndarray | None
    Suu: np.ndarray | None
    Suv: np.ndarray | None
    Svv: np.ndarray | None


def bernstein(n: int, t: np.ndarray) -> np.ndarray:
    """Bernstein basis ``B_i^n(t)``, i = 0..n, as an ``(len(t), n + 1)`` array (n >= 0)."""
    t = np.asarray(t, dtype=np.float64).reshape(-1, 1)
    s = 1.0 - t
    basis = np.ones((t.shape[0], 1))
    # de Casteljau-style raising: B_i^{k+1} = (1 - t) B_i^k + t B_{i-1}^k, stable on [0, 1].
    for k in range(n):
        nxt = np.zeros((t.shape[0], k + 2))
        nxt[:, :-1] += s * basis
        nxt[:, 1:] += t * basis
        basis = nxt
    return basis


def bernstein_derivative(n: int, t: np.ndarray, k: int) -> np.ndarray:
    """k-th derivative of the degree-n Bernstein basis, ``(len(t), n + 1)``; zero if k > n."""
    t = np.asarray(t, dtype=np.float64).reshape(-1)
    if k > n:
        return np.zeros((t.shape[0], n + 1))
    basis = bernstein(n - k, t)
    m = n - k
    for _ in range(k):
        # d/dt B_i^{m+1} = (m + 1) (B_{i-1}^m - B_i^m)
        lifted = np.zeros((t.shape[0], m + 2))
        lifted[:, 1:] += basis
        lifted[:, :-1] -= basis
        basis = (m + 1) * lifted
        m += 1
    return basis


def _contract(net: np.ndarray, bu: np.ndarray, bv: np.ndarray) -> np.ndarray:
    """``sum_ij bu[:, i] bv[:, j] net[i, j]`` for paired rows of bu, bv -> ``(N, 3)``."""
    du1, dv1, _ = net.shape
    rows = (bu @ net.reshape(du1, dv1 * 3)).reshape(-1, dv1, 3)
    return np.einsum("nj,njc->nc", bv, rows)


def evaluate(net: np.ndarray, u: np.ndarray, v: np.ndarray, derivatives: int = 2) -> PatchEval:
    """Position and partials up to order ``derivatives`` (0, 1 or 2) at flat arrays u, v."""
    du, dv = net.shape[0] - 1, net.shape[1] - 1
    bases_u = [bernstein_derivative(du, u, k) for k in range(derivatives + 1)]
    bases_v = [bernstein_derivative(dv, v, k) for k in range(derivatives + 1)]
    s = _contract(net, bases_u[0], bases_v[0])
    su = sv = suu = suv = svv = None
    if derivatives >= 1:
        su = _contract(net, bases_u[1], bases_v[0])
        sv = _contract(net, bases_u[0], bases_v[1])
    if derivatives >= 2:
        suu = _contract(net, bases_u[2], bases_v[0])
        suv = _contract(net, bases_u[1], bases_v[1])
        svv = _contract(net, bases_u[0], bases_v[2])
    return PatchEval(s, su, sv, suu, suv, svv)


def net_scale(net: np.ndarray) -> float:
    """Squared bounding-box diagonal of the net (1 for a single point): the unit of |Su x Sv|."""
    pts = net.reshape(-1, 3)
    diag2 = float(np.sum((pts.max(axis=0) - pts.min(axis=0)) ** 2))
    return diag2 if diag2 > 0.0 else 1.0


def normalised(net: np.ndarray) -> tuple[np.ndarray, float]:
    """The net moved to its box centre and divided by its largest extent, and that extent.

    Normals are invariant and curvatures scale by 1/extent, so computing them on the unit-size
    net keeps squares and cross products of huge (or tiny) coordinates from over/underflowing.
    """
    lo, hi = net.reshape(-1, 3).min(axis=0), net.reshape(-1, 3).max(axis=0)
    extent = float(np.max(hi - lo))
    extent = extent if extent > 0.0 else 1.0
    return (net - (lo + hi) / 2) / extent, extent


def _norm(a: np.ndarray) -> np.ndarray:
    return np.sqrt(np.einsum("nc,nc->n", a, a))


def _inward(u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit-step signs pointing from (u, v) towards the patch centre (0.5, 0.5)."""
    return np.where(u <= 0.5, 1.0, -1.0), np.where(v <= 0.5, 1.0, -1.0)


def _fallback_normal(net: np.ndarray) -> np.ndarray:
    """Area-weighted normal of the control net's quads, or +z if that vanishes too."""
    a, b = net[1:, 1:] - net[:-1, :-1], net[:-1, 1:] - net[1:, :-1]
    total = np.cross(a, -b).reshape(-1, 3).sum(axis=0)
    length = np.linalg.norm(total)
    return total / length if length > 0 else np.array([0.0, 0.0, 1.0])


def normals(net: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Unit normals ``Su x Sv / |Su x Sv|`` at flat u, v, with limits at degenerate points.

    Where ``|Su x Sv|`` vanishes (relative to the net's size) the normal is the direction of the
    first non-vanishing Taylor coefficient of ``Su x Sv`` along the step (hu, hv) towards the
    patch centre: order 1 is ``Su x B + A x Sv`` and order 2 ``A x B`` with ``A = hu Suu + hv Suv``,
    ``B = hu Suv + hv Svv`` (on a collapsed edge u = 0 this is ``Su x Suv``). If both vanish the
    normal at a parameter nudged inward is used, and for a net with no normal at all (all points
    collinear) the control net's mean normal or +z: every result is finite and unit.
    """
    net = normalised(net)[0]
    ev = evaluate(net, u, v, derivatives=2)
    n = np.cross(ev.Su, ev.Sv)
    length = _norm(n)
    ref = net_scale(net)
    bad = length <= _NORMAL_DEGENERATE * ref
    if np.any(bad):
        idx = np.flatnonzero(bad)
        hu, hv = _inward(u[idx], v[idx])
        su, sv = ev.Su[idx], ev.Sv[idx]
        a = hu[:, None] * ev.Suu[idx] + hv[:, None] * ev.Suv[idx]
        b = hu[:, None] * ev.Suv[idx] + hv[:, None] * ev.Svv[idx]
        limit = np.cross(su, b) + np.cross(a, sv)
        second = np.cross(a, b)
        small = _norm(limit) <= 1e-8 * ref
        limit[small] = second[small]
        still = _norm(limit) <= 1e-8 * ref
        for step in _NUDGES:
            if not np.any(still):
                break
            j = np.flatnonzero(still)
            nudged = evaluate(net, u[idx[j]] + step * hu[j], v[idx[j]] + step * hv[j], 1)
            limit[j] = np.cross(nudged.Su, nudged.Sv)
            still[j] = _norm(limit[j]) <= _NORMAL_DEGENERATE * ref
        limit[still] = _fallback_normal(net)
        n[idx] = limit
        length[idx] = _norm(limit)
    return n / length[:, None]


def curvatures(
    net: np.ndarray, u: np.ndarray, v: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Gaussian K, mean H and principal k1 >= k2 at flat u, v from the fundamental forms.

    ``E, F, G`` from Su, Sv; ``L, M, N`` from Suu, Suv, Svv and the unit normal ``Su x Sv``;
    ``K = (LN - M^2) / (EG - F^2)``, ``H = (EN - 2FM + GL) / (2 (EG - F^2))``, so H > 0 where the
    surface bends towards its normal (a sphere with outward normals has H = -1/r). At degenerate
    points (``|Su x Sv|`` below 1e-6 of the net's squared size) the forms are evaluated at the
    parameter nudged 1e-5 towards the patch centre (further if still degenerate): an O(1e-5)
    approximation of the limit. Where no nudge helps (a net without area) all four are 0.
    """
    u = np.asarray(u, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    net, extent = normalised(net)
    ref = net_scale(net)
    ue, ve = u.copy(), v.copy()
    ev = evaluate(net, ue, ve, 2)
    cross = np.cross(ev.Su, ev.Sv)
    bad = _norm(cross) <= _CURVATURE_DEGENERATE * ref
    hu, hv = _inward(u, v)
    for step in _NUDGES:
        if not np.any(bad):
            break
        j = np.flatnonzero(bad)
        ue[j], ve[j] = u[j] + step * hu[j], v[j] + step * hv[j]
        nudged = evaluate(net, ue[j], ve[j], 2)
        for full, part in zip(ev, nudged, strict=True):
            full[j] = part
        cross[j] = np.cross(nudged.Su, nudged.Sv)
        bad[j] = _norm(cross[j]) <= _CURVATURE_DEGENERATE * ref
    # |Su x Sv|^2 == EG - F^2 without the cancellation of forming it from E, F, G.
    w2 = np.einsum("nc,nc->n", cross, cross)
    w2 = np.where(bad, 1.0, w2)
    unit = cross / np.sqrt(w2)[:, None]

    def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.einsum("nc,nc->n", a, b)

    e, f, g = dot(ev.Su, ev.Su), dot(ev.Su, ev.Sv), dot(ev.Sv, ev.Sv)
    ll, mm, nn = dot(ev.Suu, unit), dot(ev.Suv, unit), dot(ev.Svv, unit)
    gauss = (ll * nn - mm * mm) / w2
    mean = (e * nn - 2.0 * f * mm + g * ll) / (2.0 * w2)
    gauss[bad] = 0.0
    mean[bad] = 0.0
    root = np.sqrt(np.maximum(mean * mean - gauss, 0.0))
    # Back to the net's own size; nets smaller than ~1e-150 would overflow here.
    gauss, mean, root = gauss / extent**2, mean / extent, root / extent
    return gauss, mean, mean + root, mean - root
