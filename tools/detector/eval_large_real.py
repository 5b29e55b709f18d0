#!/usr/bin/python3
"""Buses and trucks on real images with axis-aligned labels: boxed whole, in parts, or missed.

A real set such as ``../shared/data/real/cats-madison`` (YOLO: ``images/``, ``labels/<stem>.txt``
with ``class cx cy w h`` normalised) labels every vehicle as one class. Its long vehicles are
found by size: a label whose long side is at least --min-length-m at the set's --gsd-m (8.5 m:
longer than any car or van) is a bus or a truck. For each such label and the detections
``vp_detect_images --images ROOT`` wrote for the set (docs/detections_file.md, the ``image``
variant), with each detection's rotated box taken as its axis-aligned enclosing box clipped to
the image:

* **whole**: some detection overlaps the label with IoU >= --iou (0.5, the set's rule);
* **parts**: none does, but at least one detection lies mostly (over half its area) inside the
  label: the vehicle was boxed in pieces or with a box of the wrong size;
* **missed**: neither.

Prints the three counts (and --out writes them as JSON with one row per vehicle;
--list-failures writes the vehicles in parts or missed as a failure list for
``failure_sheet.py``: the label as a box along its long side, and the detection overlapping it
most, if any). The
detections are not matched one to one here: the figure says how long vehicles are boxed, the
set's precision and recall stay ``vp_evaluate``'s.

  tools/detector/eval_large_real.py --root ../shared/data/real/cats-madison --gsd-m 0.047 \\
      --detections dets.csv [--list split.json] [--out report.json] [--list-failures left.csv]

Run with Debian's Python (/usr/bin/python3).
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import sys
from typing import Dict, Optional, Set

import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from detector.datasets import DatasetError, file_stem, read_yolo  # noqa: E402
from detector.mine_negatives import (aa_iou, enclosing_box, read_detections,  # noqa: E402
                                     read_stems, yolo_pixel_boxes)


def _inside_share(dets: np.ndarray, label: np.ndarray) -> np.ndarray:
    """Share of each detection box [x0, y0, x1, y1] (rows of ``dets``) inside the label."""
    iw = np.clip(np.minimum(dets[:, 2], label[2]) - np.maximum(dets[:, 0], label[0]), 0, None)
    ih = np.clip(np.minimum(dets[:, 3], label[3]) - np.maximum(dets[:, 1], label[1]), 0, None)
    area = (dets[:, 2] - dets[:, 0]) * (dets[:, 3] - dets[:, 1])
    return np.where(area > 0, iw * ih / np.maximum(area, 1e-9), 0.0)


def classify(label: np.ndarray, dets: np.ndarray, iou: float) -> tuple:
    """('whole' | 'parts' | 'missed', best IoU) of one label [x0, y0, x1, y1] against the
    detections' clipped enclosing boxes ([N, 4])."""
    best = float(aa_iou(label, dets).max(initial=0.0))
    if best >= iou:
        return "whole", best
    if len(dets) and (_inside_share(dets, label) > 0.5).any():
        return "parts", best
    return "missed", best


def evaluate(root: str, detections: Dict, gsd_m: float, min_length_m: float, iou: float = 0.5,
             stems: Optional[Set[str]] = None) -> dict:
    counts = {"whole": 0, "parts": 0, "missed": 0}
    rows = []
    min_px = min_length_m / gsd_m
    for sample in read_yolo(root):
        stem = file_stem(sample.image_path)
        if (stems is not None and stem not in stems) or not len(sample.boxes):
            continue
        height, width = sample.loaded().image.shape[:2]
        rotated = [b for _, b in detections.get(stem, [])]
        dets = np.array([enclosing_box(b, width, height) for b in rotated]).reshape(-1, 4)
        for box in yolo_pixel_boxes(sample.boxes, width, height):
            length_px = max(box[2] - box[0], box[3] - box[1])
            if length_px < min_px:
                continue
            kind, best = classify(box, dets, iou)
            counts[kind] += 1
            row = {"image": stem, "cx_px": float(box[0] + box[2]) / 2,
                   "cy_px": float(box[1] + box[3]) / 2, "length_px": float(length_px),
                   "width_px": float(min(box[2] - box[0], box[3] - box[1])),
                   "heading_rad": 0.0 if box[2] - box[0] >= box[3] - box[1] else math.pi / 2,
                   "result": kind, "best_iou": round(float(best), 3)}
            overlap = aa_iou(box, dets)
            if len(overlap) and overlap.max() > 0:
                row["detection"] = [float(v) for v in rotated[int(overlap.argmax())]]
            rows.append(row)
    return {"min_length_m": min_length_m, "gsd_m": gsd_m, "iou": iou,
            "vehicles": sum(counts.values()), **counts, "rows": rows}


FAILURE_COLUMNS = ["image", "result", "cx_px", "cy_px", "length_px", "width_px", "heading_rad",
                   "det_cx_px", "det_cy_px", "det_length_px", "det_width_px", "det_angle_rad"]


def write_failures(path: str, report: dict) -> None:
    """The vehicles boxed in parts or missed, as a failure list of failure_sheet.py (label box
    along the label's long side, no direction; the most overlapping detection, else empty)."""
    with open(path, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(FAILURE_COLUMNS)
        for r in report["rows"]:
            if r["result"] == "whole":
                continue
            det = r.get("detection")
            out.writerow([r["image"], r["result"], r["cx_px"], r["cy_px"], r["length_px"],
                          r["width_px"], r["heading_rad"]] + (det if det else [""] * 5))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--root", required=True, help="YOLO folder (images/, labels/)")
    p.add_argument("--detections", required=True, help="vp_detect_images --images CSV")
    p.add_argument("--gsd-m", type=float, required=True, help="metres per image pixel")
    p.add_argument("--min-length-m", type=float, default=8.5,
                   help="labels at least this long are buses and trucks (default 8.5)")
    p.add_argument("--iou", type=float, default=0.5, help="IoU from which a box is whole")
    p.add_argument("--list", default=None, help="only these images (split.json or stems)")
    p.add_argument("--out", default=None, help="JSON report with one row per vehicle")
    p.add_argument("--list-failures", default=None,
                   help="CSV of the vehicles in parts or missed, for failure_sheet.py")
    a = p.parse_args(argv)
    if not a.gsd_m > 0 or not a.min_length_m > 0:
        p.error("--gsd-m and --min-length-m must be > 0")
    if not 0 < a.iou <= 1:
        p.error("--iou must be in (0, 1]")
    try:
        report = evaluate(a.root, read_detections(a.detections, key="image"), a.gsd_m,
                          a.min_length_m, a.iou, read_stems(a.list, "val_stems") if a.list else None)
    except (DatasetError, OSError) as e:
        print(f"eval_large_real: {e}", file=sys.stderr)
        return 1
    print(f"long vehicles (>= {a.min_length_m} m): {report['vehicles']}  whole {report['whole']}  "
          f"parts {report['parts']}  missed {report['missed']}")
    if a.out:
        with open(a.out, "w") as f:
            json.dump(report, f, indent=1)
    if a.list_failures:
        write_failures(a.list_failures, report)
    return 0


if __name__ == "__main__":
    sys.exit(main())
