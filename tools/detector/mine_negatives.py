#!/usr/bin/python3
"""Hard negatives for the detector's training: where a trained detector fires on background.

Reads recorded sequences and the detections a detector made on them (the CSV that
`vp_detect_images --sequence DIR --out FILE` writes, one file per sequence) and lists every
detection with score >= --min-score that overlaps no ground-truth vehicle — not even one the
training ignores (occluded or cut by the border) — with rotated IoU >= --max-iou. The list
(CSV: image, cx_px, cy_px, score; the image path as the sequence's frames.csv names it, made
absolute) is what `train.py --hard-negatives FILE --negative-share P` centres a share of its
tiles on, so that the first stage sees the shadows, road marks and roof fixtures it mistook for
vehicles more often than uniform tiles show them.

  tools/detector/mine_negatives.py --data SEQ_DIR... --detections DIR --out negatives.csv

DIR holds <sequence name>.csv for each sequence (its folder's basename). Run with Debian's
Python (/usr/bin/python3).
"""
from __future__ import annotations

import argparse
import csv
import os
import sys
from typing import Dict, List, Tuple

import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from detector.datasets import DatasetError, read_sequence  # noqa: E402
from detector.geometry import rotated_iou_matrix  # noqa: E402

DETECTION_COLUMNS = ["frame_id", "score", "box_cx_px", "box_cy_px", "box_length_px",
                     "box_width_px", "box_angle_rad"]


def read_detections(path: str) -> Dict[int, List[Tuple[float, np.ndarray]]]:
    """Per frame id: (score, box [cx, cy, length, width, angle]) of each detection in a
    vp_detect_images CSV (comment lines start with '#')."""
    with open(path, newline="") as f:
        rows = [line for line in f if not line.startswith("#")]
    reader = csv.DictReader(rows)
    missing = [c for c in DETECTION_COLUMNS if c not in (reader.fieldnames or [])]
    if missing:
        raise DatasetError(f"{path}: not a detections CSV (no column {', '.join(missing)})")
    out: Dict[int, List[Tuple[float, np.ndarray]]] = {}
    for line, r in enumerate(reader, start=2):
        try:
            box = np.array([float(r[c]) for c in DETECTION_COLUMNS[2:]], np.float64)
            fid, score = int(r["frame_id"]), float(r["score"])
        except ValueError as e:
            raise DatasetError(f"{path}: row {line}: {e}") from None
        out.setdefault(fid, []).append((score, box))
    return out


def mine(seq_dirs: List[str], det_dir: str, min_score: float, max_iou: float):
    """Rows (image, cx, cy, score) of the false detections and a count per sequence."""
    rows, counts = [], {}
    for seq in seq_dirs:
        name = os.path.basename(os.path.normpath(seq))
        det_path = os.path.join(det_dir, name + ".csv")
        if not os.path.isfile(det_path):
            raise DatasetError(f"{det_path}: no detections for sequence {seq}")
        dets = read_detections(det_path)
        # Every vehicle counts here, ignored ones too: a box on a half-hidden car is no
        # background to learn.
        samples = read_sequence(seq, max_occlusion=1.0, max_truncation=1.0)
        n = 0
        for s in samples:
            found = [(sc, b) for sc, b in dets.get(s.frame_index, []) if sc >= min_score]
            if not found:
                continue
            boxes = np.stack([b for _, b in found])
            iou = (rotated_iou_matrix(boxes, s.boxes).max(axis=1) if len(s)
                   else np.zeros(len(found)))
            for (sc, b), best in zip(found, iou):
                if best < max_iou:
                    rows.append((os.path.abspath(s.image_path), float(b[0]), float(b[1]), sc))
                    n += 1
        counts[name] = n
    return rows, counts


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--data", nargs="+", required=True, help="recorded sequence directories")
    p.add_argument("--detections", required=True,
                   help="folder of <sequence name>.csv files written by vp_detect_images")
    p.add_argument("--out", required=True, help="negatives CSV to write")
    p.add_argument("--min-score", type=float, default=0.4,
                   help="detections from this score count (the tracker's births start at 0.45)")
    p.add_argument("--max-iou", type=float, default=0.1,
                   help="a detection overlapping a vehicle this much or more is no negative")
    a = p.parse_args(argv)
    if not 0.0 <= a.min_score <= 1.0 or not 0.0 < a.max_iou <= 1.0:
        p.error("--min-score must be in [0, 1] and --max-iou in (0, 1]")
    try:
        rows, counts = mine(a.data, a.detections, a.min_score, a.max_iou)
    except (DatasetError, OSError) as e:
        print(f"mine_negatives.py: {e}", file=sys.stderr)
        return 1
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    with open(a.out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["image", "cx_px", "cy_px", "score"])
        for image, cx, cy, score in rows:
            w.writerow([image, f"{cx:.1f}", f"{cy:.1f}", f"{score:.4f}"])
    frames = len({r[0] for r in rows})
    print(f"mine_negatives.py: {len(rows)} false detections in {frames} frames of "
          f"{sum(1 for c in counts.values() if c)} of {len(counts)} sequences -> {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
