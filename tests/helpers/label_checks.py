"""Independent checks of contour label placements (the acceptance rules of contour labels)."""

from __future__ import annotations

import math

import numpy as np

from sciviz_gbuf.filters import contour_polylines


def corners(lab) -> np.ndarray:
    """(4, 2) image coordinates (column, row) of a label's box."""
    a = math.radians(lab.angle)
    d = np.array([math.cos(a), -math.sin(a)])  # baseline, image coordinates (rows down)
    up = np.array([d[1], -d[0]])  # the text's up vector, image coordinates
    c = np.array([lab.x, lab.y])
    hw, hh = lab.width / 2, lab.height / 2
    return np.array(
        [c + su * hw * d + sv * hh * up for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    )


def boxes_overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """Separating-axis test of two convex quadrilaterals."""
    for poly in (a, b):
        for i in range(4):
            edge = poly[(i + 1) % 4] - poly[i]
            axis = np.array([-edge[1], edge[0]])
            pa, pb = a @ axis, b @ axis
            if pa.max() <= pb.min() or pb.max() <= pa.min():
                return False
    return True


def bilinear(z: np.ndarray, x: float, y: float) -> float:
    h, w = z.shape
    c0, r0 = min(math.floor(x), w - 2), min(math.floor(y), h - 2)
    fx, fy = x - c0, y - r0
    top = z[r0, c0] * (1 - fx) + z[r0, c0 + 1] * fx
    bot = z[r0 + 1, c0] * (1 - fx) + z[r0 + 1, c0 + 1] * fx
    return float(top * (1 - fy) + bot * fy)


def gradient_at(z: np.ndarray, x: float, y: float) -> np.ndarray:
    """(d/dcolumn, d/drow) of ``z`` at a point: central differences 1 px apart."""
    return np.array(
        [
            (bilinear(z, x + 0.5, y) - bilinear(z, x - 0.5, y)),
            (bilinear(z, x, y + 0.5) - bilinear(z, x, y - 0.5)),
        ]
    )


def problems(labels, z: np.ndarray, step: float, spacing: float) -> dict[str, list]:
    """Every violated rule, by name, for labels placed on heights ``z`` (the map's grid) at
    multiples of ``step``, ``spacing`` px apart."""
    h, w = z.shape
    out: dict[str, list] = {
        k: [] for k in ("height", "tangent", "uphill", "overlap", "frame", "unlabelled")
    }
    boxes = [corners(lab) for lab in labels]
    for lab, box in zip(labels, boxes, strict=True):
        if abs(bilinear(z, lab.x, lab.y) - lab.level) > step / 4:
            out["height"].append(lab)
        g = gradient_at(z, lab.x, lab.y)
        a = math.radians(lab.angle)
        d = np.array([math.cos(a), -math.sin(a)])
        up = np.array([d[1], -d[0]])
        tangent = np.array([-g[1], g[0]]) / np.hypot(*g)
        if abs(d @ tangent) < math.cos(math.radians(15)):
            out["tangent"].append(lab)
        if not g @ up > 0:
            out["uphill"].append(lab)
        if (
            box[:, 0].min() < 0
            or box[:, 1].min() < 0
            or box[:, 0].max() > w - 1
            or box[:, 1].max() > h - 1
        ):
            out["frame"].append(lab)
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            if np.abs(boxes[i].mean(0) - boxes[j].mean(0)).max() < 2 * max(
                labels[i].width, labels[j].width
            ) and boxes_overlap(boxes[i], boxes[j]):
                out["overlap"].append((labels[i], labels[j]))
    lo, hi = np.nanmin(z), np.nanmax(z)
    levels = np.arange(math.ceil(lo / step), math.floor(hi / step) + 1) * step
    for line in contour_polylines(z, levels=levels) if levels.size else []:
        length = float(np.hypot(*np.diff(line.points, axis=0).T).sum())
        if length <= 3 * spacing:
            continue
        mine = [lab for lab in labels if lab.level == line.level]
        near = [
            lab
            for lab in mine
            if np.hypot(line.points[:, 0] - lab.x, line.points[:, 1] - lab.y).min() < 1.5
        ]
        if not near:
            out["unlabelled"].append((line.level, round(length)))
    return out
