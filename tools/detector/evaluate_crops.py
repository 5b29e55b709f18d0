#!/usr/bin/python3
"""Evaluates the second stage (CropNet) alone on ground-truth vehicles: type, shape, front/back.

    tools/detector/evaluate_crops.py --checkpoint RUN/checkpoint.pt --data SEQDIR ... \\
        [--jitter] [--seed 0] [--json OUT.json] [--label V_L1]

Contract
--------
For every ground-truth car of the held-out sequences (type known, not ``ignore``, GSD known) a
crop is cut at the ground-truth pose (``--jitter``: at a pose drawn like a first-stage
detection, ``crops.jittered_crop_target`` with a fixed seed, incl. 180-degree reversals) and the
crop net's outputs are compared with the truth. Measures (seed 000, sec. 5.1):

* type: F1 per class, OA-1 (top-1 correct), OA-2 (truth among the two highest scores);
* shape (cars only): keypoints of the 24 evaluation keypoints from the predicted and the true
  gamma through the ASM (Eq. 1), in the vehicle frame; E_D2D = RMS over vehicles and keypoints of
  the planimetric distance, E_dH = RMS of the height difference; E_l, E_w, E_h = RMS of the
  differences of the minimum 3D boxes (axis-aligned in the vehicle frame) enclosing all 36
  keypoints of each model;
* front/back: share of crops whose flip decision is wrong;
* refinement: median |centre error| (m) and |axis error| (deg) after applying ``refine``.

The figures isolate the second stage: the first stage's misses and pose errors are the full
evaluation's business (``vp_evaluate``). Prints a Markdown table row set and writes JSON.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from typing import Dict, List

if __package__ in (None, ""):
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np
import torch

from detector import crops
from detector.asm import CAR_TYPES, DEFAULT_ASM_PATH, EVAL_KEYPOINTS, TYPES, load_asm
from detector.datasets import read_sequence
from detector.model import REFINE_OFFSET, REFINE_SCALE, STRIDE, CropNet, Detector, normalize


def shape_errors(asm, pred_gamma: np.ndarray, true_gamma: np.ndarray) -> Dict[str, float]:
    """E_D2D, E_dH over the evaluation keypoints; E_l, E_w, E_h of the enclosing 3D boxes."""
    if len(pred_gamma) == 0:
        return {k: math.nan for k in ("E_D2D_m", "E_dH_m", "E_l_m", "E_w_m", "E_h_m")}
    p, t = asm.shape(pred_gamma), asm.shape(true_gamma)  # [N, 36, 3]
    ev = list(EVAL_KEYPOINTS)
    d2 = np.sum((p[:, ev, :2] - t[:, ev, :2]) ** 2, -1)
    dh = (p[:, ev, 2] - t[:, ev, 2]) ** 2
    ext_p = p.max(1) - p.min(1)
    ext_t = t.max(1) - t.min(1)
    e = np.sqrt(np.mean((ext_p - ext_t) ** 2, 0))
    return {"E_D2D_m": float(np.sqrt(d2.mean())), "E_dH_m": float(np.sqrt(dh.mean())),
            "E_l_m": float(e[0]), "E_w_m": float(e[1]), "E_h_m": float(e[2])}


def type_scores(probs: np.ndarray, truth: np.ndarray) -> Dict[str, float]:
    top = np.argsort(-probs, 1)
    out = {"OA1": float(np.mean(top[:, 0] == truth)),
           "OA2": float(np.mean((top[:, 0] == truth) | (top[:, 1] == truth)))}
    for k, name in enumerate(TYPES):
        tp = np.sum((top[:, 0] == k) & (truth == k))
        fp = np.sum((top[:, 0] == k) & (truth != k))
        fn = np.sum((top[:, 0] != k) & (truth == k))
        out[f"F1_{name}"] = float(2 * tp / (2 * tp + fp + fn)) if tp + fp + fn else math.nan
        out[f"n_{name}"] = int(np.sum(truth == k))
    return out


def evaluate(crop_net, asm, sequences: List[str], jitter: bool, seed: int, batch: int = 64) -> dict:
    rng = np.random.default_rng(seed)
    patches, types, gammas, flips, refines = [], [], [], [], []
    for d in sequences:
        for s in read_sequence(d, n_s=asm.n_s):
            s = s.loaded()
            for j in range(len(s)):
                if s.ignore[j] or s.types[j] < 0 or s.aa_only[j] or not math.isfinite(s.gsd_m[j]):
                    continue
                box, gsd = s.boxes[j], float(s.gsd_m[j])
                if jitter:
                    cen, ang, gsd_used, flip, refine = crops.jittered_crop_target(box, gsd, rng)
                else:
                    cen, ang, gsd_used = box[:2], float(box[4]), gsd
                    flip, refine = crops.refine_target(box, gsd, cen, ang)
                patches.append(crops.extract_crop(s.image, cen, ang, gsd_used))
                types.append(int(s.types[j]))
                gammas.append(s.gammas[j])
                flips.append(flip)
                refines.append(refine)
    if not patches:
        raise SystemExit("evaluate_crops: no typed ground-truth vehicles in the given sequences")
    outs: Dict[str, List[np.ndarray]] = {}
    crop_net.eval()
    with torch.no_grad():
        for i in range(0, len(patches), batch):
            x = normalize(torch.from_numpy(np.stack(patches[i:i + batch])).permute(0, 3, 1, 2))
            for k, v in crop_net(x).items():
                outs.setdefault(k, []).append(v.flatten(1).numpy())
    o = {k: np.concatenate(v) for k, v in outs.items()}
    types_a, gam, flip_t, ref_t = np.array(types), np.stack(gammas), np.array(flips), np.stack(refines)
    logits = o["type_logits"]
    probs = np.exp(logits - logits.max(1, keepdims=True))
    probs /= probs.sum(1, keepdims=True)
    res = {"vehicles": len(types), "jitter": jitter}
    res.update(type_scores(probs, types_a))
    cars = np.isfinite(gam).all(1) & (types_a < len(CAR_TYPES))
    res.update(shape_errors(asm, o["shape"][cars].astype(np.float64), gam[cars].astype(np.float64)))
    flip_p = o["flip_logit"][:, 0] > 0
    res["flip_error_share"] = float(np.mean(flip_p != flip_t.astype(bool)))
    ref = o["refine"] * np.array(REFINE_SCALE) + np.array(REFINE_OFFSET)
    res["centre_error_median_m"] = float(np.median(np.hypot(ref[:, 0] - ref_t[:, 0], ref[:, 1] - ref_t[:, 1])))
    res["axis_error_median_deg"] = float(np.degrees(np.median(np.abs(ref[:, 2] - ref_t[:, 2]))))
    res["length_rms_m"] = float(np.sqrt(np.mean((ref[:, 3] - ref_t[:, 3]) ** 2)))
    res["width_rms_m"] = float(np.sqrt(np.mean((ref[:, 4] - ref_t[:, 4]) ** 2)))
    return res


def evaluate_single_stage(det, asm, sequences: List[str], working_width: int = 648) -> dict:
    """Type and shape of the single-stage variant: the detector's dense type/shape heads read
    at the cell of each ground-truth centre (the best case for it: no localisation error)."""
    from detector.evaluate import Predictor

    pred = Predictor(det, None)
    probs, shapes, types, gammas = [], [], [], []
    det.eval()
    for d in sequences:
        for s in read_sequence(d, n_s=asm.n_s):
            s = s.loaded()
            keep = [j for j in range(len(s)) if not s.ignore[j] and s.types[j] >= 0 and not s.aa_only[j]]
            if not keep:
                continue
            scale = working_width / s.image.shape[1]
            canvas, fx, fy = pred.working_image(s.image, scale)
            x = normalize(torch.from_numpy(canvas).permute(2, 0, 1)[None])
            with torch.no_grad():
                out = det(x)
            t, g = out["type"][0].numpy(), out["shape"][0].numpy()
            for j in keep:
                u = (s.boxes[j, 0] + 0.5) * fx - 0.5
                v = (s.boxes[j, 1] + 0.5) * fy - 0.5
                ix = int(np.clip(round((u - (STRIDE - 1) / 2) / STRIDE), 0, t.shape[2] - 1))
                iy = int(np.clip(round((v - (STRIDE - 1) / 2) / STRIDE), 0, t.shape[1] - 1))
                logit = t[:, iy, ix]
                e = np.exp(logit - logit.max())
                probs.append(e / e.sum())
                shapes.append(g[:, iy, ix])
                types.append(int(s.types[j]))
                gammas.append(s.gammas[j])
    types_a, gam = np.array(types), np.stack(gammas)
    res = {"vehicles": len(types), "jitter": False}
    res.update(type_scores(np.stack(probs), types_a))
    cars = np.isfinite(gam).all(1) & (types_a < len(CAR_TYPES))
    res.update(shape_errors(asm, np.stack(shapes)[cars].astype(np.float64), gam[cars].astype(np.float64)))
    res["flip_error_share"] = math.nan
    return res


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--checkpoint", required=True, help="train.py run checkpoint (with a crop net)")
    p.add_argument("--data", nargs="+", required=True, help="held-out recorded sequences")
    p.add_argument("--asm", default=DEFAULT_ASM_PATH)
    p.add_argument("--jitter", action="store_true", help="crop at detector-like poses")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--single-stage", action="store_true",
                   help="evaluate the detector's own type/shape heads (single-stage variant) instead")
    p.add_argument("--label", default="", help="row label in the printed table")
    p.add_argument("--json", default=None, help="write the figures here")
    args = p.parse_args(argv)
    asm = load_asm(args.asm)
    ck = torch.load(args.checkpoint, map_location="cpu")
    if args.single_stage:
        if not ck.get("single_stage"):
            raise SystemExit(f"{args.checkpoint}: not a single-stage run (--single-stage)")
        det = Detector(n_s=ck.get("n_s", asm.n_s), single_stage=True)
        det.load_state_dict(ck["detector"])
        res = evaluate_single_stage(det, asm, args.data)
    else:
        if ck.get("crop") is None:
            raise SystemExit(f"{args.checkpoint}: the run has no crop net (--no-crop)")
        net = CropNet.from_state_dict(ck["crop"], n_s=ck.get("n_s", asm.n_s))
        res = evaluate(net, asm, args.data, args.jitter, args.seed)
    res.update({"checkpoint": args.checkpoint, "steps": ck.get("step"),
                "shape_loss": ck.get("shape_loss"), "label": args.label})
    if args.json:
        with open(args.json, "w") as f:
            json.dump(res, f, indent=1)
    lab = args.label or ck.get("shape_loss", "")
    print("| variant | vehicles | OA-1 | OA-2 | E_l | E_w | E_h | E_D2D | E_dH | flip err |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    print(f"| {lab} | {res['vehicles']} | {100 * res['OA1']:.1f} % | {100 * res['OA2']:.1f} % | "
          f"{res['E_l_m']:.3f} | {res['E_w_m']:.3f} | {res['E_h_m']:.3f} | {res['E_D2D_m']:.3f} | "
          f"{res['E_dH_m']:.3f} | {100 * res['flip_error_share']:.1f} % |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
