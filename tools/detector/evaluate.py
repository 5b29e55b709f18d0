"""Decoding and evaluation of the detector (Python reference; the C++ decoder comes later).

Contract
--------
* ``decode(outputs, stride=4, threshold=0.3, top_k=200)``: outputs of one image (numpy,
  [C, h, w] each, heatmap already a probability) -> detections [M, 6] = (cx, cy, length,
  width, angle, score) in pixels of the network input. Peaks: 3x3 local maxima of the
  heatmap above ``threshold`` (the max-pool NMS of CenterNet).
* ``match(pred_boxes, scores, gt_boxes, gt_ignore, iou_threshold=0.5)``: greedy by score, each
  prediction takes the free reference with the highest rotated IoU; a pair counts when
  IoU >= threshold (seed 000 sec. 5.1: "above 50 %"; >= vs > makes no difference in practice).
  Predictions matched to ``ignore`` references are neither TP nor FP.
* ``metrics(records)``: precision, recall, F1, median |position error| (px and, with a GSD,
  metres) and its MAD x 1.4826, median |orientation error| (deg, over 360 deg, only where the
  direction is known) and its MAD, share of errors > 90 deg (flips), type OA-1 / OA-2 where
  type probabilities are given.
* ``evaluate_axis_aligned``: the same P/R/F1 with the axis-aligned IoU of the enclosing box of
  each rotated prediction (for the real images' YOLO labels).
* ``Predictor``: runs a ``Detector`` (+ optional ``CropNet``) on a full frame: resize to the
  working scale, pad to a multiple of 32, decode, map back to frame pixels, then (optional)
  crops at the detections for type, shape, flip and refinement.
"""

from __future__ import annotations

import math
from typing import Dict, List, Optional, Sequence

import numpy as np

from detector.geometry import (abs_angle_difference, enclosing_aabb, rotated_iou_matrix,
                               wrap_angle)


def decode(out: Dict[str, np.ndarray], stride: int = 4, threshold: float = 0.3,
           top_k: int = 200) -> np.ndarray:
    hm = out["heatmap"][0]
    h, w = hm.shape
    pad = np.pad(hm, 1, constant_values=-1)
    neigh = np.max(np.stack([pad[dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3)]), 0)
    peaks = np.argwhere((hm >= neigh) & (hm >= threshold))
    if len(peaks) == 0:
        return np.zeros((0, 6))
    scores = hm[peaks[:, 0], peaks[:, 1]]
    order = np.argsort(-scores)[:top_k]
    peaks, scores = peaks[order], scores[order]
    iy, ix = peaks[:, 0], peaks[:, 1]
    off = out["offset"][:, iy, ix]
    size = np.exp(out["size"][:, iy, ix])
    d = out["direction"][:, iy, ix]
    c0 = (stride - 1) / 2.0
    cx = (ix + off[0]) * stride + c0
    cy = (iy + off[1]) * stride + c0
    ang = wrap_angle(np.arctan2(d[1], d[0]))
    return np.stack([cx, cy, size[0], size[1], ang, scores], -1)


def match(pred: np.ndarray, scores: np.ndarray, gt: np.ndarray, gt_ignore: np.ndarray,
          iou_threshold: float = 0.5, iou: Optional[np.ndarray] = None):
    """Returns (pairs [(p, g)], fp_indices, fn_indices) with ignore handling."""
    if iou is None:
        iou = rotated_iou_matrix(pred[:, :5], gt[:, :5]) if len(pred) and len(gt) else \
            np.zeros((len(pred), len(gt)))
    taken = np.zeros(len(gt), bool)
    pairs, fps = [], []
    for p in np.argsort(-np.asarray(scores)):
        cand = np.where(taken, -1.0, iou[p]) if len(gt) else np.zeros(0)
        g = int(np.argmax(cand)) if len(gt) else -1
        if g >= 0 and cand[g] >= iou_threshold:
            taken[g] = True
            if not gt_ignore[g]:
                pairs.append((int(p), g))
        else:
            # a prediction overlapping an ignored reference is not a false positive
            if len(gt) and gt_ignore.any() and np.max(np.where(gt_ignore, iou[p], 0)) >= iou_threshold:
                continue
            fps.append(int(p))
    fns = [g for g in range(len(gt)) if not taken[g] and not gt_ignore[g]]
    return pairs, fps, fns


def _mad(x):
    x = np.asarray(x, float)
    if len(x) == 0:
        return math.nan
    med = np.median(np.abs(x))
    return 1.4826 * float(np.median(np.abs(np.abs(x) - med)))


class Accumulator:
    """Collects per-image matches; ``result()`` gives the metrics dictionary."""

    def __init__(self):
        self.tp = self.fp = self.fn = 0
        self.pos_px: List[float] = []
        self.pos_m: List[float] = []
        self.ang_deg: List[float] = []
        self.type_top1: List[bool] = []
        self.type_top2: List[bool] = []

    def add(self, pred: np.ndarray, gt_boxes: np.ndarray, gt_ignore: np.ndarray,
            gt_dir_known: Optional[np.ndarray] = None, gt_gsd: Optional[np.ndarray] = None,
            gt_types: Optional[np.ndarray] = None, type_probs: Optional[np.ndarray] = None,
            iou_threshold: float = 0.5, axis_aligned: bool = False):
        if axis_aligned:
            iou = aa_iou_matrix(enclosing_aabb(pred[:, :5]) if len(pred) else np.zeros((0, 4)),
                                gt_boxes[:, :4])
        else:
            iou = None
        pairs, fps, fns = match(pred, pred[:, 5] if len(pred) else np.zeros(0), gt_boxes,
                                gt_ignore, iou_threshold, iou)
        self.tp += len(pairs)
        self.fp += len(fps)
        self.fn += len(fns)
        for p, g in pairs:
            d = float(np.hypot(*(pred[p, :2] - gt_boxes[g, :2])))
            self.pos_px.append(d)
            if gt_gsd is not None and math.isfinite(gt_gsd[g]):
                self.pos_m.append(d * gt_gsd[g])
            if not axis_aligned and (gt_dir_known is None or gt_dir_known[g]):
                self.ang_deg.append(math.degrees(float(abs_angle_difference(pred[p, 4], gt_boxes[g, 4]))))
            if type_probs is not None and gt_types is not None and gt_types[g] >= 0:
                order = np.argsort(-type_probs[p])
                self.type_top1.append(order[0] == gt_types[g])
                self.type_top2.append(gt_types[g] in order[:2])

    def result(self) -> Dict[str, float]:
        p = self.tp / max(1, self.tp + self.fp)
        r = self.tp / max(1, self.tp + self.fn)
        f1 = 2 * p * r / max(1e-12, p + r)
        ang = np.asarray(self.ang_deg)
        return {
            "tp": self.tp, "fp": self.fp, "fn": self.fn, "precision": p, "recall": r, "f1": f1,
            "position_median_px": float(np.median(self.pos_px)) if self.pos_px else math.nan,
            "position_median_m": float(np.median(self.pos_m)) if self.pos_m else math.nan,
            "position_mad_m": _mad(self.pos_m),
            "orientation_median_deg": float(np.median(ang)) if len(ang) else math.nan,
            "orientation_mad_deg": _mad(ang),
            "orientation_flip_share": float(np.mean(ang > 90)) if len(ang) else math.nan,
            "type_oa1": float(np.mean(self.type_top1)) if self.type_top1 else math.nan,
            "type_oa2": float(np.mean(self.type_top2)) if self.type_top2 else math.nan,
            "type_count": len(self.type_top1),
        }


def aa_iou_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """IoU of axis-aligned boxes (cx, cy, w, h): [Na, Nb]."""
    a = np.asarray(a, float).reshape(-1, 4)
    b = np.asarray(b, float).reshape(-1, 4)
    ax0, ax1 = a[:, 0] - a[:, 2] / 2, a[:, 0] + a[:, 2] / 2
    ay0, ay1 = a[:, 1] - a[:, 3] / 2, a[:, 1] + a[:, 3] / 2
    bx0, bx1 = b[:, 0] - b[:, 2] / 2, b[:, 0] + b[:, 2] / 2
    by0, by1 = b[:, 1] - b[:, 3] / 2, b[:, 1] + b[:, 3] / 2
    iw = np.clip(np.minimum(ax1[:, None], bx1[None]) - np.maximum(ax0[:, None], bx0[None]), 0, None)
    ih = np.clip(np.minimum(ay1[:, None], by1[None]) - np.maximum(ay0[:, None], by0[None]), 0, None)
    inter = iw * ih
    union = (a[:, 2] * a[:, 3])[:, None] + (b[:, 2] * b[:, 3])[None] - inter
    return np.where(union > 0, inter / np.maximum(union, 1e-12), 0.0)


class Predictor:
    """Full-frame inference with torch models (or any callable returning the same dict).

    ``detector(x)`` takes a normalised [1, 3, H, W] tensor and returns the output dict (heatmap
    logits unless ``heatmap_is_prob``). ``scale`` = working width / frame width."""

    def __init__(self, detector, crop_net=None, scale: float = 0.5, threshold: float = 0.3,
                 heatmap_is_prob: bool = False, device: str = "cpu", multiple: int = 32,
                 pad_to: Optional[Sequence[int]] = None):
        self.detector, self.crop_net = detector, crop_net
        self.pad_to = pad_to  # fixed (H, W) network input (ONNX models), else a multiple of 32
        self.scale, self.threshold = scale, threshold
        self.heatmap_is_prob = heatmap_is_prob
        self.device, self.multiple = device, multiple

    def working_image(self, image: np.ndarray, scale: Optional[float] = None):
        import cv2

        s = self.scale if scale is None else scale
        h, w = image.shape[:2]
        nw, nh = max(1, int(round(w * s))), max(1, int(round(h * s)))
        small = cv2.resize(image, (nw, nh), interpolation=cv2.INTER_AREA if s < 1 else cv2.INTER_LINEAR)
        fx, fy = nw / w, nh / h
        m = self.multiple
        pw, ph = -(-nw // m) * m, -(-nh // m) * m
        if self.pad_to is not None:
            ph, pw = self.pad_to
            if nw > pw or nh > ph:  # crop what does not fit (fixed-size engine input)
                small = small[:ph, :pw]
                nh, nw = small.shape[:2]
        canvas = np.full((ph, pw, 3), 128, np.uint8)  # mean grey = network input 0, as the C++ side pads
        canvas[:nh, :nw] = small
        return canvas, fx, fy

    def __call__(self, image: np.ndarray, gsd_m: Optional[np.ndarray] = None,
                 scale: Optional[float] = None) -> Dict[str, np.ndarray]:
        import torch

        from detector.model import normalize

        canvas, fx, fy = self.working_image(image, scale)
        x = normalize(torch.from_numpy(canvas).permute(2, 0, 1)[None].to(self.device))
        with torch.no_grad():
            out = self.detector(x)
        out = {k: v[0].float().cpu().numpy() for k, v in out.items()}
        if not self.heatmap_is_prob:
            out["heatmap"] = 1.0 / (1.0 + np.exp(-out["heatmap"]))
        det = decode(out, threshold=self.threshold)
        # back to frame pixels (pixel-centre convention)
        det[:, 0] = (det[:, 0] + 0.5) / fx - 0.5
        det[:, 1] = (det[:, 1] + 0.5) / fy - 0.5
        det[:, 2:4] /= math.sqrt(fx * fy)
        result = {"boxes": det}
        if "type" in out and len(det):
            # single-stage heads, read at the centre cell of each detection
            c0 = 1.5
            ix = np.clip(np.round(((det[:, 0] + 0.5) * fx - 0.5 - c0) / 4).astype(int), 0, out["type"].shape[2] - 1)
            iy = np.clip(np.round(((det[:, 1] + 0.5) * fy - 0.5 - c0) / 4).astype(int), 0, out["type"].shape[1] - 1)
            logits = out["type"][:, iy, ix].T
            e = np.exp(logits - logits.max(1, keepdims=True))
            result["type_probs"] = e / e.sum(1, keepdims=True)
            result["shape"] = out["shape"][:, iy, ix].T
        if self.crop_net is not None and len(det) and gsd_m is not None:
            result.update(self.run_crops(image, det, gsd_m))
        return result

    def run_crops(self, image: np.ndarray, det: np.ndarray, gsd_m) -> Dict[str, np.ndarray]:
        import torch

        from detector.crops import extract_crop
        from detector.model import REFINE_OFFSET, REFINE_SCALE, normalize

        g = np.broadcast_to(np.asarray(gsd_m, float), (len(det),))
        crops = np.stack([extract_crop(image, det[i, :2], det[i, 4], g[i]) for i in range(len(det))])
        x = normalize(torch.from_numpy(crops).permute(0, 3, 1, 2).to(self.device))
        with torch.no_grad():
            out = self.crop_net(x)
        out = {k: torch.as_tensor(v) for k, v in out.items()}
        logits = out["type_logits"].flatten(1).cpu().numpy()
        e = np.exp(logits - logits.max(1, keepdims=True))
        flip = out["flip_logit"].flatten().cpu().numpy() > 0
        refine = out["refine"].flatten(1).cpu().numpy() * np.array(REFINE_SCALE) + np.array(REFINE_OFFSET)
        boxes = det.copy()
        boxes[:, 4] = wrap_angle(boxes[:, 4] + np.where(flip, math.pi, 0.0))
        return {"crop_type_probs": e / e.sum(1, keepdims=True),
                "crop_shape": out["shape"].flatten(1).cpu().numpy(),
                "crop_flip": flip, "crop_refine": refine, "boxes_flip_corrected": boxes,
                "boxes_refined": apply_refine(det, flip, refine, g)}


def apply_refine(det: np.ndarray, flip: np.ndarray, refine: np.ndarray, gsd_m) -> np.ndarray:
    """Boxes [M, 6] after the second stage: the inverse of ``crops.refine_target``.

    The crop was cut at (cx, cy, angle) of ``det``; refine = (du_m, dv_m) the true centre in the
    crop frame (x along the crop axis, y to its right), d_angle the true axis minus the crop
    axis, length_m, width_m. The driving direction is the refined axis, turned by 180 deg where
    the crop net says the crop's +x was the rear. Scores are kept."""
    out = det.copy()
    g = np.broadcast_to(np.asarray(gsd_m, float), (len(det),))
    c, s = np.cos(det[:, 4]), np.sin(det[:, 4])
    du, dv = refine[:, 0] / g, refine[:, 1] / g
    out[:, 0] = det[:, 0] + c * du - s * dv
    out[:, 1] = det[:, 1] + s * du + c * dv
    out[:, 2] = refine[:, 3] / g
    out[:, 3] = refine[:, 4] / g
    out[:, 4] = wrap_angle(det[:, 4] + refine[:, 2] + np.where(flip, math.pi, 0.0))
    return out


def evaluate_samples(predictor: Predictor, samples: Sequence, use_crops: bool = True,
                     axis_aligned: bool = False) -> Dict[str, float]:
    """Runs the predictor on loaded-on-demand samples and accumulates the metrics."""
    acc = Accumulator()
    for s in samples:
        s = s.loaded()
        gsd = np.nanmedian(s.gsd_m) if len(s) and np.isfinite(s.gsd_m).any() else None
        res = predictor(s.image, gsd_m=gsd if use_crops else None)
        det = res["boxes"]
        probs = res.get("crop_type_probs", res.get("type_probs"))
        if "boxes_refined" in res:
            det = res["boxes_refined"]
        acc.add(det, s.boxes, s.ignore, s.direction_known, s.gsd_m, s.types, probs,
                axis_aligned=axis_aligned)
    return acc.result()
