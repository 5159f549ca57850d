"""The numba edge kernels equal a slow, literal Python transcription of the documented rules."""

from __future__ import annotations

import math

import numpy as np
import pytest
import pyvista as pv

import sciviz_gbuf as sg
from sciviz_gbuf.filters import edge_map, id_edges
from sciviz_gbuf.filters.edges import _pair_edges

JUMP, CREASE = 1.0, 30.0


class Ref:
    """Documented rules of sciviz_gbuf.filters.edges, one pixel pair at a time."""

    def __init__(self, gb):
        self.sz = gb.sz.astype(np.float64)
        self.z = gb.depth.astype(np.float64)
        self.n = gb.normal.astype(np.float64)
        self.m = gb.mask & np.isfinite(gb.sz)
        self.h, self.w = gb.shape
        cam = gb.camera
        self.parallel = cam.parallel_projection
        self.d, self.pw = cam.distance, cam.pixel_size

    def ok(self, r, c):
        return 0 <= r < self.h and 0 <= c < self.w and bool(self.m[r, c])

    def inside(self, r, c):
        return 0 <= r < self.h and 0 <= c < self.w

    def gap(self, p, q, step):
        """Unexplained jump p -> q (q = p + steps * step), in footprints."""
        (r, c), (r2, c2), (dr, dc) = p, q, step
        n = max(abs(r2 - r), abs(c2 - c)) // max(abs(dr), abs(dc))
        if not (self.ok(r - dr, c - dc) and self.ok(r2 + dr, c2 + dc)):
            return 0.0
        s_l = (self.sz[r, c] - self.sz[r - dr, c - dc]) * n
        s_r = (self.sz[r2 + dr, c2 + dc] - self.sz[r2, c2]) * n
        j = self.sz[r2, c2] - self.sz[r, c]
        lo, hi = min(s_l, s_r), max(s_l, s_r)
        g = lo - j if j < lo else (j - hi if j > hi else 0.0)
        if g == 0.0:
            return 0.0
        k = 1.0 if self.parallel else min(self.z[r, c], self.z[r2, c2]) / self.d
        s = min(abs(s_l), abs(s_r)) * k / n  # the gentler slope, footprints per pixel
        return g * k / math.sqrt(1.0 + s * s)

    def eye(self, r, c):
        k = 1.0 if self.parallel else self.z[r, c] / self.d
        return np.array(
            [(c + 0.5 - self.w / 2) * k, (self.h / 2 - r - 0.5) * k, -self.z[r, c] / self.pw]
        )

    @staticmethod
    def turn(a, b):
        cross = np.linalg.norm(np.cross(a, b))
        dot = float(np.dot(a, b))
        return 0.0 if cross == 0 and dot == 0 else math.degrees(math.atan2(cross, dot))

    def depth_crease(self, r, c, dr, dc):
        pts = [(r + k * dr, c + k * dc) for k in range(-2, 4)]  # X-2d .. Y+2d
        if not all(self.ok(*p) for p in pts):
            return 0.0
        if self.gap(pts[1], pts[2], (dr, dc)) > JUMP or self.gap(pts[3], pts[4], (dr, dc)) > JUMP:
            return 0.0
        e = [self.eye(*p) for p in pts]
        seg = [e[k + 1] - e[k] for k in range(5)]
        ang = self.turn(seg[1], seg[3])
        if ang < self.turn(seg[0], seg[2]) or ang <= self.turn(seg[2], seg[4]):
            return 0.0
        if max(self.turn(seg[0], seg[1]), self.turn(seg[3], seg[4])) > 0.25 * ang:
            return 0.0
        dih = self.flank_dihedral(pts[1], pts[4], (dr, dc))
        if dih is not None:
            ang = min(ang, dih)
        s_l = self.sz[pts[2]] - self.sz[pts[1]]
        s_r = self.sz[pts[4]] - self.sz[pts[3]]
        return ang if s_r <= s_l else -ang

    def flank_normal(self, p, a, across):
        """Normal at p from the section tangent a and the central tangent across it."""
        (r, c), (pr, pc) = p, across
        lo, hi = (r - pr, c - pc), (r + pr, c + pc)
        if not (self.ok(*lo) and self.ok(*hi)):
            return None
        if self.gap(lo, p, across) > JUMP or self.gap(p, hi, across) > JUMP:
            return None
        return np.cross(a, self.eye(*hi) - self.eye(*lo))

    def flank_dihedral(self, xm, yp, step):
        """Angle between the depth's normals at X - d and Y + d, or None."""
        (dr, dc) = step
        a = self.eye(*xm) - self.eye(xm[0] - dr, xm[1] - dc)
        b = self.eye(yp[0] + dr, yp[1] + dc) - self.eye(*yp)
        nl = self.flank_normal(xm, a, (dc, dr))
        nr = self.flank_normal(yp, b, (dc, dr))
        if nl is None or nr is None:
            return None
        return self.turn(nl, nr)

    def normal_flanks(self, x, y, step, ang):
        """ang, or 0 if the normals beside the pair turn by more than 0.3 ang."""
        (dr, dc) = step
        limit = math.cos(math.radians(0.3 * ang))
        for p, q in (((x[0] - dr, x[1] - dc), x), (y, (y[0] + dr, y[1] + dc))):
            side = q if p in (x, y) else p
            if self.ok(*side) and self.gap(p, q, step) <= JUMP:
                if float(np.dot(self.n[p], self.n[q])) < limit:
                    return 0.0
        return ang

    def pixel(self, r, c):
        if not self.ok(r, c):
            return 0.0, 0.0
        prof, best = 0.0, 0.0
        for k, (dr, dc) in enumerate([(0, 1), (0, -1), (1, 0), (-1, 0)]):
            r2, c2 = r + dr, c + dc
            if not self.inside(r2, c2):
                continue
            if not self.ok(r2, c2):
                prof = 1.0
                continue
            g = self.gap((r, c), (r2, c2), (dr, dc))
            if self.sz[r, c] > self.sz[r2, c2]:
                prof = max(prof, min(1.0, max(0.0, (g - JUMP) / JUMP)))
            if k in (1, 3) or g > JUMP:
                continue
            geo = self.depth_crease(r, c, dr, dc)
            dot = float(np.clip(np.dot(self.n[r, c], self.n[r2, c2]), -1, 1))
            ang = math.degrees(math.acos(dot))
            if ang > abs(geo) and ang > CREASE:
                ang = self.normal_flanks((r, c), (r2, c2), (dr, dc), ang)
            if ang > abs(geo):
                s = np.dot(self.n[r2, c2] - self.n[r, c], self.eye(r2, c2) - self.eye(r, c))
                geo = ang if s >= 0 else -ang
            ink = min(1.0, max(0.0, (abs(geo) - CREASE) / (CREASE / 2)))
            if ink > abs(best):
                best = ink if geo >= 0 else -ink
        return prof, (best if prof < 1.0 else 0.0)

    def pair_jump(self, p, step, steps):
        (r, c), (dr, dc) = p, step
        q = (r + steps * dr, c + steps * dc)
        if not (self.inside(*p) and self.inside(*q)):
            return 0.0
        a, b = self.ok(*p), self.ok(*q)
        if a != b:
            return 1.0
        if not a:
            return 0.0
        return min(1.0, max(0.0, (self.gap(p, q, step) - JUMP) / JUMP))

    def edge_map_alpha(self, r, c, c1):
        if c1:
            total = 0.0
            for dr in (-1, 0, 1):
                for dc in (-1, 0, 1):
                    if dr or dc:
                        wgt = 1.0 if dr and dc else 2.0
                        total += wgt * self.pair_jump((r, c), (dr, dc), 1)
            return min(1.0, total / 4)
        iz = 1.0
        for dc in (-1, 1):
            j = 2 * max(
                self.pair_jump((r - 1, c + dc), (1, -dc), 1), self.pair_jump((r, c), (1, -dc), 1)
            )
            iz *= (1 - j / 2) ** 2
        return 1 - iz


@pytest.fixture(scope="module", params=[False, True], ids=["perspective", "parallel"])
def scene_gb(request):
    # A box on a plate in front of a sphere: occlusions, creases, smooth parts, background.
    scene = [
        pv.Box(bounds=(-0.6, 0.4, -0.5, 0.5, 0.0, 0.7)),
        pv.Plane(center=(0, 0, 0), i_size=2.2, j_size=2.2),
        pv.Sphere(center=(0.6, 0.9, 0.5), radius=0.5),
    ]
    cam = ((2.6, -2.2, 2.0), (0.0, 0.2, 0.3), (0, 0, 1))
    return sg.capture(scene, window_size=(64, 48), camera=cam, parallel_projection=request.param)


def test_pair_kernel_equals_reference(scene_gb):
    ref = Ref(scene_gb)
    profile, crease = _pair_edges(scene_gb, JUMP, CREASE)
    h, w = scene_gb.shape
    want = np.array([[ref.pixel(r, c) for c in range(w)] for r in range(h)])
    np.testing.assert_allclose(profile, want[..., 0], atol=1e-4)
    np.testing.assert_allclose(crease, want[..., 1], atol=1e-4)
    assert (profile > 0).sum() > 50 and (np.abs(crease) > 0).sum() > 20  # a non-trivial case


@pytest.mark.parametrize("operator", ["diagonal", "c1"])
def test_edge_map_alpha_equals_reference(scene_gb, operator):
    ref = Ref(scene_gb)
    em = edge_map(scene_gb, operator=operator)
    h, w = scene_gb.shape
    want = np.array(
        [[ref.edge_map_alpha(r, c, operator == "c1") for c in range(w)] for r in range(h)]
    )
    np.testing.assert_allclose(em[..., 3], want, atol=1e-4)


def test_id_edges_equal_reference(scene_gb):
    gb = scene_gb
    ids = np.where(gb.mask, gb.object_id, -1)
    h, w = gb.shape
    want = np.zeros((h, w))
    for r in range(h):
        for c in range(w):
            if ids[r, c] < 0:
                continue
            for k, (dr, dc) in enumerate([(0, 1), (0, -1), (1, 0), (-1, 0)]):
                r2, c2 = r + dr, c + dc
                if not (0 <= r2 < h and 0 <= c2 < w) or ids[r2, c2] == ids[r, c]:
                    continue
                a, b = gb.depth[r, c], gb.depth[r2, c2]
                if ids[r2, c2] < 0 or a < b or (a == b and k in (0, 2)):
                    want[r, c] = 1.0
    np.testing.assert_array_equal(id_edges(gb), want)
    assert want.sum() > 30
