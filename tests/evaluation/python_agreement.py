"""vp_evaluate (C++) and tools/detector/evaluate.py (the Python evaluation used in training)
give the same figures on the same inputs.

Run by CTest as ``python.evaluate_agreement``:

    /usr/bin/python3 tests/evaluation/python_agreement.py --evaluate BUILD/tools/evaluate/vp_evaluate \
        --simulate BUILD/tools/simulator/vp_simulate [--keep DIR]

1. Rotated boxes: simulates a small sequence (vp_simulate, 3 frames, 640 x 512), reads its ground
   truth with ``datasets.read_sequence`` (same ignore rule, same GSD), writes a detections file
   (docs/detections_file.md) with seeded perturbations (misses, centre / size / angle noise,
   reversed directions, false positives, type probabilities, lifted or not), runs both
   evaluations and compares every measure evaluate.py has.
2. Axis-aligned boxes: a synthetic YOLO folder (``datasets.read_yolo``) with a validation
   list; both evaluate the listed images only.

Exits 0 when all figures agree within 1e-9 (relative or absolute), 1 otherwise, printing both.
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(REPO, "tools"))

from detector.asm import TYPES  # noqa: E402
from detector.datasets import read_sequence, read_yolo  # noqa: E402
from detector.evaluate import Accumulator  # noqa: E402

TWO_PI = 2.0 * math.pi
TOLERANCE = 1e-9
# datasets.py keeps keypoint pixels as float32, so its per-object GSD (and the position errors
# in metres) carries float32 rounding (~1e-7 relative); the C++ side reads doubles.
GSD_TOLERANCE = 1e-6
GSD_KEYS = ("position_median_m", "position_mad_m")
LIFT_WORDS = ["ok", "outside_dtm", "stale_pose"]


def header(key: str, n_gamma: int) -> str:
    cols = [key, "det_id", "score", "box_cx_px", "box_cy_px", "box_length_px", "box_width_px",
            "box_angle_rad", "direction_known", "type"] + [f"p_{t}" for t in TYPES]
    cols += [f"gamma_{i}" for i in range(n_gamma)]
    cols += ["lift_status", "east_m", "north_m", "up_m", "lat_deg", "lon_deg", "height_m",
             "heading_enu_rad", "length_m", "width_m", "height_m_vehicle"]
    return ",".join(cols)


def wrap(a: float) -> float:
    w = math.fmod(a, TWO_PI)
    if w < 0:
        w += TWO_PI
    return 0.0 if w >= TWO_PI else w


def probabilities(rng, true_type: int) -> np.ndarray:
    p = rng.dirichlet(np.full(len(TYPES), 0.7))
    if true_type >= 0 and rng.random() < 0.6:
        p[true_type] += 1.5  # usually right, sometimes only second
    p /= p.sum()
    # 6 decimals: distinct values stay distinct (and in the same order) as float32 in C++.
    text = [f"{v:.6f}" for v in p]
    return np.array([float(t) for t in text]), text


def detection_row(key: str, det_id: int, score_text: str, box, probs_text, n_gamma: int,
                  gamma=None, lifted=None) -> str:
    box_text = [repr(float(v)) for v in box]
    probs = [float(t) for t in probs_text]
    top = TYPES[int(np.argmax(probs))]
    gamma_text = ["" if gamma is None or i >= len(gamma) else f"{gamma[i]:.5f}"
                  for i in range(n_gamma)]
    if lifted is None:
        world = ["outside_dtm"] + [""] * 10
    else:
        world = ["ok"] + [repr(float(v)) for v in lifted]
    fields = [key, str(det_id), score_text] + box_text + ["1", top] + list(probs_text) + \
        gamma_text + world
    return ",".join(fields)


def compare(name: str, cpp: dict, py: dict, keys) -> bool:
    ok = True
    for k in keys:
        a, b = cpp.get(k), py.get(k)
        if isinstance(b, float) and math.isnan(b):
            same = a is None
        else:
            tol = GSD_TOLERANCE if k in GSD_KEYS else TOLERANCE
            same = a is not None and abs(a - b) <= tol * max(1.0, abs(b))
        print(f"{name:9s} {k:24s} C++ {a!s:>24s}  Python {b!s:>24s}  {'ok' if same else 'DIFFERENT'}")
        ok = ok and same
    return ok


def run_evaluate(exe: str, args) -> dict:
    proc = subprocess.run([exe] + args, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"vp_evaluate failed ({proc.returncode}): {proc.stderr}")
    out = args[args.index("--out") + 1]
    with open(os.path.join(out, "report.json"), encoding="utf-8") as f:
        return json.load(f)["measures"]


def sequence_case(args, work: str) -> bool:
    seq = os.path.join(work, "seq")
    subprocess.run([args.simulate, "--scene", "intersection", "--seed", "11", "--frames", "3",
                    "--width", "640", "--height", "512", "--supersampling", "1", "--out", seq],
                   check=True, capture_output=True)
    samples = read_sequence(seq)
    rng = np.random.default_rng(5)
    n_gamma = 3
    lines = ["# model: python agreement perturbations", header("frame_id", n_gamma)]
    acc = Accumulator()
    for s in samples:
        rows, preds, probs_all = [], [], []
        det_id = 0
        candidates = []
        for i in range(len(s)):
            if rng.random() < 0.15:
                continue  # missed
            b = s.boxes[i].copy()
            b[0] += rng.normal(0, 0.8)
            b[1] += rng.normal(0, 0.8)
            b[2] *= 1 + rng.normal(0, 0.04)
            b[3] *= 1 + rng.normal(0, 0.04)
            b[4] = wrap(b[4] + math.radians(rng.normal(0, 3)) + (math.pi if rng.random() < 0.1 else 0))
            gamma = None
            if not np.isnan(s.gammas[i]).all():
                gamma = [float(g) + rng.normal(0, 0.2) for g in s.gammas[i]]
            candidates.append((b, int(s.types[i]), gamma))
        for _ in range(rng.integers(1, 3)):  # false positives
            candidates.append((np.array([rng.uniform(0, 640), rng.uniform(0, 512),
                                         rng.uniform(20, 40), rng.uniform(8, 16),
                                         rng.uniform(0, TWO_PI)]), -1, None))
        scores = rng.permutation(len(candidates)) / max(1, len(candidates)) * 0.9 + 0.05
        for (b, t, gamma), score in zip(candidates, scores):
            score_text = f"{score + rng.uniform(0, 1e-3):.6f}"
            probs, probs_text = probabilities(rng, t)
            lifted = None
            if rng.random() < 0.8:
                lifted = [rng.normal(0, 20), rng.normal(0, 20), 250 + rng.normal(0, 1), 43.07,
                          -89.4, 250.0, rng.uniform(0, 6.28), 4.5, 1.8, 1.5]
            rows.append(detection_row(str(s.frame_index), det_id, score_text, b, probs_text,
                                      n_gamma, gamma, lifted))
            det_id += 1
            preds.append([float(x) for x in rows[-1].split(",")[3:8]] + [float(score_text)])
            probs_all.append(probs)
        lines += rows
        pred = np.array(preds).reshape(-1, 6)
        acc.add(pred, s.boxes, s.ignore, s.direction_known, s.gsd_m, s.types,
                np.array(probs_all).reshape(-1, len(TYPES)))
    det_file = os.path.join(work, "seq_detections.csv")
    with open(det_file, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")
    py = acc.result()
    cpp = run_evaluate(args.evaluate, ["--sequence", seq, "--detections", det_file,
                                       "--out", os.path.join(work, "seq_report")])
    return compare("sequence", cpp, py,
                   ["tp", "fp", "fn", "precision", "recall", "f1", "position_median_px",
                    "position_median_m", "position_mad_m", "orientation_median_deg",
                    "orientation_mad_deg", "orientation_flip_share", "type_oa1", "type_oa2",
                    "type_count"])


def yolo_case(args, work: str) -> bool:
    import cv2

    root = os.path.join(work, "yolo")
    os.makedirs(os.path.join(root, "images"))
    os.makedirs(os.path.join(root, "labels"))
    rng = np.random.default_rng(6)
    stems = [f"{clip}_{i}" for clip in ("0", "Drone2") for i in range(4)]
    for stem in stems:
        cv2.imwrite(os.path.join(root, "images", stem + ".png"), np.full((240, 320, 3), 80, np.uint8))
        with open(os.path.join(root, "labels", stem + ".txt"), "w", encoding="utf-8") as f:
            for _ in range(rng.integers(2, 7)):
                f.write(f"{rng.integers(0, 2)} {rng.uniform(0.1, 0.9):.6f} {rng.uniform(0.1, 0.9):.6f} "
                        f"{rng.uniform(0.05, 0.15):.6f} {rng.uniform(0.05, 0.15):.6f}\n")
    val = stems[1::2]
    with open(os.path.join(work, "val.txt"), "w", encoding="utf-8") as f:
        f.write("# validation stems\n" + "\n".join(val) + "\n")
    lines = ["# model: python agreement yolo", header("image", 0)]
    acc = Accumulator()
    uniform = [f"{1 / 7:.6f}"] * 6 + [f"{1 - 6 * float(f'{1 / 7:.6f}'):.6f}"]
    for s in read_yolo(root):
        s = s.loaded()
        stem = os.path.splitext(os.path.basename(s.image_path))[0]
        preds, rows = [], []
        for i in range(len(s)):
            if rng.random() < 0.15:
                continue
            cx, cy, w, h = s.boxes[i, :4]
            standing = h > w  # a rotated box whose enclosing box is about the label's
            length, width = (h, w) if standing else (w, h)
            ang = (math.pi / 2 if standing else 0.0) + (math.pi if rng.random() < 0.5 else 0.0)
            b = [cx + rng.normal(0, 1), cy + rng.normal(0, 1), length * (1 + rng.normal(0, 0.05)),
                 width * (1 + rng.normal(0, 0.05)), wrap(ang + math.radians(rng.normal(0, 2)))]
            preds.append(b)
        preds.append([rng.uniform(0, 320), rng.uniform(0, 240), 30.0, 12.0, rng.uniform(0, 6.28)])
        scores = [f"{v:.6f}" for v in rng.permutation(len(preds)) / len(preds) * 0.9 + 0.05]
        for k, (b, score_text) in enumerate(zip(preds, scores)):
            rows.append(detection_row(stem, k, score_text, b, uniform, 0))
        lines += rows
        if stem in val:
            pred = np.array([[float(x) for x in r.split(",")[3:8]] + [float(sc)]
                             for r, sc in zip(rows, scores)]).reshape(-1, 6)
            acc.add(pred, s.boxes, s.ignore, axis_aligned=True)
    det_file = os.path.join(work, "yolo_detections.csv")
    with open(det_file, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")
    py = acc.result()
    cpp = run_evaluate(args.evaluate, ["--yolo", root, "--detections", det_file, "--val-list",
                                       os.path.join(work, "val.txt"), "--out",
                                       os.path.join(work, "yolo_report")])
    return compare("yolo", cpp, py, ["tp", "fp", "fn", "precision", "recall", "f1",
                                     "position_median_px"])


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--evaluate", required=True, help="the vp_evaluate executable")
    p.add_argument("--simulate", required=True, help="the vp_simulate executable")
    p.add_argument("--keep", help="work folder to keep (default: a temporary one)")
    args = p.parse_args()
    if args.keep:
        os.makedirs(args.keep, exist_ok=False)
        ok = sequence_case(args, args.keep) & yolo_case(args, args.keep)
    else:
        with tempfile.TemporaryDirectory(prefix="vp_eval_agree_") as work:
            ok = sequence_case(args, work) & yolo_case(args, work)
    print("agreement:", "all figures agree" if ok else "FIGURES DIFFER")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
