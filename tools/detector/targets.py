"""CenterNet training targets for the ``Detector`` from a loaded, augmented ``Sample``.

Contract
--------
``encode(sample, stride=4, max_objects=128)`` -> dict of numpy arrays for one image of size
H x W (multiples of ``stride``); feature grid h = H/stride, w = W/stride. A pixel coordinate u
maps to the feature coordinate f = (u - (stride - 1) / 2) / stride (cell centres), the centre
cell is round(f) and the offset target f - round(f) is in [-0.5, 0.5].

* ``heatmap`` [1, h, w]: max over objects of an oriented Gaussian at the centre, sigma along the
  box axes = max(0.5, 0.15 * length / stride), max(0.5, 0.15 * width / stride) (axis-aligned
  boxes: along u and v); peaks set to exactly 1.
* ``hm_weight`` [1, h, w]: 0 inside ``ignore`` objects' boxes (no negative loss there), else 1.
* per object (padded to ``max_objects``; ``mask`` says which rows are real):
  ``ind`` (flat cell index), ``offset`` (2), ``log_size`` (2, rotated boxes), ``direction``
  (cos, sin), ``dir_known`` (0/1), ``rot`` (1 = rotated box known, 0 = axis-aligned only),
  ``log_aa`` (2: log of the enclosing axis-aligned box w, h), ``type`` (-1 unknown),
  ``gamma`` (n_s, NaN unknown).
Ignored objects get no centre and no regression rows.
"""

from __future__ import annotations

import math
from typing import Dict

import cv2
import numpy as np

from detector.datasets import Sample
from detector.geometry import box_corners, enclosing_aabb

SIGMA_FACTOR = 0.15


def encode(s: Sample, stride: int = 4, max_objects: int = 128, n_s: int = 3) -> Dict[str, np.ndarray]:
    H, W = s.image.shape[:2]
    if H % stride or W % stride:
        raise ValueError(f"image {W}x{H} is not a multiple of the stride {stride}")
    h, w = H // stride, W // stride
    hm = np.zeros((h, w), np.float32)
    weight = np.ones((h, w), np.float32)
    out = {
        "ind": np.zeros(max_objects, np.int64), "mask": np.zeros(max_objects, np.float32),
        "offset": np.zeros((max_objects, 2), np.float32),
        "log_size": np.zeros((max_objects, 2), np.float32),
        "direction": np.zeros((max_objects, 2), np.float32),
        "dir_known": np.zeros(max_objects, np.float32), "rot": np.zeros(max_objects, np.float32),
        "log_aa": np.zeros((max_objects, 2), np.float32),
        "type": np.full(max_objects, -1, np.int64),
        "gamma": np.full((max_objects, n_s), np.nan, np.float32),
    }
    boxes = s.boxes
    c0 = (stride - 1) / 2.0
    # ignore regions first (positives are written afterwards and win)
    for i in np.nonzero(s.ignore)[0]:
        b = boxes[i].copy()
        poly = box_corners(b)[0] if not s.aa_only[i] else box_corners(
            np.array([b[0], b[1], b[2], b[3], 0.0]))[0]
        pts = np.round((poly - c0) / stride).astype(np.int32)
        cv2.fillPoly(weight, [pts], 0.0)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    k = 0
    for i in range(len(s)):
        if s.ignore[i]:
            continue
        b = boxes[i]
        fx, fy = (b[0] - c0) / stride, (b[1] - c0) / stride
        ix, iy = int(round(fx)), int(round(fy))
        if not (0 <= ix < w and 0 <= iy < h) or b[2] <= 0 or b[3] <= 0:
            continue
        ang = 0.0 if s.aa_only[i] else float(b[4])
        sl = max(0.5, SIGMA_FACTOR * b[2] / stride)
        sw = max(0.5, SIGMA_FACTOR * b[3] / stride)
        ca, sa = math.cos(ang), math.sin(ang)
        r = int(math.ceil(3 * max(sl, sw)))
        x0, x1, y0, y1 = max(0, ix - r), min(w, ix + r + 1), max(0, iy - r), min(h, iy + r + 1)
        dx, dy = xx[y0:y1, x0:x1] - ix, yy[y0:y1, x0:x1] - iy
        along, across = dx * ca + dy * sa, -dx * sa + dy * ca
        g = np.exp(-0.5 * ((along / sl) ** 2 + (across / sw) ** 2))
        hm[y0:y1, x0:x1] = np.maximum(hm[y0:y1, x0:x1], g)
        hm[iy, ix] = 1.0
        weight[iy, ix] = 1.0
        if k >= max_objects:
            continue
        out["ind"][k] = iy * w + ix
        out["mask"][k] = 1.0
        out["offset"][k] = (fx - ix, fy - iy)
        if s.aa_only[i]:
            out["log_aa"][k] = (math.log(b[2]), math.log(b[3]))
        else:
            out["rot"][k] = 1.0
            out["log_size"][k] = (math.log(b[2]), math.log(b[3]))
            out["direction"][k] = (ca, sa)
            out["dir_known"][k] = float(s.direction_known[i])
            aa = enclosing_aabb(b)[0]
            out["log_aa"][k] = (math.log(max(aa[2], 1e-3)), math.log(max(aa[3], 1e-3)))
        out["type"][k] = s.types[i]
        out["gamma"][k] = s.gammas[i][:n_s]
        k += 1
    out["heatmap"] = hm[None]
    out["hm_weight"] = np.maximum(weight, (hm >= 1.0).astype(np.float32))[None]
    return out


def collate(items):
    """List of ``encode`` dicts -> dict of stacked numpy arrays."""
    return {k: np.stack([it[k] for it in items]) for k in items[0]}
