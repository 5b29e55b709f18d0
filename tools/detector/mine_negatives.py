#!/usr/bin/python3
"""Hard negatives for the detector's training: where a trained detector fires on background.

Reads recorded sequences and the detections a detector made on them (the CSV that
`vp_detect_images --sequence DIR --out FILE` writes, one file per sequence) and lists every
detection with score >= --min-score that overlaps no ground-truth vehicle — not even one the
training ignores (occluded or cut by the border) — with rotated IoU >= --max-iou. The list
(CSV: image, cx_px, cy_px, score; the image path as the sequence's frames.csv names it, made
absolute) is what `train.py --hard-negatives FILE --negative-share P` centres a share of its
tiles on, so that the first stage sees the shadows, road marks and roof fixtures it mistook for
vehicles more often than uniform tiles show them. Each row also carries the detected box
(length_px, width_px, angle_rad), the ground sample distance the crop network would cut it at
(gsd_m: the frame's median vehicle GSD; real images: --gsd-m) and a label (0: background), so
that `train.py --verifier-samples FILE` can teach the crop network's verifier head the same
mistakes at 6 cm per pixel.

  tools/detector/mine_negatives.py --data SEQ_DIR... --detections DIR --out negatives.csv
  tools/detector/mine_negatives.py --data SEQ_DIR... --detections DIR --by-kind --out neg.csv
      (also prints what the false detections lie on: benches, shelters ... motorbikes,
      bicycles, pedestrians, as the simulator lists them in ground_truth/furniture.csv)
  tools/detector/mine_negatives.py --images ROOT --list STEMS --detections FILE --gsd-m G \
      --positives --out real_samples.csv
  tools/detector/mine_negatives.py --data SEQ_DIR... --furniture --out furniture.csv

DIR holds <sequence name>.csv for each sequence (its folder's basename). With --images (a
folder of images/ and YOLO labels/, as ../shared/data/real/cats-madison) FILE is one
`vp_detect_images --images ROOT` CSV; a detection's axis-aligned enclosing box, clipped to the
image as the labels are, is compared with the labels (IoU), and --positives also lists the
detections that match a label (IoU >= 0.5) with label 1: real vehicles as the first stage boxes
them, so that the verifier does not learn "real image = background". Run with Debian's Python
(/usr/bin/python3).
"""
from __future__ import annotations

import argparse
import csv
import math
import os
import sys
from typing import Dict, List, Tuple

import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from detector.datasets import DatasetError, file_stem, read_sequence, read_yolo  # noqa: E402
from detector.geometry import rotated_iou_matrix  # noqa: E402

DETECTION_COLUMNS = ["score", "box_cx_px", "box_cy_px", "box_length_px", "box_width_px",
                     "box_angle_rad"]
OUT_COLUMNS = ["image", "cx_px", "cy_px", "score", "length_px", "width_px", "angle_rad", "gsd_m",
               "label"]


def read_detections(path: str, key: str = "frame_id") -> Dict:
    """Per frame id (or per ``key`` column, e.g. "image") : (score, box [cx, cy, length, width,
    angle]) of each detection in a vp_detect_images CSV (comment lines start with '#')."""
    with open(path, newline="") as f:
        rows = [line for line in f if not line.startswith("#")]
    reader = csv.DictReader(rows)
    missing = [c for c in [key] + DETECTION_COLUMNS if c not in (reader.fieldnames or [])]
    if missing:
        raise DatasetError(f"{path}: not a detections CSV (no column {', '.join(missing)})")
    out: Dict = {}
    for line, r in enumerate(reader, start=2):
        try:
            box = np.array([float(r[c]) for c in DETECTION_COLUMNS[1:]], np.float64)
            fid = int(r[key]) if key == "frame_id" else r[key]
            score = float(r["score"])
        except ValueError as e:
            raise DatasetError(f"{path}: row {line}: {e}") from None
        out.setdefault(fid, []).append((score, box))
    return out


def enclosing_box(box: np.ndarray, width: int, height: int) -> np.ndarray:
    """Axis-aligned box [x0, y0, x1, y1] around a rotated one, clipped to the image."""
    c, s = abs(math.cos(box[4])), abs(math.sin(box[4]))
    hw, hh = 0.5 * (box[2] * c + box[3] * s), 0.5 * (box[2] * s + box[3] * c)
    return np.array([max(box[0] - hw, -0.5), max(box[1] - hh, -0.5),
                     min(box[0] + hw, width - 0.5), min(box[1] + hh, height - 0.5)])


def yolo_pixel_boxes(boxes: np.ndarray, width: int, height: int) -> np.ndarray:
    """[N, 4] pixel boxes [x0, y0, x1, y1] of read_yolo's normalised (cx, cy, w, h, ...) rows."""
    return np.array([[(cx - bw / 2) * width - 0.5, (cy - bh / 2) * height - 0.5,
                      (cx + bw / 2) * width - 0.5, (cy + bh / 2) * height - 0.5]
                     for cx, cy, bw, bh, *_ in boxes]).reshape(-1, 4)


def aa_iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """IoU of one box [x0, y0, x1, y1] with each row of ``b``."""
    if not len(b):
        return np.zeros(0)
    ix = np.clip(np.minimum(a[2], b[:, 2]) - np.maximum(a[0], b[:, 0]), 0, None)
    iy = np.clip(np.minimum(a[3], b[:, 3]) - np.maximum(a[1], b[:, 1]), 0, None)
    inter = ix * iy
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[:, 2] - b[:, 0]) * (b[:, 3] - b[:, 1]) - inter
    return np.where(union > 0, inter / np.maximum(union, 1e-9), 0.0)


def mine_images(root: str, det_path: str, stems, gsd_m: float, min_score: float, max_iou: float,
                positives: bool):
    """Rows of OUT_COLUMNS for the images of a YOLO folder: detections overlapping no label
    (label 0) and, with ``positives``, those matching one with IoU >= 0.5 (label 1)."""
    dets = read_detections(det_path, key="image")
    rows, counts = [], {}
    for s in read_yolo(root):
        stem = file_stem(s.image_path)
        if stems is not None and stem not in stems:
            continue
        found = [(sc, b) for sc, b in dets.get(stem, []) if sc >= min_score]
        if not found:
            continue
        h, w = s.loaded().image.shape[:2]
        labels = yolo_pixel_boxes(s.boxes, w, h)
        n = 0
        for sc, b in found:
            best = aa_iou(enclosing_box(b, w, h), labels).max(initial=0.0)
            label = 0 if best < max_iou else (1 if positives and best >= 0.5 else -1)
            if label >= 0:
                rows.append((os.path.abspath(s.image_path), *b[:2], sc, *b[2:], gsd_m, label))
                n += label == 0
        counts[stem] = n
    return rows, counts


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
            gsd = float(np.nanmedian(s.gsd_m)) if np.isfinite(s.gsd_m).any() else math.nan
            for (sc, b), best in zip(found, iou):
                if best < max_iou:
                    rows.append((os.path.abspath(s.image_path), *b[:2], sc, *b[2:], gsd, 0))
                    n += 1
        counts[name] = n
    return rows, counts


def read_furniture(seq: str) -> Dict[int, List[Tuple]]:
    """Per frame id: (kind, cx, cy, length, width, angle, visible_px) of each item of the street
    furniture the simulator listed in view (ground_truth/furniture.csv)."""
    path = os.path.join(seq, "ground_truth", "furniture.csv")
    if not os.path.isfile(path):
        raise DatasetError(f"{path}: no furniture list (render the sequence with a "
                           "vp_simulate that writes it)")
    by_frame: Dict[int, List[Tuple]] = {}
    with open(path, newline="") as f:
        for line_no, r in enumerate(csv.DictReader(f), start=2):
            try:
                by_frame.setdefault(int(r["frame_id"]), []).append(
                    (r["kind"], float(r["cx_px"]), float(r["cy_px"]), float(r["length_px"]),
                     float(r["width_px"]), float(r["angle_rad"]), int(r["visible_px"])))
            except (KeyError, ValueError, TypeError):
                raise DatasetError(f"{path}:{line_no}: not a furniture row") from None
    return by_frame


def furniture_samples(seq_dirs: List[str], min_visible_px: int, max_iou: float):
    """Background rows for the street furniture the simulator lists in view
    (ground_truth/furniture.csv: benches, shelters, kiosks, stair entrances): a car-sized box
    (at least 4.6 x 1.9 m at the frame's vehicle GSD) centred on each item with at least
    min_visible_px visible pixels and overlapping no vehicle — what the first stage boxes when
    it mistakes one for a car, so that the verifier learns to refuse them."""
    rows, counts = [], {}
    for seq in seq_dirs:
        name = os.path.basename(os.path.normpath(seq))
        by_frame = read_furniture(seq)
        samples = read_sequence(seq, max_occlusion=1.0, max_truncation=1.0)
        n = 0
        for s in samples:
            items = [it[1:] for it in by_frame.get(s.frame_index, []) if it[6] >= min_visible_px]
            if not items:
                continue
            gsd = float(np.nanmedian(s.gsd_m)) if np.isfinite(s.gsd_m).any() else math.nan
            if not math.isfinite(gsd):
                continue
            boxes = np.array([[cx, cy, max(length, 4.6 / gsd), max(width, 1.9 / gsd), angle]
                              for cx, cy, length, width, angle, _ in items])
            iou = (rotated_iou_matrix(boxes, s.boxes).max(axis=1) if len(s)
                   else np.zeros(len(boxes)))
            for b, best in zip(boxes, iou):
                if best < max_iou:
                    rows.append((os.path.abspath(s.image_path), b[0], b[1], 1.0, *b[2:], gsd, 0))
                    n += 1
        counts[name] = n
    return rows, counts


def false_boxes_by_kind(seq_dirs: List[str], rows, min_visible_px: int) -> Dict[str, List[int]]:
    """What the false detections of ``mine`` lie on: per furniture kind [item-frames in view
    with at least min_visible_px pixels, false detections whose centre lies inside such an
    item's image box]; the kind "(elsewhere)" holds the rest. A sequence without a furniture
    list counts every false detection as elsewhere."""
    out: Dict[str, List[int]] = {}
    for seq in seq_dirs:
        path = os.path.join(seq, "ground_truth", "furniture.csv")
        by_frame = read_furniture(seq) if os.path.isfile(path) else {}
        frame_of = {os.path.abspath(s.image_path): s.frame_index
                    for s in read_sequence(seq, max_occlusion=1.0, max_truncation=1.0)}
        for items in by_frame.values():
            for it in items:
                if it[6] >= min_visible_px:
                    out.setdefault(it[0], [0, 0])[0] += 1
        for image, cx, cy, *_ in rows:
            if image not in frame_of:
                continue
            kind = "(elsewhere)"
            for k, icx, icy, length, width, angle, visible in by_frame.get(frame_of[image], []):
                c, s_ = math.cos(angle), math.sin(angle)
                dx, dy = cx - icx, cy - icy
                if (visible >= min_visible_px and abs(dx * c + dy * s_) <= 0.5 * length
                        and abs(-dx * s_ + dy * c) <= 0.5 * width):
                    kind = k
                    break
            out.setdefault(kind, [0, 0])[1] += 1
    return out


def read_stems(path: str, key: str = "train_stems"):
    """Image stems from a text file (one per line) or a split JSON (its ``key`` list:
    train_stems, or val_stems for the held-out images)."""
    import json

    with open(path) as f:
        text = f.read()
    if path.endswith(".json"):
        try:
            return set(json.loads(text)[key])
        except (ValueError, KeyError):
            raise DatasetError(f"{path}: not a split JSON with {key}") from None
    return {line.strip() for line in text.splitlines() if line.strip()}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--data", nargs="+", help="recorded sequence directories")
    src.add_argument("--images", help="a folder of images/ and YOLO labels/ (real images)")
    p.add_argument("--furniture", action="store_true",
                   help="--data: instead of detections, list the street furniture the simulator "
                        "recorded in view (ground_truth/furniture.csv) as background boxes")
    p.add_argument("--min-visible-px", type=int, default=60,
                   help="--furniture, --by-kind: items with fewer visible pixels are left out")
    p.add_argument("--by-kind", action="store_true",
                   help="--data with --detections: also print what the false detections lie on, "
                        "per kind of listed furniture (benches ... motorbikes, bicycles, "
                        "pedestrians), beside the number of item-frames in view")
    p.add_argument("--detections",
                   help="--data: folder of <sequence name>.csv files written by vp_detect_images; "
                        "--images: that tool's one CSV for the folder")
    p.add_argument("--list", help="--images: only these images (one stem per line, or a split "
                                  "JSON's train_stems)")
    p.add_argument("--gsd-m", type=float, default=math.nan,
                   help="--images: ground sample distance the detections were cropped at, m/px")
    p.add_argument("--positives", action="store_true",
                   help="--images: also list detections matching a label (label 1)")
    p.add_argument("--out", required=True, help="negatives CSV to write")
    p.add_argument("--min-score", type=float, default=0.4,
                   help="detections from this score count (the tracker's births start at 0.45)")
    p.add_argument("--max-iou", type=float, default=0.1,
                   help="a detection overlapping a vehicle this much or more is no negative")
    a = p.parse_args(argv)
    if not 0.0 <= a.min_score <= 1.0 or not 0.0 < a.max_iou <= 1.0:
        p.error("--min-score must be in [0, 1] and --max-iou in (0, 1]")
    if a.furniture and a.images:
        p.error("--furniture goes with --data (simulated sequences)")
    if a.by_kind and (a.images or a.furniture):
        p.error("--by-kind goes with --data and --detections")
    if not a.furniture and not a.detections:
        p.error("--detections is required (except with --furniture)")
    if a.images and not (a.gsd_m > 0):
        p.error("--images needs --gsd-m > 0 (the GSD the detections were cropped at)")
    try:
        if a.images:
            stems = read_stems(a.list) if a.list else None
            rows, counts = mine_images(a.images, a.detections, stems, a.gsd_m, a.min_score,
                                       a.max_iou, a.positives)
        elif a.furniture:
            rows, counts = furniture_samples(a.data, a.min_visible_px, a.max_iou)
        else:
            rows, counts = mine(a.data, a.detections, a.min_score, a.max_iou)
            kinds = false_boxes_by_kind(a.data, rows, a.min_visible_px) if a.by_kind else {}
    except (DatasetError, OSError) as e:
        print(f"mine_negatives.py: {e}", file=sys.stderr)
        return 1
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    with open(a.out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(OUT_COLUMNS)
        for image, cx, cy, score, length, width, angle, gsd, label in rows:
            w.writerow([image, f"{cx:.1f}", f"{cy:.1f}", f"{score:.4f}", f"{length:.1f}",
                        f"{width:.1f}", f"{angle:.4f}", f"{gsd:.5f}", label])
    negatives = [r for r in rows if r[-1] == 0]
    frames = len({r[0] for r in negatives})
    what = "furniture boxes" if a.furniture else "false detections"
    print(f"mine_negatives.py: {len(negatives)} {what} in {frames} frames of "
          f"{sum(1 for c in counts.values() if c)} of {len(counts)} "
          f"{'images' if a.images else 'sequences'}"
          + (f", {len(rows) - len(negatives)} matched ones" if a.positives else "") + f" -> {a.out}")
    if a.by_kind:
        print(f"{'on':<16} {'items in view':>13} {'false boxes':>11}")
        for kind, (items, boxes) in sorted(kinds.items(), key=lambda kv: kv[0] == "(elsewhere)"):
            print(f"{kind:<16} {items if kind != '(elsewhere)' else '':>13} {boxes:>11}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
