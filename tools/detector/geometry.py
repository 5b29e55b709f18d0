"""Rotated-box geometry shared by the detector's data, training and evaluation code.

Contract
--------
* Image coordinates follow docs/conventions.md: u to the right, v down, origin at the
  **centre** of the top-left pixel.
* A rotated box is ``(cx, cy, length, width, angle)``: centre in pixels, ``length`` along the
  driving direction, ``width`` across it, ``angle`` of the forward axis in [0, 2*pi) measured
  from +u towards +v (clockwise on screen). The angle is never folded to 180 degrees.
* Every function takes and returns numpy arrays (float64 unless stated) and has no side
  effects. Boxes are arrays of shape [N, 5] (or [5]).

Functions: ``wrap_angle`` / ``angle_difference`` / ``abs_angle_difference`` /
``axis_angle_difference`` (the same definitions as the C++ ``angleDifference`` family),
``box_corners``, ``enclosing_aabb``, ``polygon_area``, ``clip_convex``, ``rotated_iou``
(exact, by Sutherland-Hodgman clipping of two convex quadrilaterals; shapely is not
available) and ``rotated_iou_matrix``.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

TWO_PI = 2.0 * math.pi


def wrap_angle(a):
    """Angle(s) wrapped to [0, 2*pi)."""
    w = np.mod(np.asarray(a, dtype=np.float64), TWO_PI)
    # np.mod can return 2*pi for tiny negative inputs because of rounding.
    return np.where(w >= TWO_PI, 0.0, w)


def angle_difference(a, b):
    """Signed a - b in (-pi, pi]."""
    d = np.mod(np.asarray(a, np.float64) - np.asarray(b, np.float64) + math.pi, TWO_PI) - math.pi
    return np.where(d <= -math.pi, d + TWO_PI, d)


def abs_angle_difference(a, b):
    """|a - b| in [0, pi] (the 'up to 180 degrees' error the reports use)."""
    return np.abs(angle_difference(a, b))


def axis_angle_difference(a, b):
    """Difference of the box axes, ignoring front/back, in [0, pi/2]."""
    d = np.mod(abs_angle_difference(a, b), math.pi)
    return np.minimum(d, math.pi - d)


def box_corners(boxes) -> np.ndarray:
    """Corners [N, 4, 2] (u, v) of boxes [N, 5], in order front-left, front-right, rear-right,
    rear-left as seen in the vehicle frame projected onto the image (front = +length axis)."""
    b = np.asarray(boxes, np.float64).reshape(-1, 5)
    c, s = np.cos(b[:, 4]), np.sin(b[:, 4])
    fx, fy = c * b[:, 2] / 2, s * b[:, 2] / 2  # half length along the forward axis
    # "left" of the forward axis on screen: rotate forward by -90 degrees (towards -v side)
    lx, ly = s * b[:, 3] / 2, -c * b[:, 3] / 2
    cx, cy = b[:, 0], b[:, 1]
    pts = np.stack([
        np.stack([cx + fx + lx, cy + fy + ly], -1),
        np.stack([cx + fx - lx, cy + fy - ly], -1),
        np.stack([cx - fx - lx, cy - fy - ly], -1),
        np.stack([cx - fx + lx, cy - fy + ly], -1),
    ], 1)
    return pts


def enclosing_aabb(boxes) -> np.ndarray:
    """Axis-aligned box (cx, cy, w, h) [N, 4] enclosing each rotated box."""
    b = np.asarray(boxes, np.float64).reshape(-1, 5)
    c, s = np.abs(np.cos(b[:, 4])), np.abs(np.sin(b[:, 4]))
    w = b[:, 2] * c + b[:, 3] * s
    h = b[:, 2] * s + b[:, 3] * c
    return np.stack([b[:, 0], b[:, 1], w, h], -1)


def polygon_area(poly: np.ndarray) -> float:
    """Area of a simple polygon [K, 2] (shoelace; absolute value)."""
    if len(poly) < 3:
        return 0.0
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def _signed_area(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def clip_convex(subject: np.ndarray, clip: np.ndarray) -> np.ndarray:
    """Sutherland-Hodgman: the part of polygon ``subject`` [K, 2] inside the convex polygon
    ``clip`` [M, 2] (any winding). Returns [L, 2] (L may be 0)."""
    clip = np.asarray(clip, np.float64)
    if _signed_area(clip) < 0:
        clip = clip[::-1]
    out = [tuple(p) for p in np.asarray(subject, np.float64)]
    m = len(clip)
    for i in range(m):
        if not out:
            break
        ax, ay = clip[i]
        bx, by = clip[(i + 1) % m]
        ex, ey = bx - ax, by - ay

        def side(p):  # > 0: inside (left of the edge for a counter-clockwise clip polygon)
            return ex * (p[1] - ay) - ey * (p[0] - ax)

        inp = out
        out = []
        prev = inp[-1]
        sp = side(prev)
        for cur in inp:
            sc = side(cur)
            if sc >= 0:
                if sp < 0:
                    t = sp / (sp - sc)
                    out.append((prev[0] + t * (cur[0] - prev[0]), prev[1] + t * (cur[1] - prev[1])))
                out.append(cur)
            elif sp >= 0:
                t = sp / (sp - sc)
                out.append((prev[0] + t * (cur[0] - prev[0]), prev[1] + t * (cur[1] - prev[1])))
            prev, sp = cur, sc
    return np.asarray(out, np.float64).reshape(-1, 2)


def rotated_iou(a: Sequence[float], b: Sequence[float]) -> float:
    """Exact IoU of two rotated boxes (5-vectors)."""
    pa, pb = box_corners(a)[0], box_corners(b)[0]
    area_a = float(a[2]) * float(a[3])
    area_b = float(b[2]) * float(b[3])
    if area_a <= 0 or area_b <= 0:
        return 0.0
    inter = polygon_area(clip_convex(pa, pb))
    union = area_a + area_b - inter
    return inter / union if union > 0 else 0.0


def rotated_iou_matrix(a, b) -> np.ndarray:
    """IoU [Na, Nb] between two sets of rotated boxes; pairs whose circumscribed circles do not
    overlap are 0 without clipping."""
    a = np.asarray(a, np.float64).reshape(-1, 5)
    b = np.asarray(b, np.float64).reshape(-1, 5)
    out = np.zeros((len(a), len(b)))
    if len(a) == 0 or len(b) == 0:
        return out
    ra = 0.5 * np.hypot(a[:, 2], a[:, 3])
    rb = 0.5 * np.hypot(b[:, 2], b[:, 3])
    d = np.hypot(a[:, None, 0] - b[None, :, 0], a[:, None, 1] - b[None, :, 1])
    cand = np.argwhere(d < ra[:, None] + rb[None, :])
    for i, j in cand:
        out[i, j] = rotated_iou(a[i], b[j])
    return out
