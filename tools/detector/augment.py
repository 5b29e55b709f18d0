"""Geometry-consistent augmentations of a loaded ``datasets.Sample``.

Contract
--------
Every function takes a *loaded* Sample (``image`` set, pixel boxes) and returns a new one; the
input is not modified. Geometry follows docs/conventions.md (pixel centres at integer
coordinates, angle from +u towards +v):

================= ============================== ===============================================
transform         point (u, v) ->                angle a ->
================= ============================== ===============================================
hflip             (W-1-u, v)                     pi - a      (mod 2 pi)
vflip             (u, H-1-v)                     -a          (mod 2 pi)
rot90(k=1)        (H-1-v, u)  (90 deg clockwise  a + pi/2    (mod 2 pi)
                  on screen, cv2.ROTATE_90_CLOCKWISE)
scale(s)          ((u+.5)s-.5, (v+.5)s-.5)       a;  lengths * s, gsd / s
crop(x0, y0, w, h) (u-x0, v-y0), zero padding     a
================= ============================== ===============================================

Axis-aligned-only boxes stay axis-aligned: their angle stays 0 and rot90 swaps w and h.
Keypoints (u, v) are transformed like points. Photometric jitter (brightness/contrast,
white-balance gains, saturation, gamma, Gaussian blur, Gaussian noise), ``cast_shadow`` (a
soft-edged shadow of a building or a tree crown laid across the tile) and ``compress`` (JPEG
re-encoding, as video streams and web frames come) change pixels only.
``random_augment`` draws a combination with a numpy Generator (deterministic for a seed).
"""

from __future__ import annotations

import math
from typing import Optional, Tuple

import cv2
import numpy as np

from detector.datasets import Sample

TWO_PI = 2 * math.pi


def _pts(s: Sample, fn):
    """Applies fn(u, v) -> (u', v') to box centres and keypoints of a copy of s."""
    out = s.copy()
    u, v = fn(out.boxes[:, 0].copy(), out.boxes[:, 1].copy())
    out.boxes[:, 0], out.boxes[:, 1] = u, v
    if out.keypoints is not None and len(out.keypoints):
        ku, kv = fn(out.keypoints[..., 0].astype(np.float64), out.keypoints[..., 1].astype(np.float64))  # copies
        out.keypoints[..., 0], out.keypoints[..., 1] = ku, kv
    return out


def _set_angle(out: Sample, fn):
    rot = ~out.aa_only
    out.boxes[rot, 4] = np.mod(fn(out.boxes[rot, 4]), TWO_PI)


def hflip(s: Sample) -> Sample:
    w = s.image.shape[1]
    out = _pts(s, lambda u, v: (w - 1 - u, v))
    out.image = np.ascontiguousarray(s.image[:, ::-1])
    _set_angle(out, lambda a: math.pi - a)
    return out


def vflip(s: Sample) -> Sample:
    h = s.image.shape[0]
    out = _pts(s, lambda u, v: (u, h - 1 - v))
    out.image = np.ascontiguousarray(s.image[::-1])
    _set_angle(out, lambda a: -a)
    return out


def rot90(s: Sample, k: int = 1) -> Sample:
    """Rotates by k * 90 degrees clockwise on screen."""
    k %= 4
    out = s
    for _ in range(k):
        h = out.image.shape[0]
        nxt = _pts(out, lambda u, v, h=h: (h - 1 - v, u))
        nxt.image = np.ascontiguousarray(np.rot90(out.image, -1))
        _set_angle(nxt, lambda a: a + math.pi / 2)
        aa = nxt.aa_only
        nxt.boxes[aa, 2], nxt.boxes[aa, 3] = out.boxes[aa, 3].copy(), out.boxes[aa, 2].copy()
        out = nxt
    return out if k else s.copy()


def scale(s: Sample, f: float, interpolation: Optional[int] = None) -> Sample:
    h, w = s.image.shape[:2]
    nw, nh = max(1, int(round(w * f))), max(1, int(round(h * f)))
    fx, fy = nw / w, nh / h  # exact factors of the integer output size
    out = _pts(s, lambda u, v: ((u + 0.5) * fx - 0.5, (v + 0.5) * fy - 0.5))
    if interpolation is None:
        interpolation = cv2.INTER_AREA if f < 1 else cv2.INTER_LINEAR
    out.image = cv2.resize(s.image, (nw, nh), interpolation=interpolation)
    fm = math.sqrt(fx * fy)
    rot = ~out.aa_only
    out.boxes[rot, 2:4] *= fm
    out.boxes[~rot, 2] *= fx
    out.boxes[~rot, 3] *= fy
    out.gsd_m = out.gsd_m / fm
    return out


def crop(s: Sample, x0: int, y0: int, w: int, h: int, fill: int = 0,
         min_visible: float = 0.5) -> Sample:
    """Window [x0, x0+w) x [y0, y0+h) (may extend past the image: padded with ``fill``).
    Objects whose centre leaves the window are dropped; objects with less than
    ``min_visible`` of their enclosing box inside become ``ignore``."""
    H, W = s.image.shape[:2]
    img = np.full((h, w, 3), fill, np.uint8)
    sx0, sy0 = max(0, x0), max(0, y0)
    sx1, sy1 = min(W, x0 + w), min(H, y0 + h)
    if sx1 > sx0 and sy1 > sy0:
        img[sy0 - y0:sy1 - y0, sx0 - x0:sx1 - x0] = s.image[sy0:sy1, sx0:sx1]
    out = _pts(s, lambda u, v: (u - x0, v - y0))
    out.image = img
    from detector.geometry import enclosing_aabb

    b = out.boxes
    inside = (b[:, 0] >= -0.5) & (b[:, 0] < w - 0.5) & (b[:, 1] >= -0.5) & (b[:, 1] < h - 0.5)
    out = out.subset(inside)
    if len(out):
        aa = enclosing_aabb(out.boxes)
        aa[out.aa_only, 2:4] = out.boxes[out.aa_only, 2:4]
        lo_u, hi_u = aa[:, 0] - aa[:, 2] / 2, aa[:, 0] + aa[:, 2] / 2
        lo_v, hi_v = aa[:, 1] - aa[:, 3] / 2, aa[:, 1] + aa[:, 3] / 2
        iu = np.clip(np.minimum(hi_u, w - 0.5) - np.maximum(lo_u, -0.5), 0, None)
        iv = np.clip(np.minimum(hi_v, h - 0.5) - np.maximum(lo_v, -0.5), 0, None)
        vis = iu * iv / np.maximum(aa[:, 2] * aa[:, 3], 1e-9)
        out.ignore = out.ignore | (vis < min_visible)
    return out


def photometric(s: Sample, rng: np.random.Generator, strength: float = 1.0) -> Sample:
    """Brightness/contrast, white-balance gains, saturation, gamma, blur, noise."""
    img = s.image.astype(np.float32) / 255.0
    gains = np.exp(rng.normal(0, 0.08 * strength, 3)).astype(np.float32)  # white balance
    img = img * gains
    gray = img.mean(2, keepdims=True)
    sat = float(np.exp(rng.normal(0, 0.2 * strength)))
    img = gray + (img - gray) * sat
    contrast = float(np.exp(rng.normal(0, 0.15 * strength)))
    bright = float(rng.normal(0, 0.06 * strength))
    img = (img - 0.5) * contrast + 0.5 + bright
    img = np.clip(img, 0, 1)
    gamma = float(np.exp(rng.normal(0, 0.15 * strength)))
    img = img ** gamma
    if rng.random() < 0.3 * strength:
        sigma = float(rng.uniform(0.3, 1.2))
        img = cv2.GaussianBlur(img, (0, 0), sigma)
    if rng.random() < 0.5 * strength:
        img = img + rng.normal(0, rng.uniform(0.0, 0.03), img.shape).astype(np.float32)
    out = s.copy()
    out.image = np.clip(img * 255.0 + 0.5, 0, 255).astype(np.uint8)
    return out


def cast_shadow(s: Sample, rng: np.random.Generator) -> Sample:
    """Darkens part of the tile as a cast shadow does: the light left is the sky's, so the
    shadow is dimmer (to 0.25-0.65 of the light) and bluer. The shape is either a building's
    (a half-plane at a random angle with a straight, slightly soft edge) or a tree crown's
    (blurred blobs). Real vehicles in building and tree shadow are a known miss; the
    simulator's shadows alone do not cover them."""
    h, w = s.image.shape[:2]
    mask = np.zeros((h, w), np.float32)
    if rng.random() < 0.5:
        a = rng.uniform(0, 2 * math.pi)
        c = np.array([rng.uniform(0, w), rng.uniform(0, h)])
        yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
        mask = ((xx - c[0]) * math.cos(a) + (yy - c[1]) * math.sin(a) > 0).astype(np.float32)
        edge = float(rng.uniform(0.5, 3.0))
    else:
        for _ in range(int(rng.integers(2, 7))):
            r = float(rng.uniform(0.08, 0.3)) * min(h, w)
            cv2.circle(mask, (int(rng.uniform(0, w)), int(rng.uniform(0, h))), int(r), 1.0, -1)
        edge = float(rng.uniform(2.0, 6.0))
    mask = cv2.GaussianBlur(mask, (0, 0), edge)[..., None]
    light = float(rng.uniform(0.25, 0.65))
    tint = np.array([1.0 + rng.uniform(0.0, 0.25), 1.0, 1.0 - rng.uniform(0.0, 0.15)],
                    np.float32)  # channel order B, G, R: bluer
    factor = 1.0 - mask * (1.0 - np.clip(light * tint, 0.0, 1.0))
    out = s.copy()
    out.image = np.clip(s.image.astype(np.float32) * factor + 0.5, 0, 255).astype(np.uint8)
    return out


def compress(s: Sample, rng: np.random.Generator) -> Sample:
    """Re-encodes the tile as JPEG at quality 25-85 (block and ringing artefacts)."""
    quality = int(rng.integers(25, 86))
    ok, buf = cv2.imencode(".jpg", s.image, [cv2.IMWRITE_JPEG_QUALITY, quality])
    if not ok:
        raise RuntimeError("augment.compress: cv2.imencode failed")
    out = s.copy()
    out.image = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    return out


def random_geometric(s: Sample, rng: np.random.Generator) -> Sample:
    """Random flip / 90-degree rotation (the dihedral group: 8 outcomes)."""
    if rng.random() < 0.5:
        s = hflip(s)
    k = int(rng.integers(0, 4))
    return rot90(s, k) if k else s


def random_crop(s: Sample, size: Tuple[int, int], rng: np.random.Generator,
                focus_objects: float = 0.7, weights: Optional[np.ndarray] = None) -> Sample:
    """A random (w, h) window; with probability ``focus_objects`` centred near an object, drawn
    uniformly or, given ``weights`` [N] (> 0), with probability proportional to its weight."""
    w, h = size
    H, W = s.image.shape[:2]
    if len(s) and rng.random() < focus_objects:
        if weights is None:
            i = int(rng.integers(0, len(s)))
        else:
            i = int(rng.choice(len(s), p=weights / weights.sum()))
        return crop_near(s, (float(s.boxes[i, 0]), float(s.boxes[i, 1])), size, rng)
    x0 = int(rng.integers(min(0, W - w), max(0, W - w) + 1))
    y0 = int(rng.integers(min(0, H - h), max(0, H - h) + 1))
    return crop(s, x0, y0, w, h)


def crop_near(s: Sample, point: Tuple[float, float], size: Tuple[int, int],
              rng: np.random.Generator) -> Sample:
    """A (w, h) window that holds ``point`` (pixels), placed at random: the point anywhere in
    the middle 80 % of the window, the window kept inside the image where it fits."""
    w, h = size
    H, W = s.image.shape[:2]
    cx = point[0] + rng.uniform(-0.4, 0.4) * w
    cy = point[1] + rng.uniform(-0.4, 0.4) * h
    x0, y0 = int(round(cx - w / 2)), int(round(cy - h / 2))
    x0 = int(np.clip(x0, min(0, W - w), max(0, W - w)))
    y0 = int(np.clip(y0, min(0, H - h), max(0, H - h)))
    return crop(s, x0, y0, w, h)
