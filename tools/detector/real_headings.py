#!/usr/bin/python3
"""Driving-direction labels for real vehicles that carry none, from their neighbours or motion.

Real images with axis-aligned labels (the CATS Madison set: frames of hovering drone videos,
``0_13.jpg``, ``0_14.jpg`` …, ``Drone2_(N).jpg``) carry no heading. Two sources of it:

* ``--method lane`` (default): vehicles that stand on one line along their common axis — a
  lane, a row of parked cars — drive (or face) the same way. A vehicle's label is the
  majority direction of its lane-mates in its own frame and in the frames of its clip within
  --lane-frames index steps (registered to it by phase correlation: the drone hovers, the
  camera drifts), each lane-mate voting with the direction the detector gave it. A label needs
  at least --min-votes votes and a share of at least --min-agreement; the vehicle's own vote
  is left out, so a vehicle the detector reverses against a lane that agrees is labelled
  against the detector. Lane-mates: centre within --max-across of the vehicle's width from its
  axis line, axis within --max-axis-deg, at most --lane-length-m along it.
* ``--method motion``: a vehicle that moves between neighbouring frames of a clip (index gap
  <= --max-gap; camera drift taken out by phase correlation) shows its direction: candidates on
  its axis line within --max-step-m per index step, none standing (< --min-step-m), all on one
  side, the frame before and the frame after agreeing. Needs frames close in time (video);
  CATS Madison's frames are seconds apart (the nearest vehicle in the next frame is 80 px away
  at the median for index gaps 1, 2 and 3 alike), so this method labels almost nothing there.

Vehicles are the detections of ``vp_detect_images --images ROOT`` (their rotated box gives the
axis, their angle the vote) that match a label (IoU of the detection's enclosing box >= 0.5);
with ``--boxes-from labels`` on a rotated-label folder (``bev-intersection-de``) the labelled
boxes themselves, to measure how often this tool's labels agree with known headings: the
labelled headings are then the votes, and --flip-votes P reverses a random share P of them
first (as a detector that reverses P of the vehicles would vote).

``--judge CSV...`` scores other runs against the labels made here: detections of the same images
whose boxes are those of ``--detections`` (another crop network behind the same first stage, whose
front/back alone differs); each prints how many labelled vehicles it shows reversed. Labels made
from one run's boxes and votes and judged on another's front/back keep the comparison on one fixed
set of labels (that run's own reversals are ``det_reversed``).

Writes a CSV with the columns of mine_negatives.py's lists (image, cx_px, cy_px, score,
length_px, width_px, angle_rad, gsd_m, label = 1), where angle_rad is the box axis turned to
the label's direction — what ``train.py --heading-samples FILE`` trains the crop network's
front/back output on — plus ``det_reversed``: whether the detector's own angle pointed the
other way.

  tools/detector/real_headings.py --root ../shared/data/real/cats-madison \
      --detections cats_all.csv --gsd-m 0.047 [--list split.json --side train] --out headings.csv

Run with Debian's Python (/usr/bin/python3).
"""
from __future__ import annotations

import argparse
import collections
import csv
import json
import math
import os
import sys
from typing import Dict, List, Optional, Tuple

import cv2
import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from detector.datasets import DatasetError, clip_and_index, file_stem, read_yolo  # noqa: E402
from detector.geometry import axis_angle_difference  # noqa: E402
from detector.mine_negatives import (aa_iou, enclosing_box, read_detections,  # noqa: E402
                                     yolo_pixel_boxes)

COLUMNS = ["image", "cx_px", "cy_px", "score", "length_px", "width_px", "angle_rad", "gsd_m",
           "label", "det_reversed"]


def camera_shift(a: np.ndarray, b: np.ndarray) -> Tuple[np.ndarray, float]:
    """Image translation (du, dv) that maps frame ``a``'s background onto frame ``b``, and the
    phase correlation's peak response (low: the frames hardly overlap)."""
    ga = cv2.cvtColor(cv2.pyrDown(a), cv2.COLOR_BGR2GRAY).astype(np.float32)
    gb = cv2.cvtColor(cv2.pyrDown(b), cv2.COLOR_BGR2GRAY).astype(np.float32)
    if ga.shape != gb.shape:
        return np.zeros(2), 0.0
    win = cv2.createHanningWindow(ga.shape[::-1], cv2.CV_32F)
    (du, dv), response = cv2.phaseCorrelate(ga, gb, win)
    return 2.0 * np.array([du, dv]), float(response)


def step_sign(box: np.ndarray, others: np.ndarray, shift: np.ndarray, gap: int, gsd_m: float,
              opts) -> int:
    """+1: the vehicle's successor lies ahead along the box's angle, -1 behind, 0: none, standing
    or ambiguous. ``others``: [M, 5] boxes of the other frame; ``shift``: camera drift from this
    frame to the other; ``gap``: signed frame index difference (other - this)."""
    if not len(others):
        return 0
    axis = np.array([math.cos(box[4]), math.sin(box[4])])
    d = others[:, :2] - shift[None] - box[None, :2]
    along = d @ axis
    across = np.abs(d[:, 0] * axis[1] - d[:, 1] * axis[0])
    axis_ok = np.degrees(axis_angle_difference(others[:, 4], box[4])) <= opts.max_axis_deg
    near = (across <= opts.max_across * box[3]) & axis_ok
    near &= np.abs(along) * gsd_m <= opts.max_step_m * abs(gap)
    if not near.any():
        return 0
    if (np.abs(along[near]) * gsd_m < opts.min_step_m * abs(gap)).any():
        return 0  # standing (or too slow to tell)
    ahead, behind = (along[near] > 0).any(), (along[near] < 0).any()
    if ahead == behind:
        return 0
    s = 1 if ahead else -1
    return s if gap > 0 else -s


def vehicles_of(stem: str, image_shape, dets: Dict, yolo_boxes: np.ndarray) -> np.ndarray:
    """[N, 6] (cx, cy, length, width, angle, score): the detections of one image that match an
    axis-aligned label (enclosing-box IoU >= 0.5; each label once, best score first)."""
    h, w = image_shape[:2]
    labels = yolo_pixel_boxes(yolo_boxes, w, h)
    out, used = [], set()
    for score, b in sorted(dets.get(stem, []), key=lambda x: -x[0]):
        iou = aa_iou(enclosing_box(b, w, h), labels)
        j = int(np.argmax(iou)) if len(iou) else -1
        if j >= 0 and iou[j] >= 0.5 and j not in used:
            used.add(j)
            out.append([*b, score])
    return np.asarray(out, np.float64).reshape(-1, 6)


class ImageCache:
    """The last few frames read (the methods walk clips in order)."""

    def __init__(self, capacity: int = 16):
        self.capacity, self.images = capacity, collections.OrderedDict()

    def __call__(self, f: dict) -> np.ndarray:
        path = f["path"]
        if path in self.images:
            self.images.move_to_end(path)
            return self.images[path]
        img = cv2.imread(path, cv2.IMREAD_COLOR)
        if img is None:
            raise DatasetError(f"{path}: cannot read image")
        self.images[path] = img
        while len(self.images) > self.capacity:
            self.images.popitem(last=False)
        return img


def clips_of(frames: List[dict]) -> Dict[str, List[dict]]:
    by_clip = collections.defaultdict(list)
    for f in frames:
        by_clip[f["clip"]].append(f)
    for seq in by_clip.values():
        seq.sort(key=lambda f: f["index"])
    return by_clip


def label_motion(frames: List[dict], gsd_m: float, opts) -> List[dict]:
    """Motion labels for the vehicles of ``frames`` (dicts with stem, path, clip, index,
    vehicles [N, 6]: box and score, votes [N]: angle each vehicle votes with); one dict per
    labelled vehicle."""
    by_clip = clips_of(frames)
    image = ImageCache()
    out = []
    for clip, seq in sorted(by_clip.items()):
        for k, f in enumerate(seq):
            prev = seq[k - 1] if k > 0 and 0 < f["index"] - seq[k - 1]["index"] <= opts.max_gap else None
            nxt = seq[k + 1] if k + 1 < len(seq) and 0 < seq[k + 1]["index"] - f["index"] <= opts.max_gap else None
            if prev is None or nxt is None or not len(f["vehicles"]):
                continue
            shift_p = camera_shift(image(f), image(prev))[0]
            shift_n = camera_shift(image(f), image(nxt))[0]
            for i, v in enumerate(f["vehicles"]):
                sp = step_sign(v[:5], prev["vehicles"][:, :5], shift_p, prev["index"] - f["index"],
                               gsd_m, opts)
                sn = step_sign(v[:5], nxt["vehicles"][:, :5], shift_n, nxt["index"] - f["index"],
                               gsd_m, opts)
                if sp == 0 or sp != sn:
                    continue
                out.append(labelled(f, i, sp < 0))
    return out


def labelled(f: dict, i: int, against_box: bool) -> dict:
    """The row of vehicle ``i`` of frame ``f`` labelled with its box angle, turned by pi when
    ``against_box``; ``det_reversed``: its own vote points the other way than the label."""
    v = f["vehicles"][i]
    angle = float((v[4] + math.pi) % (2 * math.pi)) if against_box else float(v[4])
    return {"stem": f["stem"], "path": f["path"], "box": v[:5].copy(), "angle": angle,
            "score": float(v[5]), "against_box": int(against_box),
            "det_reversed": int(math.cos(f["votes"][i] - angle) < 0)}


def lane_votes(v: np.ndarray, others: np.ndarray, others_votes: np.ndarray, gsd_m: float, opts,
               skip_same: bool) -> np.ndarray:
    """+1 / -1 per lane-mate of box ``v`` among ``others`` (boxes in v's frame's pixels):
    whether its vote angle points along v's angle or against it. ``skip_same``: leave out
    boxes that overlap v along its axis (the same vehicle seen in another frame)."""
    if not len(others):
        return np.zeros(0)
    axis = np.array([math.cos(v[4]), math.sin(v[4])])
    d = others[:, :2] - v[None, :2]
    along = d @ axis
    across = np.abs(d[:, 0] * axis[1] - d[:, 1] * axis[0])
    ok = (across <= opts.max_across * v[3]) & (np.abs(along) * gsd_m <= opts.lane_length_m)
    ok &= np.degrees(axis_angle_difference(others[:, 4], v[4])) <= opts.max_axis_deg
    if skip_same:
        ok &= np.abs(along) > 0.5 * v[2]
    return np.where(np.cos(others_votes[ok] - v[4]) >= 0, 1.0, -1.0)


def label_lanes(frames: List[dict], gsd_m: float, opts) -> List[dict]:
    """Lane-vote labels for the vehicles of ``frames`` (see label_motion for the dicts)."""
    image = ImageCache(capacity=4 * opts.lane_frames + 4)
    out = []
    for clip, seq in sorted(clips_of(frames).items()):
        for k, f in enumerate(seq):
            if not len(f["vehicles"]):
                continue
            mates = []  # (boxes in f's pixels, votes, same frame?)
            for g in seq:
                if g is f or abs(g["index"] - f["index"]) > opts.lane_frames or not len(g["vehicles"]):
                    continue
                shift, response = camera_shift(image(f), image(g))
                if response < opts.min_response:
                    continue
                boxes = g["vehicles"][:, :5].copy()
                boxes[:, :2] -= shift[None]
                mates.append((boxes, g["votes"]))
            for i, v in enumerate(f["vehicles"]):
                own = np.arange(len(f["vehicles"])) != i
                votes = [lane_votes(v[:5], f["vehicles"][own, :5], f["votes"][own], gsd_m, opts, False)]
                votes += [lane_votes(v[:5], b, vt, gsd_m, opts, True) for b, vt in mates]
                votes = np.concatenate(votes)
                if len(votes) < opts.min_votes:
                    continue
                agree = float((votes > 0).mean())
                if agree >= opts.min_agreement:
                    out.append(labelled(f, i, False))
                elif 1.0 - agree >= opts.min_agreement:
                    out.append(labelled(f, i, True))
    return out


JUDGE_MATCH_PX = 3.0


def judge(rows: List[dict], path: str) -> Tuple[int, int, int]:
    """(matched, reversed, unmatched) of the labelled vehicles in another detections file: the
    detection of the same image whose centre is nearest the label's box centre, within
    JUDGE_MATCH_PX, counts as reversed when its angle is more than 90 degrees from the label."""
    dets = read_detections(path, key="image")
    matched = reversed_ = unmatched = 0
    for r in rows:
        best = None
        for _, box in dets.get(r["stem"], []):
            d = math.hypot(box[0] - r["box"][0], box[1] - r["box"][1])
            if d <= JUDGE_MATCH_PX and (best is None or d < best[0]):
                best = (d, box[4])
        if best is None:
            unmatched += 1
            continue
        matched += 1
        reversed_ += int(math.cos(best[1] - r["angle"]) < 0)
    return matched, reversed_, unmatched


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--root", required=True, help="folder with images/ and labels/")
    p.add_argument("--method", choices=["lane", "motion"], default="lane")
    p.add_argument("--detections", default=None, help="vp_detect_images --images CSV of ROOT")
    p.add_argument("--boxes-from", choices=["detections", "labels"], default="detections",
                   help="labels: the rotated labels (class cx cy length width heading) are the "
                        "vehicles, and the labels made are checked against their heading")
    p.add_argument("--flip-votes", type=float, default=0.0,
                   help="with --boxes-from labels: reverse this random share of the votes")
    p.add_argument("--seed", type=int, default=0, help="of --flip-votes")
    p.add_argument("--gsd-m", type=float, required=True, help="metres per pixel of the images")
    p.add_argument("--list", default=None, help="split JSON (split_real.py) ...")
    p.add_argument("--side", choices=["train", "val"], default="train",
                   help="... use its train_stems or val_stems")
    p.add_argument("--max-across", type=float, default=0.5,
                   help="largest offset across the axis, in vehicle widths")
    p.add_argument("--max-axis-deg", type=float, default=15.0, help="largest axis difference")
    p.add_argument("--lane-frames", type=int, default=3, help="lane: frames either side used")
    p.add_argument("--lane-length-m", type=float, default=60.0, help="lane: farthest lane-mate")
    p.add_argument("--min-votes", type=int, default=3, help="lane: fewest votes for a label")
    p.add_argument("--min-agreement", type=float, default=0.8, help="lane: least share agreeing")
    p.add_argument("--min-response", type=float, default=0.05,
                   help="lane: least phase-correlation response for a frame to be registered")
    p.add_argument("--max-gap", type=int, default=2, help="motion: largest frame index step")
    p.add_argument("--max-step-m", type=float, default=16.0, help="motion: most per index step")
    p.add_argument("--min-step-m", type=float, default=0.6, help="motion: less per step is standing")
    p.add_argument("--out", default=None, help="CSV of the labelled vehicles")
    p.add_argument("--judge", nargs="+", default=[], metavar="CSV",
                   help="detections of other runs on the same images whose boxes are those of "
                        "--detections (another crop network behind the same first stage): each "
                        "is scored against the labels made here, box centre within "
                        f"{JUDGE_MATCH_PX:g} px")
    a = p.parse_args(argv)
    if not a.gsd_m > 0:
        p.error("--gsd-m must be > 0")
    if not 0.5 < a.min_agreement <= 1:
        p.error("--min-agreement must be in (0.5, 1]")
    if a.boxes_from == "detections" and not a.detections:
        p.error("--detections is required unless --boxes-from labels")
    try:
        stems = None
        if a.list:
            with open(a.list) as f:
                split = json.load(f)
            key = f"{a.side}_stems"
            if key not in split:
                raise DatasetError(f"{a.list}: no '{key}'")
            stems = set(split[key])
        frames = []
        if a.boxes_from == "labels":
            from detector.eval_rotated_real import read_rotated_labels

            rng = np.random.default_rng(a.seed)
            for stem, boxes in read_rotated_labels(a.root).items():
                if stems is not None and stem not in stems:
                    continue
                clip, idx = clip_and_index(stem)
                votes = boxes[:, 4] + np.where(rng.random(len(boxes)) < a.flip_votes, math.pi, 0.0)
                frames.append({"stem": stem, "path": os.path.join(a.root, "images", stem + ".jpg"),
                               "clip": clip, "index": idx, "votes": votes,
                               "vehicles": np.hstack([boxes, np.ones((len(boxes), 1))])})
        else:
            dets = read_detections(a.detections, key="image")
            for s in read_yolo(a.root):
                stem = file_stem(s.image_path)
                if stems is not None and stem not in stems:
                    continue
                clip, idx = clip_and_index(stem)
                h, w = cv2.imread(s.image_path, cv2.IMREAD_REDUCED_GRAYSCALE_8).shape[:2]
                vehicles = vehicles_of(stem, (h * 8, w * 8), dets, s.boxes)
                frames.append({"stem": stem, "path": os.path.abspath(s.image_path), "clip": clip,
                               "index": idx, "vehicles": vehicles, "votes": vehicles[:, 4].copy()})
        rows = (label_lanes if a.method == "lane" else label_motion)(frames, a.gsd_m, a)
    except (DatasetError, OSError, json.JSONDecodeError) as e:
        print(f"real_headings.py: {e}", file=sys.stderr)
        return 1
    n_vehicles = sum(len(f["vehicles"]) for f in frames)
    rev = sum(r["det_reversed"] for r in rows)
    print(f"{len(frames)} frames, {n_vehicles} vehicles, {len(rows)} labelled ({a.method}); "
          f"their own vote reversed on {rev} ({100 * rev / max(1, len(rows)):.1f} %)")
    if a.boxes_from == "labels":
        wrong = sum(r["against_box"] for r in rows)  # the box angle is the labelled heading
        print(f"check: the label made disagrees with the labelled heading on {wrong} of "
              f"{len(rows)} ({100 * wrong / max(1, len(rows)):.1f} %)")
    for path in a.judge:
        try:
            matched, rev_j, unmatched = judge(rows, path)
        except (DatasetError, OSError) as e:
            print(f"real_headings.py: {e}", file=sys.stderr)
            return 1
        print(f"{path}: reversed on {rev_j} of {matched} labelled vehicles matched "
              f"({100 * rev_j / max(1, matched):.1f} %), {unmatched} not matched")
    if a.out:
        with open(a.out, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(COLUMNS)
            for r in rows:
                b = r["box"]
                w.writerow([r["path"], b[0], b[1], r["score"], b[2], b[3], r["angle"], a.gsd_m, 1,
                            r["det_reversed"]])
    return 0


if __name__ == "__main__":
    sys.exit(main())
