#!/usr/bin/python3
"""Detection and driving-direction measures on real images labelled with rotated boxes.

Reads a folder of real images whose labels are rotated boxes with the driving direction
(``labels/<stem>.txt``, one line per vehicle: ``car cx cy length width heading_rad`` in pixels,
the project's image convention: heading of the forward axis from +u towards +v in [0, 2pi);
``../shared/data/real/bev-intersection-de``) and the detections ``vp_detect_images --images
ROOT`` wrote for it (docs/detections_file.md, the ``image`` variant). Per image, detections
are matched to labels greedily by descending score when their rotated IoU reaches --iou (0.5,
seed 000's rule; ``evaluate.match``, as for the simulated sets); every label and detection is
used at most once.

Prints and writes (--out, JSON) precision, recall, F1, the median and MAD (x1.4826) of the
absolute heading error of matched vehicles, the share reversed (error > 90 degrees) and the
cumulative histogram of the heading error; --list-reversed also lists each reversed vehicle
(image, label box, detection), --list-false each detection matching no label and --list-missed
each label no detection matched, for pictures of the failures (``failure_sheet.py``).

The false detections are also counted by where they are: those whose box reaches beyond the
image (a vehicle cut by the border; the set labels none, so every such box is false by its
rule) and the rest; ``precision_inside`` is the precision without the former. It explains the
official figure, it does not replace it.

  tools/detector/eval_rotated_real.py --root ../shared/data/real/bev-intersection-de \
      --detections dets.csv [--out report.json] [--list-reversed reversed.csv] \
      [--list-false false.csv] [--list-missed missed.csv]

Run with Debian's Python (/usr/bin/python3).
"""
from __future__ import annotations

import argparse
import csv
import glob
import json
import math
import os
import sys
from typing import Dict, Tuple

import cv2
import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from detector.datasets import DatasetError  # noqa: E402
from detector.evaluate import match  # noqa: E402
from detector.geometry import abs_angle_difference, enclosing_aabb  # noqa: E402
from detector.mine_negatives import read_detections  # noqa: E402


def read_rotated_labels(root: str) -> Dict[str, np.ndarray]:
    """stem -> [N, 5] boxes (cx, cy, length, width, heading) of ``root/labels/*.txt``; a
    malformed line is an error naming the file and line."""
    folder = os.path.join(root, "labels")
    if not os.path.isdir(folder):
        raise DatasetError(f"{folder}: missing label folder")
    out = {}
    for path in sorted(glob.glob(os.path.join(folder, "*.txt"))):
        boxes = []
        with open(path) as f:
            for line_no, line in enumerate(f, start=1):
                parts = line.split()
                if not parts:
                    continue
                if len(parts) != 6:
                    raise DatasetError(f"{path}:{line_no}: expected 'class cx cy length width "
                                       f"heading_rad', got {len(parts)} fields")
                try:
                    vals = [float(p) for p in parts[1:]]
                except ValueError:
                    raise DatasetError(f"{path}:{line_no}: not a number in '{line.strip()}'") from None
                if not all(math.isfinite(v) for v in vals) or vals[2] <= 0 or vals[3] <= 0:
                    raise DatasetError(f"{path}:{line_no}: sizes must be finite and > 0")
                boxes.append(vals)
        out[os.path.splitext(os.path.basename(path))[0]] = np.asarray(boxes, np.float64).reshape(-1, 5)
    if not out:
        raise DatasetError(f"{folder}: no label files")
    return out


def image_path(root: str, stem: str) -> str | None:
    """The image of a label stem in ``root/images`` (any extension), or None."""
    hits = sorted(glob.glob(os.path.join(root, "images", glob.escape(stem) + ".*")))
    return hits[0] if hits else None


def reaches_border(box: np.ndarray, size: Tuple[int, int]) -> bool:
    """Whether a rotated box (cx, cy, length, width, angle) reaches beyond a (width, height)
    image."""
    cx, cy, w, h = enclosing_aabb(box)[0]
    return bool(cx - w / 2 < 0 or cy - h / 2 < 0 or cx + w / 2 > size[0] or cy + h / 2 > size[1])


def evaluate(labels: Dict[str, np.ndarray], dets: Dict, iou: float = 0.5, min_score: float = 0.0,
             failures: Dict[str, list] | None = None,
             sizes: Dict[str, Tuple[int, int]] | None = None):
    """(report, reversed rows); with ``failures`` (a dict) also fills its ``false`` rows
    (image, score, detection box) and ``missed`` rows (image, label box); with ``sizes`` (stem
    -> image width, height) the report splits the false detections by the border."""
    tp = n_det = n_lab = false_border = 0
    errors, reversed_rows = [], []
    for stem, boxes in labels.items():
        found = [(s, b) for s, b in dets.get(stem, []) if s >= min_score]
        n_det += len(found)
        n_lab += len(boxes)
        pairs, _, _ = match(np.array([b for _, b in found]).reshape(-1, 5),
                            np.array([sc for sc, _ in found]), boxes.reshape(-1, 5),
                            np.zeros(len(boxes), bool), iou)
        used_det = {k for k, _ in pairs}
        if sizes is not None and stem in sizes:
            false_border += sum(1 for k in range(len(found))
                                if k not in used_det and reaches_border(found[k][1], sizes[stem]))
        if failures is not None:
            used_lab = {j for _, j in pairs}
            failures.setdefault("false", []).extend(
                (stem, found[k][0], *found[k][1]) for k in range(len(found)) if k not in used_det)
            failures.setdefault("missed", []).extend(
                (stem, *boxes[j]) for j in range(len(boxes)) if j not in used_lab)
        for k, j in pairs:
            tp += 1
            err = math.degrees(float(abs_angle_difference(found[k][1][4], boxes[j][4])))
            errors.append(err)
            if err > 90.0:
                reversed_rows.append((stem, *boxes[j], found[k][0], *found[k][1]))
    p = tp / n_det if n_det else 0.0
    r = tp / n_lab if n_lab else 0.0
    e = np.asarray(errors)
    med = float(np.median(e)) if len(e) else math.nan
    report = {
        "images": len(labels), "labels": n_lab, "detections": n_det, "true_positives": tp,
        "precision": p, "recall": r, "f1": 2 * p * r / (p + r) if p + r else 0.0,
        "heading_median_deg": med,
        "heading_mad_deg": float(1.4826 * np.median(np.abs(e - med))) if len(e) else math.nan,
        "false_detections": n_det - tp,
        "false_reaching_border": false_border if sizes is not None else None,
        "precision_inside": (tp / (n_det - false_border) if n_det - false_border else 0.0)
        if sizes is not None else None,
        "reversed": int((e > 90).sum()), "reversed_share": float((e > 90).mean()) if len(e) else math.nan,
        "heading_cumulative": {f"<={t}": float((e <= t).mean()) if len(e) else math.nan
                               for t in (2, 5, 10, 20, 45, 90, 135, 180)},
    }
    return report, reversed_rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--root", required=True, help="folder with images/ and labels/ (rotated)")
    p.add_argument("--detections", required=True, help="vp_detect_images --images CSV")
    p.add_argument("--iou", type=float, default=0.5, help="rotated IoU from which a match counts")
    p.add_argument("--min-score", type=float, default=0.0, help="ignore detections below")
    p.add_argument("--out", default=None, help="write the report as JSON")
    p.add_argument("--list-reversed", default=None, help="write the reversed vehicles as CSV")
    p.add_argument("--list-false", default=None, help="write the detections matching no label as CSV")
    p.add_argument("--list-missed", default=None, help="write the labels no detection matched as CSV")
    a = p.parse_args(argv)
    if not 0 < a.iou <= 1:
        p.error("--iou must be in (0, 1]")
    try:
        labels = read_rotated_labels(a.root)
        dets = read_detections(a.detections, key="image")
    except (DatasetError, OSError) as e:
        print(f"eval_rotated_real.py: {e}", file=sys.stderr)
        return 1
    unknown = sorted(set(dets) - set(labels))
    if unknown:
        print(f"eval_rotated_real.py: {a.detections}: {len(unknown)} images without labels, "
              f"e.g. '{unknown[0]}'", file=sys.stderr)
        return 1
    sizes = {}
    for stem in labels:
        path = image_path(a.root, stem)
        img = cv2.imread(path, cv2.IMREAD_UNCHANGED) if path else None
        if img is not None:
            sizes[stem] = (img.shape[1], img.shape[0])
    failures: Dict[str, list] = {}
    report, rows = evaluate(labels, dets, a.iou, a.min_score, failures, sizes)
    report["detections_file"] = os.path.abspath(a.detections)
    print(f"P {report['precision']:.3f}  R {report['recall']:.3f}  F1 {report['f1']:.3f}  "
          f"heading median {report['heading_median_deg']:.2f} deg  reversed "
          f"{report['reversed']}/{report['true_positives']} ({100 * report['reversed_share']:.1f} %)")
    print(f"false detections {report['false_detections']}: {report['false_reaching_border']} reach the "
          f"image border (the set labels no vehicle cut by it), precision without them "
          f"{report['precision_inside']:.3f}")
    if a.out:
        with open(a.out, "w") as f:
            json.dump(report, f, indent=2)
    if a.list_reversed:
        with open(a.list_reversed, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["image", "cx_px", "cy_px", "length_px", "width_px", "heading_rad", "score",
                        "det_cx_px", "det_cy_px", "det_length_px", "det_width_px", "det_angle_rad"])
            w.writerows(rows)
    lists = ((a.list_false, "false", ["image", "score", "det_cx_px", "det_cy_px", "det_length_px",
                                      "det_width_px", "det_angle_rad"]),
             (a.list_missed, "missed", ["image", "cx_px", "cy_px", "length_px", "width_px",
                                        "heading_rad"]))
    for path, key, header in lists:
        if path:
            with open(path, "w", newline="") as f:
                w = csv.writer(f)
                w.writerow(header)
                w.writerows(failures.get(key, []))
    return 0


if __name__ == "__main__":
    sys.exit(main())
