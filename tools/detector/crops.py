"""Rotated, direction-aligned vehicle crops for the second-stage ``CropNet``.

Contract
--------
``crop_affine(box_center, angle, gsd_m)`` is the 2x3 affine map from crop pixels (x, y) to
image pixels (u, v) (pixel centres at integer coordinates on both sides):

    (u, v) = (cu, cv) + k * R(angle) * (x - (CROP_W - 1) / 2, y - (CROP_H - 1) / 2),
    k = CROP_GSD_M / gsd_m   (image pixels per crop pixel), R = rotation by +angle

so the crop's +x is the box's forward axis (the vehicle points right) and +y is the vehicle's
right side in a nadir view. The C++ perception code must cut crops with exactly this map
(bilinear, border = replicate) for the trained CropNet to apply.

``extract_crop(image, center, angle, gsd_m)`` -> uint8 [CROP_H, CROP_W, 3].

``jittered_crop_target(box, gsd_m, rng, ...)`` draws the crop pose a detector would produce
around a ground-truth box (centre, angle, scale jitter, 180-degree flips) and returns the crop
pose and the CropNet targets: ``flip`` (1 when the crop's +x is the vehicle's rear), ``refine``
= (du_m, dv_m, d_angle, length_m, width_m): the true centre in the crop frame (metres, x
forward, y right), the true axis minus the crop axis in (-pi/2, pi/2], and the true size.
"""

from __future__ import annotations

import math
from typing import Tuple

import cv2
import numpy as np

from detector.geometry import angle_difference
from detector.model import CROP_GSD_M, CROP_H, CROP_W


def crop_affine(center: Tuple[float, float], angle: float, gsd_m: float,
                crop_gsd_m: float = CROP_GSD_M) -> np.ndarray:
    k = crop_gsd_m / gsd_m
    c, s = math.cos(angle), math.sin(angle)
    x0, y0 = (CROP_W - 1) / 2.0, (CROP_H - 1) / 2.0
    a = np.array([[k * c, -k * s], [k * s, k * c]])
    t = np.asarray(center, np.float64) - a @ np.array([x0, y0])
    return np.hstack([a, t[:, None]])


def extract_crop(image: np.ndarray, center, angle: float, gsd_m: float) -> np.ndarray:
    m = crop_affine(center, angle, gsd_m)
    return cv2.warpAffine(image, m, (CROP_W, CROP_H),
                          flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                          borderMode=cv2.BORDER_REPLICATE)


def refine_target(box: np.ndarray, gsd_m: float, crop_center, crop_angle: float):
    """Targets of a crop taken at (crop_center, crop_angle) for the true ``box``."""
    d = (np.asarray(box[:2], np.float64) - np.asarray(crop_center, np.float64)) * gsd_m
    c, s = math.cos(crop_angle), math.sin(crop_angle)
    du, dv = c * d[0] + s * d[1], -s * d[0] + c * d[1]
    diff = float(angle_difference(box[4], crop_angle))
    flip = abs(diff) > math.pi / 2
    axis = diff - math.copysign(math.pi, diff) if flip else diff
    return int(flip), np.array([du, dv, axis, box[2] * gsd_m, box[3] * gsd_m], np.float32)


def jittered_crop_target(box: np.ndarray, gsd_m: float, rng: np.random.Generator,
                         center_sigma_m: float = 0.25, angle_sigma: float = math.radians(6),
                         flip_prob: float = 0.5, gsd_jitter: float = 0.05):
    """Returns (crop_center, crop_angle, crop_gsd_m_used, flip, refine)."""
    cen = np.asarray(box[:2], np.float64) + rng.normal(0, center_sigma_m / gsd_m, 2)
    ang = float(box[4]) + float(rng.normal(0, angle_sigma))
    if rng.random() < flip_prob:
        ang += math.pi
    ang %= 2 * math.pi
    gsd_used = gsd_m * float(math.exp(rng.normal(0, gsd_jitter)))  # error of the GSD estimate
    flip, refine = refine_target(box, gsd_m, cen, ang)
    return cen, ang, gsd_used, flip, refine
