#!/usr/bin/python3
"""Trains the detector (and the second-stage crop classifier) on recorded sequences, real
axis-aligned images and DOTA-format data. Run with Debian's Python (/usr/bin/python3).

    tools/detector/train.py --data SEQDIR [SEQDIR ...] [--real DIR] [--dota DIR ...]
        --out RUNDIR [--epochs N] [--budget-minutes M] [--resume] [--shape-loss l1|l2]
        [--single-stage] [--val-data SEQDIR ...]

Contract
--------
* Inputs: ``--data`` recorded sequences (docs/recorded_sequence.md, simulator or field
  recordings with ground_truth/); ``--real`` a YOLO folder (images/, labels/; split without
  near-duplicates, datasets.split_near_duplicate_free, report in RUNDIR/split.json);
  ``--dota`` DOTA folders (images/, labelTxt/; heading unknown). A user trains on their own
  data with these flags only, no code change.
* Working scale: recorded frames are resized so their width becomes ``--working-width``
  (648 = 2592/4, what the application feeds the engine) times a +-15 % jitter; images without
  a camera model (real, DOTA) are resized to a working GSD drawn from
  ``--working-gsd-range`` (their GSD: the DOTA header, else estimated from the median box
  long side taken as a 4.5 m car). Training tiles are ``--tile`` px squares.
* Every step trains the Detector on a batch of tiles and (unless ``--no-crop``) the CropNet on
  a batch of jittered ground-truth crops (crops.py); losses in losses.py; the shape loss is
  V_L1 or V_L2 (``--shape-loss``). With ``--verifier-samples`` the CropNet gets its verifier
  head (vehicle or not): each crop batch adds ``--verifier-batch`` crops of mined boxes and of
  random vehicle-free places, which train that head only (``--verifier-head-only``: nothing
  else).
* Output (never inside the repository): RUNDIR/checkpoint.pt (every
  ``--checkpoint-minutes`` and at the end; atomic replace), RUNDIR/train_log.jsonl (losses),
  RUNDIR/split.json, RUNDIR/metrics.json (validation at the end), RUNDIR/args.json.
* ``--resume`` continues from RUNDIR/checkpoint.pt: models, optimisers, step, RNG states and
  the elapsed training time (``--budget-minutes`` is the total over all runs;
  ``--session-minutes`` ends one run earlier, checkpointed, so a long run can go in time slices).
  Runs are deterministic for a seed on one device and thread count (data sampling happens in
  the main process from one numpy Generator). ``--workers N`` makes the batches in N worker
  processes instead (for a GPU, which the main process alone cannot feed): each worker draws
  from its own Generator seeded by (seed, worker, step at start), so such runs are
  reproducible from their start but not batch-for-batch across a resume.
* ``--qat-from EXPORTDIR`` fine-tunes an export's first stage through int8 fake quantization
  instead (qat.py; the checkpoint holds that graph's weights; export with qat.py).
* CUDA is used when available (``--device auto``), else the CPU.
"""

from __future__ import annotations

import argparse
import collections
import csv
import json
import math
import os
import sys
import time
from typing import Dict, List, Optional, Sequence, Tuple

if __package__ in (None, ""):
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# OpenCV single-threaded, set before cv2 is first imported: the --workers processes are forked
# from this one, and pip's OpenCV (the GPU machine's) keeps a thread pool that does not survive
# a fork: the workers hung in their first cv2 call until this was set (round 5). The batches are
# made by the workers in parallel anyway.
os.environ.setdefault("OPENCV_FOR_THREADS_NUM", "1")

import numpy as np
import torch

from detector import augment, crops, targets
from detector.asm import DEFAULT_ASM_PATH, REPO_ROOT, load_asm
from detector.datasets import (LARGE, Sample, load_image, read_dota, read_sequence, read_yolo,
                               split_from_file, split_near_duplicate_free)
from detector.geometry import rotated_iou_matrix
from detector.losses import crop_loss, detector_loss, make_shape_loss
from detector.model import CropNet, Detector, normalize

CAR_LENGTH_M = 4.5


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--data", nargs="*", default=[], help="recorded sequence directories")
    p.add_argument("--real", default=None, help="YOLO folder (images/, labels/) of real images")
    p.add_argument("--split-seed", type=int, default=0,
                   help="seed of the near-duplicate-free real split (kept apart from --seed so that "
                        "every run holds out the same images; 0 is the model card's split)")
    p.add_argument("--real-split", default=None,
                   help="split JSON (split_real.py or a run's split.json): its val_stems are the "
                        "validation images, its train_stems the training images (without that "
                        "list: every other image in --real)")
    p.add_argument("--real-max", type=int, default=0, help="use at most N real training images (0: all)")
    p.add_argument("--real-val-max", type=int, default=0, help="evaluate at most N real validation images (0: all)")
    p.add_argument("--real-share", type=float, default=0.3, help="share of tiles from real images")
    p.add_argument("--dota", nargs="*", default=[], help="DOTA folders (images/, labelTxt/)")
    p.add_argument("--val-data", nargs="*", default=[], help="held-out recorded sequences")
    p.add_argument("--out", required=True, help="run directory (checkpoints, logs)")
    p.add_argument("--epochs", type=int, default=50)
    p.add_argument("--budget-minutes", type=float, default=60.0, help="total training time")
    p.add_argument("--checkpoint-minutes", type=float, default=10.0)
    p.add_argument("--resume", action="store_true")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--device", default="auto", help="auto, cpu, cuda")
    p.add_argument("--threads", type=int, default=2, help="torch CPU threads")
    p.add_argument("--batch", type=int, default=8)
    p.add_argument("--crop-batch", type=int, default=32)
    p.add_argument("--tile", type=int, default=256)
    p.add_argument("--lr", type=float, default=2e-3)
    p.add_argument("--warmup-steps", type=int, default=100)
    p.add_argument("--schedule", choices=["steps", "time"], default="steps",
                   help="cosine learning-rate decay over the planned steps, or over the time budget "
                        "(for CPU runs whose step count the budget decides; resumable)")
    p.add_argument("--hard-weight", type=float, default=1.0,
                   help="object-centred tiles pick hard vehicles (large, or occluded by at least "
                        "--hard-occlusion but not ignored) this many times as often as others")
    p.add_argument("--hard-occlusion", type=float, default=0.2,
                   help="occlusion share from which a vehicle counts as hard (--hard-weight)")
    p.add_argument("--hard-negatives", default=None,
                   help="CSV of false detections on training frames or real training images "
                        "(mine_negatives.py --data or --images): --negative-share of the tiles "
                        "of those frames are centred on one")
    p.add_argument("--negative-share", type=float, default=0.25,
                   help="share of a listed frame's tiles centred on one of its hard negatives")
    p.add_argument("--verifier-samples", nargs="+", default=[], metavar="CSV",
                   help="train the crop network's verifier head (vehicle or not) on these "
                        "mine_negatives.py lists: detected boxes labelled 0 (background) or 1 "
                        "(vehicle); the ground-truth crops count as vehicles")
    p.add_argument("--verifier-head-only", action="store_true",
                   help="train only the verifier head; the rest of the crop network (type, shape, "
                        "flip, refinement) stays as --init-from left it")
    p.add_argument("--verifier-batch", type=int, default=16,
                   help="listed or random background crops added to each crop batch")
    p.add_argument("--verifier-random-share", type=float, default=0.25,
                   help="share of those cut at a random place of a training frame that holds no "
                        "vehicle (car-sized box, random angle)")
    p.add_argument("--verifier-negative-share", type=float, default=0.6,
                   help="share of the listed crops drawn from the background (label 0) rows")
    p.add_argument("--heading-samples", nargs="+", default=[], metavar="CSV",
                   help="real vehicles labelled with their driving direction only "
                        "(real_headings.py lists): crops that train the front/back output")
    p.add_argument("--large-crop-share", type=float, default=0.0,
                   help="share of the ground-truth crops drawn from the large vehicles (buses, "
                        "trucks) alone")
    p.add_argument("--large-end-share", type=float, default=0.0,
                   help="share of a large vehicle's crops cut at one of its ends (the window's "
                        "edge on the vehicle's end), as the app's crop_large_vehicle_ends looks: "
                        "they train the front/back output only")
    p.add_argument("--heading-batch", type=int, default=16,
                   help="heading crops added to every crop batch (with --heading-samples)")
    p.add_argument("--flip-branch", action="store_true",
                   help="give the crop network's front/back output its own fully connected "
                        "layer, started as a copy of the shared one")
    p.add_argument("--verifier-branch", action="store_true",
                   help="give the crop network's verifier output its own fully connected layer, "
                        "started as a copy of the shared one (with --verifier-head-only: trained "
                        "alone, the rest of the crop network bit for bit --init-from's)")
    p.add_argument("--flip-head-only", action="store_true",
                   help="train only the front/back branch (needs --flip-branch, --init-from and "
                        "--crop-only): type, shape, refinement and verifier stay as they are")
    p.add_argument("--type-head-only", action="store_true",
                   help="train only the type output layer (needs --init-from and --crop-only): "
                        "shape, front/back, refinement and verifier stay exactly as they are")
    p.add_argument("--refine-head-only", action="store_true",
                   help="train only the box refinement head (needs --init-from and --crop-only): "
                        "type, shape, front/back and verifier stay exactly as they are")
    p.add_argument("--shadow-share", type=float, default=0.0,
                   help="share of first-stage tiles given a cast shadow (augment.cast_shadow)")
    p.add_argument("--jpeg-share", type=float, default=0.0,
                   help="share of first-stage tiles re-encoded as JPEG (augment.compress)")
    p.add_argument("--working-width", type=int, default=648)
    p.add_argument("--working-gsd-range", type=float, nargs=2, default=(0.08, 0.18))
    p.add_argument("--shape-loss", choices=["l1", "l2"], default="l1", help="V_L1 or V_L2")
    p.add_argument("--single-stage", action="store_true", help="add type/shape heads to the detector")
    p.add_argument("--no-crop", action="store_true", help="do not train the crop classifier")
    p.add_argument("--init-from", default=None,
                   help="start from this run's detector (and crop net) weights (missing heads stay new)")
    p.add_argument("--train-heads-only", action="store_true",
                   help="with --single-stage: train only the type/shape heads on a frozen detector "
                        "(the single- vs two-stage comparison of the model card)")
    p.add_argument("--qat-from", default=None, metavar="EXPORTDIR",
                   help="quantization-aware fine-tuning of an export.py folder's first stage "
                        "(detector_fp32.onnx + detector_int8.onnx; qat.py): int8 fake quantization "
                        "with the export's activation ranges; implies --no-crop; export the run "
                        "with tools/detector/qat.py")
    p.add_argument("--crop-only", action="store_true",
                   help="train only the crop classifier (second stage; e.g. the V_L1/V_L2 comparison)")
    p.add_argument("--asm", default=DEFAULT_ASM_PATH)
    p.add_argument("--cache-frames", type=int, default=256)
    p.add_argument("--log-every", type=int, default=10)
    p.add_argument("--max-steps", type=int, default=0, help="stop after N steps (tests)")
    p.add_argument("--session-minutes", type=float, default=0.0,
                   help="end this run after M minutes of wall time with a checkpoint (the schedule "
                        "still spans --budget-minutes; continue with --resume); 0: no limit")
    p.add_argument("--preload", action="store_true",
                   help="read every training frame into memory at start (cache without eviction; "
                        "shared with --workers); needs about 4 MiB per 1296 x 1024 frame")
    p.add_argument("--workers", type=int, default=0,
                   help="batch-making worker processes (0: the main process, deterministic)")
    p.add_argument("--no-eval", action="store_true")
    return p.parse_args(argv)


def pick_device(name: str) -> torch.device:
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    return torch.device(name)


class FrameCache:
    """Loaded (full-resolution) samples, least recently used dropped beyond ``capacity``."""

    def __init__(self, capacity: int):
        self.capacity = capacity
        self.items: Dict[int, Sample] = {}

    def get(self, key: int, sample: Sample) -> Sample:
        if key in self.items:
            s = self.items.pop(key)
        else:
            s = sample.loaded()
        self.items[key] = s
        while len(self.items) > self.capacity:
            self.items.pop(next(iter(self.items)))
        return s


def estimate_gsd(s: Sample) -> float:
    """GSD (m/px) of an image: known per-object values, else the median box long side as a car."""
    if len(s) and np.isfinite(s.gsd_m).any():
        return float(np.nanmedian(s.gsd_m))
    if len(s):
        return CAR_LENGTH_M / float(np.median(np.maximum(s.boxes[:, 2], s.boxes[:, 3])))
    return math.nan


def hard_example_weights(s: Sample, weight: float, min_occlusion: float) -> Optional[np.ndarray]:
    """Weights of the objects an object-centred tile is drawn around: ``weight`` for the hard
    ones (large, or occluded by at least ``min_occlusion`` but not ignored), 1 for the others;
    None (uniform, v1's rule) when ``weight`` is 1."""
    if weight == 1.0 or not len(s):
        return None
    hard = (s.types == LARGE) | (s.occlusion >= min_occlusion)  # unknown (NaN) is not hard
    return np.where(hard & ~s.ignore, weight, 1.0)


def read_hard_negatives(path: str, seq: List[Sample],
                        real: Sequence[Sample] = ()) -> Dict[Tuple[str, int], np.ndarray]:
    """The hard negatives of mine_negatives.py per training frame: ("seq", index into ``seq``)
    or ("real", index into ``real``) -> [K, 2] pixel centres in the frame as stored. Rows of
    frames in neither list are skipped (mined on other data, or a held-out real image); a
    malformed file is an error naming the row."""
    index = {os.path.abspath(s.image_path): ("seq", i) for i, s in enumerate(seq) if s.image_path}
    index.update({os.path.abspath(s.image_path): ("real", i)
                  for i, s in enumerate(real) if s.image_path})
    points: Dict[Tuple[str, int], list] = {}
    try:
        with open(path, newline="") as f:
            reader = csv.DictReader(f)
            if not {"image", "cx_px", "cy_px"} <= set(reader.fieldnames or []):
                raise SystemExit(f"{path}: not a hard-negatives CSV (columns image, cx_px, cy_px)")
            for line, r in enumerate(reader, start=2):
                try:
                    u, v = float(r["cx_px"]), float(r["cy_px"])
                except (TypeError, ValueError):
                    raise SystemExit(f"{path}:{line}: cx_px, cy_px: not numbers") from None
                if not (math.isfinite(u) and math.isfinite(v)):
                    raise SystemExit(f"{path}:{line}: cx_px, cy_px: not finite")
                i = index.get(os.path.abspath(r["image"] or ""))
                if i is not None:
                    points.setdefault(i, []).append((u, v))
    except OSError as e:
        raise SystemExit(f"--hard-negatives: {e}") from None
    return {i: np.asarray(p, np.float64) for i, p in points.items()}


def read_verifier_samples(path: str) -> List[tuple]:
    """Rows (image, cx, cy, length, width, angle, gsd_m, label) of a mine_negatives.py list;
    rows without a finite GSD are skipped; a malformed file is an error naming the row."""
    cols = ["image", "cx_px", "cy_px", "length_px", "width_px", "angle_rad", "gsd_m", "label"]
    out = []
    try:
        with open(path, newline="") as f:
            reader = csv.DictReader(f)
            if not set(cols) <= set(reader.fieldnames or []):
                raise SystemExit(f"{path}: not a verifier list (columns {', '.join(cols)})")
            for line, r in enumerate(reader, start=2):
                try:
                    vals = [float(r[c]) for c in cols[1:7]]
                    label = int(r["label"])
                except (TypeError, ValueError):
                    raise SystemExit(f"{path}:{line}: not numbers") from None
                if label not in (0, 1):
                    raise SystemExit(f"{path}:{line}: label must be 0 or 1")
                if all(math.isfinite(v) for v in vals) and vals[5] > 0:
                    out.append((os.path.abspath(r["image"]), *vals, label))
    except OSError as e:
        raise SystemExit(f"--verifier-samples: {e}") from None
    return out


class Data:
    """Training and validation sources and the batch makers (all randomness from ``rng``)."""

    def __init__(self, args, n_s: int, log=print):
        self.args = args
        self.n_s = n_s
        self.seq: List[Sample] = []
        for d in args.data:
            self.seq.extend(read_sequence(d, n_s=n_s))
        for d in args.dota:
            self.seq.extend(read_dota(d, n_s=n_s))
        self.val_seq: List[Sample] = []
        for d in args.val_data:
            self.val_seq.extend(read_sequence(d, n_s=n_s))
        self.real: List[Sample] = []
        self.real_val: List[Sample] = []
        self.split_report = None
        if args.real:
            all_real = read_yolo(args.real, n_s=n_s)
            if args.real_split:
                self.real, self.real_val, self.split_report = split_from_file(
                    all_real, args.real_split)
            else:
                self.real, self.real_val, self.split_report = split_near_duplicate_free(
                    all_real, seed=args.split_seed)
            if args.real_max:
                sel = np.random.default_rng(args.seed).permutation(len(self.real))[:args.real_max]
                self.real = [self.real[i] for i in sorted(sel)]
            if args.real_val_max:
                sel = np.random.default_rng(args.seed + 1).permutation(len(self.real_val))[:args.real_val_max]
                self.real_val = [self.real_val[i] for i in sorted(sel)]
        if not self.seq and not self.real:
            raise SystemExit("no training data: give --data, --real or --dota")
        self.crop_pool = [(i, j) for i, s in enumerate(self.seq) for j in range(len(s))
                          if not s.ignore[j] and s.types[j] >= 0 and not s.aa_only[j]
                          and s.direction_known[j] and math.isfinite(s.gsd_m[j])]
        self.large_pool = [(i, j) for i, j in self.crop_pool if self.seq[i].types[j] == LARGE]
        self.cache = FrameCache(args.cache_frames)
        self.negatives = (read_hard_negatives(args.hard_negatives, self.seq, self.real)
                          if args.hard_negatives else {})
        self.verifier = [read_verifier_samples(p) for p in args.verifier_samples]
        self.verifier = {label: [r for rows in self.verifier for r in rows if r[-1] == label]
                         for label in (0, 1)} if self.verifier else {}
        self.headings = [r for p in args.heading_samples for r in read_verifier_samples(p)]
        if self.headings:
            log(f"heading samples: {len(self.headings)} real vehicles with a driving direction")
        self.gsd_frames = [i for i, s in enumerate(self.seq) if np.isfinite(s.gsd_m).any()]
        self.verifier_images = collections.OrderedDict()  # path -> image, least recent first
        if self.verifier:
            log(f"verifier: {len(self.verifier[0])} background and {len(self.verifier[1])} vehicle "
                f"boxes listed, random background from {len(self.gsd_frames)} frames")
        log(f"data: {len(self.seq)} sequence/DOTA frames ({sum(len(s) for s in self.seq)} objects), "
            f"{len(self.real)} real training images, {len(self.real_val)} real validation images, "
            f"{len(self.val_seq)} validation frames, {len(self.crop_pool)} typed objects for crops"
            + (f", {sum(len(v) for v in self.negatives.values())} hard negatives in "
               f"{len(self.negatives)} frames" if self.negatives else ""))

    def preload(self, threads: int = 8, log=print) -> None:
        """Every training frame into the cache (no eviction): read once, then shared by the
        --workers processes, which fork after it (copy-on-write: the pixels are never written)."""
        from concurrent.futures import ThreadPoolExecutor

        keys = [("seq", i) for i in range(len(self.seq))] + [("real", i) for i in range(len(self.real))]
        self.cache.capacity = max(self.cache.capacity, len(keys))
        t0 = time.monotonic()
        with ThreadPoolExecutor(max(1, threads)) as pool:  # cv2.imread releases the GIL
            loaded = list(pool.map(lambda k: (self.seq if k[0] == "seq" else self.real)[k[1]].loaded(), keys))
        for (pool_name, i), s in zip(keys, loaded):
            self._load(pool_name, i, s)  # already loaded: only cached
        mb = sum(s.image.nbytes for s in loaded) / 2**20
        log(f"preloaded {len(keys)} frames ({mb:.0f} MiB) in {time.monotonic() - t0:.1f} s")

    def frames_per_epoch(self) -> int:
        return len(self.seq) + len(self.real)

    def _load(self, pool: str, i: int, sample: Optional[Sample] = None) -> Sample:
        src = self.seq if pool == "seq" else self.real
        key = i if pool == "seq" else -1 - i
        return self.cache.get(key, src[i] if sample is None else sample)

    def tile(self, rng: np.random.Generator) -> Sample:
        a = self.args
        use_real = self.real and (not self.seq or rng.random() < a.real_share)
        pool = "real" if use_real else "seq"
        src = self.real if use_real else self.seq
        i = int(rng.integers(0, len(src)))
        s = self._load(pool, i)
        if pool == "seq" and np.isfinite(s.gsd_m).any() and s.keypoints is not None:
            f = a.working_width / s.image.shape[1]
        else:
            gsd = estimate_gsd(s)
            target = rng.uniform(*a.working_gsd_range)
            f = gsd / target if math.isfinite(gsd) else a.working_width / s.image.shape[1]
        f *= math.exp(rng.uniform(-0.15, 0.15))
        negatives = self.negatives.get((pool, i))
        h0, w0 = s.image.shape[:2]
        s = augment.scale(s, f)
        if negatives is not None and rng.random() < a.negative_share:
            u, v = negatives[int(rng.integers(0, len(negatives)))]
            fx, fy = s.image.shape[1] / w0, s.image.shape[0] / h0  # as scale() moved the pixels
            s = augment.crop_near(s, ((u + 0.5) * fx - 0.5, (v + 0.5) * fy - 0.5),
                                  (a.tile, a.tile), rng)
        else:
            s = augment.random_crop(s, (a.tile, a.tile), rng,
                                    weights=hard_example_weights(s, a.hard_weight, a.hard_occlusion))
        s = augment.random_geometric(s, rng)
        if rng.random() < a.shadow_share:
            s = augment.cast_shadow(s, rng)
        s = augment.photometric(s, rng)
        if rng.random() < a.jpeg_share:
            s = augment.compress(s, rng)
        return s

    def detector_arrays(self, rng) -> Dict[str, np.ndarray]:
        """One batch of training tiles and their targets, as numpy arrays (``image``: NHWC)."""
        items, imgs = [], []
        for _ in range(self.args.batch):
            s = self.tile(rng)
            items.append(targets.encode(s, n_s=self.n_s))
            imgs.append(s.image)
        batch = dict(targets.collate(items))
        batch["image"] = np.stack(imgs)
        return batch

    def crop_arrays(self, rng) -> Optional[Dict[str, np.ndarray]]:
        """One batch of jittered ground-truth crops and their targets (None: no typed objects)."""
        if not self.crop_pool:
            return None
        imgs, types, gammas, flips, refines, full = [], [], [], [], [], []
        for _ in range(self.args.crop_batch):
            pool = self.crop_pool
            if self.large_pool and rng.random() < self.args.large_crop_share:
                pool = self.large_pool
            i, j = pool[int(rng.integers(0, len(pool)))]
            s = self._load("seq", i)
            box, gsd = s.boxes[j], float(s.gsd_m[j])
            end_crop = (s.types[j] == LARGE and rng.random() < self.args.large_end_share
                        and box[2] * gsd > crops.CROP_W * crops.CROP_GSD_M)
            if end_crop:
                # The app looks at a bus's two ends for its front (crop_large_vehicle_ends): a
                # window at one end, which only the front/back output learns from.
                offset = (0.5 * box[2] - 0.5 * crops.CROP_W * crops.CROP_GSD_M / gsd) * (
                    1.0 if rng.random() < 0.5 else -1.0)
                box = box.copy()
                box[0] += offset * math.cos(box[4])
                box[1] += offset * math.sin(box[4])
            cen, ang, gsd_used, flip, refine = crops.jittered_crop_target(box, gsd, rng)
            patch = crops.extract_crop(s.image, cen, ang, gsd_used)
            if rng.random() < 0.5:  # mirror about the length axis: left/right swap
                patch = np.ascontiguousarray(patch[::-1])
                refine = refine.copy()
                refine[1] = -refine[1]
                refine[2] = -refine[2]
            tmp = Sample(image_path=None, image=patch, **{k: v for k, v in _empty(self.n_s).items()})
            patch = augment.photometric(tmp, rng).image
            imgs.append(patch)
            types.append(-1 if end_crop else s.types[j])
            gammas.append(np.full(self.n_s, np.nan, np.float32) if end_crop else s.gammas[j])
            flips.append(flip)
            refines.append(np.zeros(5, np.float32) if end_crop else refine)
            full.append(not end_crop)
        flip_known = [True] * len(imgs)
        vehicle = [1.0] * len(imgs)
        for _ in range(self.args.heading_batch if self.headings else 0):
            patch, flip = self.heading_crop(rng)
            tmp = Sample(image_path=None, image=patch, **{k: v for k, v in _empty(self.n_s).items()})
            imgs.append(augment.photometric(tmp, rng).image)
            types.append(-1)
            gammas.append(np.full(self.n_s, np.nan, np.float32))
            flips.append(float(flip))
            refines.append(np.zeros(5, np.float32))
            full.append(False)
            flip_known.append(True)
            vehicle.append(1.0)
        if self.verifier:
            for _ in range(self.args.verifier_batch):
                patch, label = self.verifier_crop(rng)
                tmp = Sample(image_path=None, image=patch, **{k: v for k, v in _empty(self.n_s).items()})
                imgs.append(augment.photometric(tmp, rng).image)
                types.append(-1)
                gammas.append(np.full(self.n_s, np.nan, np.float32))
                flips.append(0.0)
                refines.append(np.zeros(5, np.float32))
                full.append(False)
                flip_known.append(False)
                vehicle.append(float(label))
        return {"image": np.stack(imgs), "type": np.array(types), "gamma": np.stack(gammas),
                "flip": np.array(flips), "refine": np.stack(refines),
                "full": np.array(full), "flip_known": np.array(flip_known),
                "vehicle": np.array(vehicle, np.float32)}

    def heading_crop(self, rng) -> Tuple[np.ndarray, int]:
        """A crop of a listed real vehicle, posed as the detector would (jittered, reversed half
        of the time), and its flip target (1: the crop's +x is the vehicle's rear)."""
        path, cx, cy, length, width, angle, gsd, _ = self.headings[int(rng.integers(0, len(self.headings)))]
        box = np.array([cx, cy, length, width, angle])
        cen, ang, gsd_used, flip, _ = crops.jittered_crop_target(box, gsd, rng, center_sigma_m=0.15,
                                                                 angle_sigma=math.radians(4))
        patch = crops.extract_crop(self._verifier_image(path), cen, ang, gsd_used)
        if rng.random() < 0.5:  # mirror about the length axis: front/back unchanged
            patch = np.ascontiguousarray(patch[::-1])
        return patch, flip

    def _verifier_image(self, path: str) -> np.ndarray:
        img = self.verifier_images.pop(path, None)
        if img is None:
            img = load_image(path)
            while len(self.verifier_images) >= max(16, self.args.cache_frames // 4):
                self.verifier_images.popitem(last=False)
        self.verifier_images[path] = img
        return img

    def verifier_crop(self, rng) -> Tuple[np.ndarray, int]:
        """One crop for the verifier head and its label (1 vehicle, 0 background): a listed box
        (jittered like the ground-truth crops) or a car-sized box at a random place of a
        training frame that overlaps no vehicle."""
        a = self.args
        if self.gsd_frames and rng.random() < a.verifier_random_share:
            for _ in range(20):
                s = self._load("seq", self.gsd_frames[int(rng.integers(0, len(self.gsd_frames)))])
                gsd = float(np.nanmedian(s.gsd_m))
                h, w = s.image.shape[:2]
                box = np.array([rng.uniform(0, w), rng.uniform(0, h), 4.5 / gsd, 1.9 / gsd,
                                rng.uniform(0, 2 * math.pi)])
                if not len(s) or rotated_iou_matrix(box[None], s.boxes).max() < 0.01:
                    return crops.extract_crop(s.image, box[:2], float(box[4]), gsd), 0
        label = 0 if (not self.verifier[1] or (self.verifier[0] and
                                               rng.random() < a.verifier_negative_share)) else 1
        rows = self.verifier[label]
        path, cx, cy, length, width, angle, gsd, _ = rows[int(rng.integers(0, len(rows)))]
        box = np.array([cx, cy, length, width, angle])
        cen, ang, gsd_used, _, _ = crops.jittered_crop_target(box, gsd, rng, center_sigma_m=0.15,
                                                              angle_sigma=math.radians(4))
        patch = crops.extract_crop(self._verifier_image(path), cen, ang, gsd_used)
        if rng.random() < 0.5:
            patch = np.ascontiguousarray(patch[::-1])
        return patch, label

    def detector_batch(self, rng, device) -> Dict[str, torch.Tensor]:
        return to_device(self.detector_arrays(rng), device)

    def crop_batch(self, rng, device) -> Optional[Dict[str, torch.Tensor]]:
        arrays = self.crop_arrays(rng)
        return None if arrays is None else to_device(arrays, device)


def to_device(arrays, device) -> Dict[str, torch.Tensor]:
    """numpy arrays (or the tensors a DataLoader made of them) on ``device``; ``image`` (NHWC
    uint8) becomes the normalised NCHW ``input``."""
    out = {k: torch.as_tensor(v).to(device, non_blocking=True) for k, v in arrays.items()
           if k != "image"}
    x = torch.as_tensor(arrays["image"]).to(device, non_blocking=True).permute(0, 3, 1, 2)
    out["input"] = normalize(x)
    return out


class BatchStream(torch.utils.data.IterableDataset):
    """Endless (detector arrays, crop arrays) pairs for --workers: worker k draws from a numpy
    Generator seeded by (seed, k, start step), so a run is reproducible from its start."""

    def __init__(self, data: "Data", seed: int, start_step: int, detector: bool, crop: bool):
        super().__init__()
        self.data, self.seed, self.start_step = data, seed, start_step
        self.detector, self.crop = detector, crop

    def __iter__(self):
        info = torch.utils.data.get_worker_info()
        rng = np.random.default_rng([self.seed, info.id if info else 0, self.start_step])
        while True:
            yield (self.data.detector_arrays(rng) if self.detector else None,
                   self.data.crop_arrays(rng) if self.crop else None)


def _worker_init(_):
    import cv2

    torch.set_num_threads(1)  # the workers together use the cores; one thread each
    cv2.setNumThreads(1)


def _empty(n_s):
    from detector.datasets import empty_like_arrays

    return empty_like_arrays(0, n_s)


def lr_at(step: int, total: int, base: float, warmup: int = 100,
          progress: Optional[float] = None) -> float:
    """Linear warm-up, then cosine decay to 2 % of ``base`` over the steps after the warm-up,
    or over ``progress`` in [0, 1] (share of the time budget used) when given."""
    if step < warmup:
        return base * (step + 1) / warmup
    t = min(1.0, (step - warmup) / max(1, total - warmup)) if progress is None else min(1.0, progress)
    return base * (0.02 + 0.98 * 0.5 * (1 + math.cos(math.pi * t)))


def save_checkpoint(path: str, state: dict) -> None:
    tmp = path + ".tmp"
    torch.save(state, tmp)
    os.replace(tmp, path)


def _check_out_dir(out: str) -> None:
    real = os.path.realpath(out)
    if real == REPO_ROOT or real.startswith(REPO_ROOT + os.sep):
        raise SystemExit(f"--out {out}: run directories must be outside the repository")


def train(args) -> dict:
    _check_out_dir(args.out)
    if args.workers < 0 or args.session_minutes < 0:
        raise SystemExit(f"--workers and --session-minutes must be >= 0 (got {args.workers}, "
                         f"{args.session_minutes})")
    if not args.hard_weight > 0 or not 0.0 <= args.hard_occlusion <= 1.0:
        raise SystemExit(f"--hard-weight must be > 0 (got {args.hard_weight}) and --hard-occlusion "
                         f"in [0, 1] (got {args.hard_occlusion})")
    if args.verifier_samples and (args.no_crop or args.verifier_batch < 1 or not (
            0.0 <= args.verifier_random_share <= 1.0 and 0.0 <= args.verifier_negative_share <= 1.0)):
        raise SystemExit("--verifier-samples needs the crop network (no --no-crop), "
                         "--verifier-batch >= 1 and shares in [0, 1]")
    if not 0.0 <= args.negative_share <= 1.0:
        raise SystemExit(f"--negative-share must be in [0, 1] (got {args.negative_share})")
    os.makedirs(args.out, exist_ok=True)
    log_path = os.path.join(args.out, "train_log.jsonl")

    def log(msg):
        print(msg, flush=True)

    device = pick_device(args.device)
    torch.set_num_threads(args.threads)
    torch.manual_seed(args.seed)
    if device.type == "cuda":
        torch.backends.cudnn.benchmark = False
        torch.backends.cudnn.deterministic = True
    asm = load_asm(args.asm)
    data = Data(args, asm.n_s, log)
    if args.preload:
        data.preload(threads=max(1, args.workers), log=log)
    if data.split_report:
        with open(os.path.join(args.out, "split.json"), "w") as f:
            json.dump(data.split_report, f, indent=1)
        r = data.split_report
        if "from_file" in r:
            log(f"real split from {r['from_file']}: {r['train']} train / {r['val']} val images "
                f"({r['train_boxes']} / {r['val_boxes']} boxes; {r['val_stems_missing']} listed "
                f"validation images not in the folder)")
        else:
            log(f"real split: {r['train']} train / {r['val']} val images ({r['train_boxes']} / "
                f"{r['val_boxes']} boxes); dropped from val: {r['val_dropped_gap']} (frame gap), "
                f"{r['val_dropped_hash']} (dHash <= {r['hash_threshold_bits']} bits); min val-train "
                f"hash distance {r['min_val_train_hash_distance']}")
    if args.qat_from:
        if args.init_from or args.single_stage or args.crop_only or args.train_heads_only:
            raise SystemExit("--qat-from excludes --init-from, --single-stage, --crop-only and "
                             "--train-heads-only (it fine-tunes the exported first stage as it is)")
        from detector.qat import QatDetector

        det = QatDetector.from_export(args.qat_from).to(device)
        args.no_crop = True
        log(f"quantization-aware fine-tuning of {args.qat_from}: {len(det.params)} weight "
            f"tensors, {len(det.act_params)} fixed activation ranges")
    else:
        det = Detector(n_s=asm.n_s, single_stage=args.single_stage).to(device)
    if args.crop_only and args.no_crop:
        raise SystemExit("--crop-only and --no-crop exclude each other")
    if args.heading_samples and (args.no_crop or args.heading_batch < 1):
        raise SystemExit("--heading-samples needs the crop network (no --no-crop) and "
                         "--heading-batch >= 1")
    crop_net = (None if args.no_crop
                else CropNet(n_s=asm.n_s, verifier=bool(args.verifier_samples),
                             flip_branch=args.flip_branch,
                             verifier_branch=args.verifier_branch).to(device))
    if args.verifier_branch and not args.verifier_samples:
        raise SystemExit("--verifier-branch needs --verifier-samples (the verifier's training)")
    if args.init_from:
        ck0 = torch.load(args.init_from, map_location=device)
        missing, unexpected = det.load_state_dict(ck0["detector"], strict=False)
        if unexpected:
            raise SystemExit(f"--init-from {args.init_from}: unexpected detector weights {unexpected[:4]}")
        if crop_net is not None and ck0.get("crop") is not None:
            ck_crop = ck0["crop"]
            width = (int(ck_crop["verifier_fc.0.weight"].shape[0])
                     if "verifier_fc.0.weight" in ck_crop else 192)
            if "vehicle_logit_edge.weight" in ck_crop or width != 192:
                # Two verifiers in one branch, the border's own head (verifier_ensemble.py, v14):
                # the network takes the checkpoint's layout.
                crop_net = CropNet(n_s=asm.n_s, verifier=True,
                                   flip_branch=args.flip_branch or "flip_fc.0.weight" in ck_crop,
                                   verifier_branch=True, verifier_width=width,
                                   verifier_edge="vehicle_logit_edge.weight" in ck_crop).to(device)
            elif "vehicle_logit.weight" in ck_crop and not crop_net.verifier:
                crop_net = CropNet(n_s=asm.n_s, verifier=True, flip_branch=args.flip_branch).to(device)
            missing_c, unexpected_c = crop_net.load_state_dict(ck0["crop"], strict=False)
            if unexpected_c or any(not k.startswith(("vehicle_logit.", "flip_fc.", "verifier_fc."))
                                   for k in missing_c):
                raise SystemExit(f"--init-from {args.init_from}: crop network weights do not fit "
                                 f"(missing {missing_c[:4]}, unexpected {unexpected_c[:4]})")
            if any(k.startswith("flip_fc.") for k in missing_c):
                crop_net.start_flip_branch_from_shared()
                missing_c = [k for k in missing_c if not k.startswith("flip_fc.")]
            if any(k.startswith("verifier_fc.") for k in missing_c):
                crop_net.start_verifier_branch_from_shared()
                missing_c = [k for k in missing_c if not k.startswith("verifier_fc.")]
            missing += missing_c
        log(f"initialised from {args.init_from}; new: {sorted({k.split('.')[0] for k in missing})}")
    head_names = ("type_head", "shape_head")
    if args.train_heads_only:
        if not args.single_stage:
            raise SystemExit("--train-heads-only needs --single-stage")
        for name, prm in det.named_parameters():
            prm.requires_grad = name.split(".")[0] in head_names
    opt_d = torch.optim.AdamW([q for q in det.parameters() if q.requires_grad], lr=args.lr,
                              weight_decay=1e-4)
    # Head-only modes: the crop-network parameters that train (every other weight and batch-norm
    # statistic stays --init-from's), and the options each needs beside --init-from, --crop-only.
    head_only = {"verifier_head_only": (("vehicle_logit.", "verifier_fc."), ("verifier_samples",)),
                 "flip_head_only": (("flip_fc.", "flip_logit."), ("flip_branch",)),
                 "refine_head_only": (("refine.",), ()),
                 "type_head_only": (("type_logits.",), ())}
    for mode, (prefixes, needs) in head_only.items():
        if not getattr(args, mode):
            continue
        if not (all(getattr(args, n) for n in needs) and args.init_from and args.crop_only):
            flags = [f"--{n.replace('_', '-')}" for n in needs] + ["--init-from"]
            raise SystemExit(f"--{mode.replace('_', '-')} needs {', '.join(flags)} and --crop-only")
        for name, prm in crop_net.named_parameters():
            prm.requires_grad = name.startswith(prefixes)
    opt_c = torch.optim.AdamW([q for q in crop_net.parameters() if q.requires_grad], lr=args.lr,
                              weight_decay=1e-4) if crop_net else None
    shape_loss = make_shape_loss(args.shape_loss, asm)
    steps_per_epoch = max(1, math.ceil(data.frames_per_epoch() / args.batch))
    total_steps = args.epochs * steps_per_epoch
    if args.max_steps:
        total_steps = min(total_steps, args.max_steps)
    rng = np.random.default_rng(args.seed)
    step, elapsed = 0, 0.0
    ckpt_path = os.path.join(args.out, "checkpoint.pt")
    if args.resume and os.path.isfile(ckpt_path):
        ck = torch.load(ckpt_path, map_location=device)
        det.load_state_dict(ck["detector"])
        opt_d.load_state_dict(ck["opt_detector"])
        if crop_net is not None and ck.get("crop") is not None:
            crop_net.load_state_dict(ck["crop"])
            opt_c.load_state_dict(ck["opt_crop"])
        step, elapsed = ck["step"], ck["elapsed_s"]
        rng.bit_generator.state = ck["numpy_rng"]
        torch.set_rng_state(ck["torch_rng"].cpu())  # map_location moved it to the device
        log(f"resumed at step {step} ({elapsed / 60:.1f} min trained)")
    elif args.resume:
        log(f"--resume: no {ckpt_path}, starting fresh")
    with open(os.path.join(args.out, "args.json"), "w") as f:
        json.dump(vars(args), f, indent=1)

    def state():
        return {"detector": det.state_dict(), "opt_detector": opt_d.state_dict(),
                "crop": crop_net.state_dict() if crop_net else None,
                "opt_crop": opt_c.state_dict() if opt_c else None,
                "step": step, "elapsed_s": elapsed, "numpy_rng": rng.bit_generator.state,
                "torch_rng": torch.get_rng_state(), "args": vars(args), "n_s": asm.n_s,
                "single_stage": args.single_stage, "shape_loss": args.shape_loss}

    budget_s = args.budget_minutes * 60
    log(f"device {device}, {steps_per_epoch} steps/epoch, planned {total_steps} steps, "
        f"budget {args.budget_minutes} min")
    det.train()
    if args.train_heads_only:  # frozen parts keep their batch-norm statistics
        for name, mod in det.named_children():
            if name not in head_names:
                mod.eval()
    if crop_net:
        # Head only: the frozen layers keep their batch-norm statistics (eval mode), so the
        # other outputs stay exactly what --init-from gave.
        crop_net.train(not any(getattr(args, mode) for mode in head_only))
    last_ckpt = time.monotonic()
    t_run = time.monotonic()
    elapsed0 = elapsed
    history = []
    stream = None
    if args.workers > 0:
        stream = iter(torch.utils.data.DataLoader(
            BatchStream(data, args.seed, step, not args.crop_only, crop_net is not None),
            batch_size=None, num_workers=args.workers, prefetch_factor=4,
            worker_init_fn=_worker_init, pin_memory=device.type == "cuda"))
    session_s = args.session_minutes * 60 if args.session_minutes > 0 else math.inf
    with open(log_path, "a") as logf:
        while step < total_steps and elapsed < budget_s and time.monotonic() - t_run < session_s:
            t0 = time.monotonic()
            arrays_d, arrays_c = next(stream) if stream is not None else (None, None)
            if args.schedule == "time":
                lr = lr_at(step, total_steps, args.lr, args.warmup_steps, progress=elapsed / budget_s)
            else:
                lr = lr_at(step, total_steps, args.lr, args.warmup_steps)
            rec = {"step": step, "lr": lr}
            t_data = 0.0
            if not args.crop_only:
                for g in opt_d.param_groups:
                    g["lr"] = lr
                batch = (to_device(arrays_d, device) if stream is not None
                         else data.detector_batch(rng, device))
                t_data = time.monotonic() - t0
                out = det(batch["input"])
                loss_d, terms_d = detector_loss(out, batch, shape_loss)
                opt_d.zero_grad(set_to_none=True)
                loss_d.backward()
                torch.nn.utils.clip_grad_norm_(det.parameters(), 10.0)
                opt_d.step()
                rec.update({"det_loss": float(loss_d.detach()),
                            **{f"det_{k}": v for k, v in terms_d.items()}})
            if crop_net is not None:
                if stream is not None:
                    cb = None if arrays_c is None else to_device(arrays_c, device)
                else:
                    cb = data.crop_batch(rng, device)
                if cb is not None:
                    for g in opt_c.param_groups:
                        g["lr"] = lr
                    loss_c, terms_c = crop_loss(crop_net(cb["input"]), cb, shape_loss)
                    opt_c.zero_grad(set_to_none=True)
                    loss_c.backward()
                    torch.nn.utils.clip_grad_norm_(crop_net.parameters(), 10.0)
                    opt_c.step()
                    rec.update({"crop_loss": float(loss_c.detach()),
                                **{f"crop_{k}": v for k, v in terms_c.items()}})
            step += 1
            elapsed = elapsed0 + (time.monotonic() - t_run)
            rec.update({"elapsed_s": elapsed, "step_s": time.monotonic() - t0, "data_s": t_data})
            history.append(rec)
            logf.write(json.dumps(rec) + "\n")
            if step % args.log_every == 0 or step == 1:
                logf.flush()
                log(f"step {step}/{total_steps} ep {step / steps_per_epoch:.2f} "
                    f"{elapsed / 60:.1f} min det {rec.get('det_loss', float('nan')):.3f} "
                    + " ".join(f"{k[4:]} {v:.3f}" for k, v in rec.items() if k.startswith("det_") and k != "det_loss")
                    + (f" | crop {rec['crop_loss']:.3f}" if "crop_loss" in rec else "")
                    + f" | {rec['step_s']:.2f} s/step (data {t_data:.2f})")
            if time.monotonic() - last_ckpt > args.checkpoint_minutes * 60:
                save_checkpoint(ckpt_path, state())
                last_ckpt = time.monotonic()
                log(f"checkpoint at step {step}")
    save_checkpoint(ckpt_path, state())
    log(f"stopped at step {step} ({elapsed / 60:.1f} min); checkpoint {ckpt_path}")
    result = {"steps": step, "elapsed_s": elapsed, "history": history}
    if not args.no_eval and (data.val_seq or data.real_val):
        det.eval()
        if crop_net:
            crop_net.eval()
        metrics = validate(det, crop_net, data, args, device)
        with open(os.path.join(args.out, "metrics.json"), "w") as f:
            json.dump(metrics, f, indent=1)
        log("validation: " + json.dumps(metrics))
        result["metrics"] = metrics
    return result


def validate(det, crop_net, data: Data, args, device) -> dict:
    from detector.evaluate import Predictor, evaluate_samples

    out = {}
    if data.val_seq:
        w = data.val_seq[0].loaded().image.shape[1]
        pred = Predictor(det, crop_net, scale=args.working_width / w, device=str(device))
        out["sim_val"] = evaluate_samples(pred, data.val_seq)
    if data.real_val:
        accs = []
        from detector.evaluate import Accumulator

        acc = Accumulator()
        for s in data.real_val:
            s = s.loaded()
            gsd = estimate_gsd(s)
            scale = gsd / 0.12 if math.isfinite(gsd) else 0.4
            pred = Predictor(det, None, device=str(device))
            res = pred(s.image, scale=scale)
            acc.add(res["boxes"], s.boxes, s.ignore, axis_aligned=True)
        out["real_val_axis_aligned"] = acc.result()
    return out


def main(argv=None) -> int:
    args = parse_args(argv)
    train(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
