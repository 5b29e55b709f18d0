"""Training data for the detector: one sample type, three readers, a near-duplicate-free split.

Contract
--------
``Sample`` is the unified annotation of one image (all arrays have N rows, one per object):

=================== ============ ==================================================================
field               type         meaning
=================== ============ ==================================================================
image_path          str | None   image file (read lazily by ``load_image``; RGB uint8)
image               ndarray|None RGB uint8 [H, W, 3] once loaded (augmentations set it)
boxes               [N, 5] f64   rotated boxes (cx, cy, length, width, angle) in pixels,
                                 docs/conventions.md; for ``aa_only`` rows (cx, cy, w, h, 0)
direction_known     [N] bool     angle is the driving direction over 360 deg (else: axis only)
aa_only             [N] bool     only the axis-aligned enclosing box is known (YOLO labels)
types               [N] i64      index into ``asm.TYPES`` (6 car types + large), -1 unknown
gammas              [N, n_s] f32 ASM shape parameters, NaN where unknown (large, real, DOTA)
ignore              [N] bool     don't train on it, don't penalise detecting it (heavily
                                 occluded / truncated / DOTA 'difficult')
gsd_m               [N] f64      metres per pixel at the object (NaN unknown)
occlusion           [N] f64      share of the vehicle hidden (trees, buildings; NaN unknown)
keypoints           [N,36,3]|None (u, v, visible) per ASM keypoint, NaN where unknown
source, group       str          where it came from; split group (clip / sequence)
=================== ============ ==================================================================

Readers (all return ``List[Sample]`` with images not yet loaded, and raise ``DatasetError``
naming file and line on malformed input):

* ``read_sequence(dir)``: our recorded-sequence format (docs/recorded_sequence.md): frames.csv
  (PNG or JPEG), ground_truth/objects.csv (type, gamma_*, box_*, truncation, occlusion) and
  ground_truth/keypoints.csv. Per-object GSD comes from the wheel-centre keypoints
  (pixel distance vs horizontal world distance), else length_m / box_length_px.
* ``read_yolo(dir)``: ``images/*.jpg|png`` + ``labels/<stem>.txt`` with ``class cx cy w h``
  normalised (YOLO). Axis-aligned only, type unknown (class 0 = car). The clip id is the file
  stem before the first ``_`` (``0_13`` -> clip ``0`` frame 13; ``Drone2_(363)`` -> clip
  ``Drone2`` frame 363).
* ``read_dota(dir)``: ``images/`` + ``labelTxt/<stem>.txt`` with ``x1 y1 ... x4 y4 class
  difficult`` (optional ``imagesource:``/``gsd:`` header lines). Heading is ambiguous in DOTA:
  ``direction_known`` is False (the box axis is kept). Classes map to types by ``class_map``
  (default: small-vehicle -> car of unknown type, large-vehicle -> large; others dropped).

``split_near_duplicate_free(samples, ...)`` splits YOLO-style frames so that no near-duplicate
frame is in both parts: whole clips go to one side; a clip holding more than
``max_group_share`` of the frames is cut into blocks of ``block`` consecutive frame indices
and frames within ``gap`` indices of a train/val block boundary are dropped from validation;
finally every validation image whose 64-bit dHash is within ``hash_threshold`` bits of any
training image is dropped too. Returns (train, val, report).
"""

from __future__ import annotations

import csv
import dataclasses
import glob
import math
import os
import re
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

import numpy as np

from detector.asm import TYPES

TYPE_INDEX = {t: i for i, t in enumerate(TYPES)}
LARGE = TYPE_INDEX["large"]
IMAGE_EXTS = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")


class DatasetError(ValueError):
    pass


@dataclasses.dataclass
class Sample:
    image_path: Optional[str]
    boxes: np.ndarray
    direction_known: np.ndarray
    aa_only: np.ndarray
    types: np.ndarray
    gammas: np.ndarray
    ignore: np.ndarray
    gsd_m: np.ndarray
    occlusion: np.ndarray
    keypoints: Optional[np.ndarray] = None
    image: Optional[np.ndarray] = None
    source: str = ""
    group: str = ""
    frame_index: int = 0
    normalized: bool = False  # boxes in [0, 1] image units until the image is loaded

    def __len__(self) -> int:
        return int(self.boxes.shape[0])

    def copy(self, **changes) -> "Sample":
        fields = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        for k, v in fields.items():
            if isinstance(v, np.ndarray) and k != "image":
                fields[k] = v.copy()
        fields.update(changes)
        return Sample(**fields)

    def loaded(self) -> "Sample":
        """A copy with ``image`` (RGB uint8) read and normalised boxes turned into pixels."""
        if self.image is not None and not self.normalized:
            return self
        img = self.image if self.image is not None else load_image(self.image_path)
        s = self.copy(image=img)
        if self.normalized:
            h, w = img.shape[:2]
            b = s.boxes
            # YOLO/normalised coordinates are relative to the image edges; pixel centres are at
            # integer positions (docs/conventions.md), hence the -0.5.
            b[:, 0] = b[:, 0] * w - 0.5
            b[:, 1] = b[:, 1] * h - 0.5
            b[:, 2] = b[:, 2] * w
            b[:, 3] = b[:, 3] * h
            s.normalized = False
        return s

    def subset(self, keep: np.ndarray) -> "Sample":
        keep = np.asarray(keep)
        return self.copy(boxes=self.boxes[keep], direction_known=self.direction_known[keep],
                         aa_only=self.aa_only[keep], types=self.types[keep],
                         gammas=self.gammas[keep], ignore=self.ignore[keep],
                         gsd_m=self.gsd_m[keep], occlusion=self.occlusion[keep],
                         keypoints=None if self.keypoints is None else self.keypoints[keep])


def empty_like_arrays(n: int, n_s: int):
    return dict(boxes=np.zeros((n, 5)), direction_known=np.zeros(n, bool),
                aa_only=np.zeros(n, bool), types=np.full(n, -1, np.int64),
                gammas=np.full((n, n_s), np.nan, np.float32), ignore=np.zeros(n, bool),
                gsd_m=np.full(n, np.nan), occlusion=np.full(n, np.nan))


def load_image(path: str) -> np.ndarray:
    """RGB uint8 [H, W, 3]; raises DatasetError for a missing or corrupt file."""
    import cv2

    img = cv2.imread(path, cv2.IMREAD_COLOR)
    if img is None:
        raise DatasetError(f"{path}: cannot decode image (missing or corrupt)")
    return cv2.cvtColor(img, cv2.COLOR_BGR2RGB)


# ----------------------------------------------------------------------------------------------
# recorded sequences


def _read_csv(path: str, expect_prefix: Sequence[str]) -> Tuple[List[str], List[Tuple[int, List[str]]]]:
    if not os.path.isfile(path):
        raise DatasetError(f"{path}: missing")
    with open(path, "r", encoding="utf-8", newline="") as f:
        lines = f.read().splitlines()
    if not lines:
        raise DatasetError(f"{path}:1: empty file (header expected)")
    header = lines[0].rstrip("\r").split(",")
    if header[:len(expect_prefix)] != list(expect_prefix):
        raise DatasetError(f"{path}:1: header: expected '{','.join(expect_prefix)}...', "
                           f"got '{lines[0]}'")
    rows = []
    for i, line in enumerate(lines[1:], start=2):
        line = line.rstrip("\r")
        if not line:
            raise DatasetError(f"{path}:{i}: empty line")
        fields = line.split(",")
        if len(fields) != len(header):
            raise DatasetError(f"{path}:{i}: expected {len(header)} fields, got {len(fields)}")
        rows.append((i, fields))
    return header, rows


def _num(path: str, line: int, name: str, text: str, integer: bool = False):
    try:
        v = int(text) if integer else float(text)
    except ValueError:
        raise DatasetError(f"{path}:{line}: {name}: not a number '{text}'") from None
    if not integer and not math.isfinite(v):
        raise DatasetError(f"{path}:{line}: {name}: not finite '{text}'")
    return v


OBJECT_COLUMNS_BEFORE_GAMMA = ["frame_id", "track_id", "type"]
OBJECT_COLUMNS_AFTER_GAMMA = [
    "length_m", "width_m", "height_m", "east_m", "north_m", "up_m", "heading_enu_rad",
    "speed_mps", "yaw_rate_radps", "box_cx_px", "box_cy_px", "box_length_px", "box_width_px",
    "box_angle_rad", "truncation", "occlusion", "parked"]


def read_sequence(seq_dir: str, n_s: int = 3, max_occlusion: float = 0.7,
                  max_truncation: float = 0.5) -> List[Sample]:
    """Samples of every frame of a recorded sequence (one per frames.csv row).

    Objects with occlusion > ``max_occlusion`` or truncation > ``max_truncation`` are marked
    ``ignore``. gamma columns beyond ``n_s`` are dropped; missing ones are NaN."""
    frames_csv = os.path.join(seq_dir, "frames.csv")
    _, frame_rows = _read_csv(frames_csv, ["frame_id", "timestamp_ns", "file"])
    frames: Dict[int, str] = {}
    order: List[int] = []
    for line, (fid, _ts, file) in frame_rows:
        fid = _num(frames_csv, line, "frame_id", fid, True)
        if os.path.isabs(file) or ".." in file.split("/"):
            raise DatasetError(f"{frames_csv}:{line}: file: must be relative without '..'")
        if not file.lower().endswith(IMAGE_EXTS):
            raise DatasetError(f"{frames_csv}:{line}: file: not an image '{file}'")
        frames[fid] = os.path.join(seq_dir, file)
        order.append(fid)

    per_frame: Dict[int, list] = {fid: [] for fid in order}
    obj_csv = os.path.join(seq_dir, "ground_truth", "objects.csv")
    kp_by_obj: Dict[Tuple[int, int], np.ndarray] = {}
    kp_world: Dict[Tuple[int, int], np.ndarray] = {}
    if os.path.isfile(obj_csv):
        header, rows = _read_csv(obj_csv, OBJECT_COLUMNS_BEFORE_GAMMA)
        n_gamma = len(header) - len(OBJECT_COLUMNS_BEFORE_GAMMA) - len(OBJECT_COLUMNS_AFTER_GAMMA)
        expect = (OBJECT_COLUMNS_BEFORE_GAMMA + [f"gamma_{i}" for i in range(max(n_gamma, 0))]
                  + OBJECT_COLUMNS_AFTER_GAMMA)
        if header != expect:
            raise DatasetError(f"{obj_csv}:1: header: expected '{','.join(expect)}', "
                               f"got '{','.join(header)}'")
        col = {name: i for i, name in enumerate(header)}
        for line, f in rows:
            fid = _num(obj_csv, line, "frame_id", f[0], True)
            if fid not in per_frame:
                raise DatasetError(f"{obj_csv}:{line}: frame_id: no frame {fid} in frames.csv")
            t = f[col["type"]]
            if t not in TYPE_INDEX:
                raise DatasetError(f"{obj_csv}:{line}: type: unknown vehicle type '{t}'")
            g = np.full(n_s, np.nan, np.float32)
            for k in range(min(n_gamma, n_s)):
                txt = f[col[f"gamma_{k}"]]
                if txt:
                    g[k] = _num(obj_csv, line, f"gamma_{k}", txt)
            rec = {name: _num(obj_csv, line, name, f[col[name]])
                   for name in OBJECT_COLUMNS_AFTER_GAMMA}
            rec["track_id"] = _num(obj_csv, line, "track_id", f[1], True)
            rec["type"] = TYPE_INDEX[t]
            rec["gamma"] = g
            per_frame[fid].append(rec)
        kp_csv = os.path.join(seq_dir, "ground_truth", "keypoints.csv")
        if os.path.isfile(kp_csv):
            _, krows = _read_csv(kp_csv, ["frame_id", "track_id", "keypoint", "u_px", "v_px",
                                          "visible", "east_m", "north_m", "up_m"])
            for line, f in krows:
                key = (_num(kp_csv, line, "frame_id", f[0], True),
                       _num(kp_csv, line, "track_id", f[1], True))
                k = _num(kp_csv, line, "keypoint", f[2], True)
                if not 0 <= k < 36:
                    raise DatasetError(f"{kp_csv}:{line}: keypoint: {k} not in 0..35")
                arr = kp_by_obj.setdefault(key, np.full((36, 3), np.nan, np.float32))
                w = kp_world.setdefault(key, np.full((36, 3), np.nan))
                arr[k] = [_num(kp_csv, line, "u_px", f[3]), _num(kp_csv, line, "v_px", f[4]),
                          _num(kp_csv, line, "visible", f[5], True)]
                w[k] = [_num(kp_csv, line, "east_m", f[6]), _num(kp_csv, line, "north_m", f[7]),
                        _num(kp_csv, line, "up_m", f[8])]

    name = os.path.basename(os.path.normpath(seq_dir))
    samples = []
    for fid in order:
        objs = per_frame[fid]
        n = len(objs)
        a = empty_like_arrays(n, n_s)
        kps = np.full((n, 36, 3), np.nan, np.float32)
        for i, o in enumerate(objs):
            a["boxes"][i] = [o["box_cx_px"], o["box_cy_px"], o["box_length_px"],
                             o["box_width_px"], o["box_angle_rad"] % (2 * math.pi)]
            a["direction_known"][i] = True
            a["types"][i] = o["type"]
            a["gammas"][i] = o["gamma"]
            a["ignore"][i] = o["occlusion"] > max_occlusion or o["truncation"] > max_truncation
            a["occlusion"][i] = o["occlusion"]
            key = (fid, o["track_id"])
            gsd = math.nan
            if key in kp_by_obj:
                kps[i] = kp_by_obj[key]
                gsd = _gsd_from_keypoints(kp_by_obj[key], kp_world[key])
            if not math.isfinite(gsd) and o["box_length_px"] > 0:
                gsd = o["length_m"] / o["box_length_px"]
            a["gsd_m"][i] = gsd
        samples.append(Sample(image_path=frames[fid], keypoints=kps, source=f"{name}:{fid}",
                              group=name, frame_index=fid, **a))
    return samples


def _gsd_from_keypoints(kp: np.ndarray, world: np.ndarray) -> float:
    """Metres per pixel from the wheel-centre keypoints (0 FL, 1 FR, 2 RL, 3 RR): ratio of the
    horizontal world distance to the pixel distance over the four sides of the wheel
    rectangle. The wheel centres are ~0.3 m above the road, so this is the ground GSD to
    well under 1 % at 60-150 m."""
    ratios = []
    for i, j in ((0, 2), (1, 3), (0, 1), (2, 3)):
        dp = float(np.hypot(*(kp[i, :2] - kp[j, :2])))
        dw = float(np.hypot(*(world[i, :2] - world[j, :2])))
        if math.isfinite(dp) and math.isfinite(dw) and dp > 1.0:
            ratios.append((dw / dp, dw))
    if not ratios:
        return math.nan
    num = sum(r * w for r, w in ratios)  # weighted by length: the long sides dominate
    return num / sum(w for _, w in ratios)


# ----------------------------------------------------------------------------------------------
# YOLO (CATS Madison) and DOTA


_CLIP_RE = re.compile(r"^(?P<clip>[^_]+)_\(?(?P<idx>\d+)\)?$")


def file_stem(path: Optional[str]) -> str:
    """'images/0_13.jpg' -> '0_13': how split files name images."""
    return os.path.splitext(os.path.basename(path or ""))[0]


def clip_and_index(stem: str) -> Tuple[str, int]:
    """'0_13' -> ('0', 13); 'Drone2_(363)' -> ('Drone2', 363); other names -> (stem, 0)."""
    m = _CLIP_RE.match(stem)
    if not m:
        return stem, 0
    return m.group("clip"), int(m.group("idx"))


def _list_images(folder: str) -> List[str]:
    if not os.path.isdir(folder):
        raise DatasetError(f"{folder}: missing image folder")
    return sorted(p for p in glob.glob(os.path.join(folder, "*"))
                  if p.lower().endswith(IMAGE_EXTS))


def read_yolo(root: str, n_s: int = 3, class_types: Optional[Dict[int, int]] = None) -> List[Sample]:
    """YOLO axis-aligned labels; ``class_types`` maps YOLO class -> type index (-1 unknown car);
    classes not in it are dropped. Default {0: -1}."""
    class_types = {0: -1} if class_types is None else class_types
    out = []
    for img in _list_images(os.path.join(root, "images")):
        stem = file_stem(img)
        lab = os.path.join(root, "labels", stem + ".txt")
        rows = []
        if os.path.isfile(lab):
            with open(lab, "r", encoding="utf-8") as f:
                for ln, line in enumerate(f, start=1):
                    parts = line.split()
                    if not parts:
                        continue
                    if len(parts) != 5:
                        raise DatasetError(f"{lab}:{ln}: expected 'class cx cy w h', got '{line.strip()}'")
                    cls = _num(lab, ln, "class", parts[0], True)
                    vals = [_num(lab, ln, n, v) for n, v in zip(("cx", "cy", "w", "h"), parts[1:])]
                    if cls in class_types:
                        rows.append((class_types[cls], vals))
        a = empty_like_arrays(len(rows), n_s)
        for i, (t, (cx, cy, w, h)) in enumerate(rows):
            a["boxes"][i] = [cx, cy, w, h, 0.0]
            a["types"][i] = t
        a["aa_only"][:] = True
        clip, idx = clip_and_index(stem)
        out.append(Sample(image_path=img, source=f"yolo:{stem}", group=clip, frame_index=idx,
                          normalized=True, **a))
    return out


DEFAULT_DOTA_CLASSES = {"small-vehicle": -1, "large-vehicle": LARGE}


def quad_to_box(quad: np.ndarray) -> np.ndarray:
    """Rotated box (cx, cy, length, width, angle) of a quadrilateral [4, 2]: the length axis is
    the longer pair of opposite sides (mean lengths), its angle that of the first such side's
    direction (an axis: the heading is unknown)."""
    q = np.asarray(quad, np.float64)
    c = q.mean(0)
    e = [q[(i + 1) % 4] - q[i] for i in range(4)]
    l01 = 0.5 * (np.hypot(*e[0]) + np.hypot(*e[2]))
    l12 = 0.5 * (np.hypot(*e[1]) + np.hypot(*e[3]))
    if l01 >= l12:
        d = e[0] - e[2]  # both sides in the same direction
        length, width = l01, l12
    else:
        d = e[1] - e[3]
        length, width = l12, l01
    ang = math.atan2(d[1], d[0]) % (2 * math.pi)
    return np.array([c[0], c[1], length, width, ang])


def read_dota(root: str, n_s: int = 3, class_map: Optional[Dict[str, int]] = None,
              label_dir: str = "labelTxt") -> List[Sample]:
    class_map = DEFAULT_DOTA_CLASSES if class_map is None else class_map
    out = []
    for img in _list_images(os.path.join(root, "images")):
        stem = file_stem(img)
        lab = os.path.join(root, label_dir, stem + ".txt")
        rows, gsd = [], math.nan
        if os.path.isfile(lab):
            with open(lab, "r", encoding="utf-8") as f:
                for ln, line in enumerate(f, start=1):
                    s = line.strip()
                    if not s:
                        continue
                    if s.startswith("imagesource:"):
                        continue
                    if s.startswith("gsd:"):
                        txt = s[4:].strip()
                        try:
                            gsd = float(txt)
                        except ValueError:
                            gsd = math.nan  # 'gsd:null' occurs in DOTA
                        continue
                    parts = s.split()
                    if len(parts) not in (9, 10):
                        raise DatasetError(f"{lab}:{ln}: expected 'x1 y1 ... x4 y4 class "
                                           f"difficult', got '{s}'")
                    quad = np.array([_num(lab, ln, f"p{k}", v) for k, v in enumerate(parts[:8])])
                    cls = parts[8]
                    diff = len(parts) == 10 and parts[9] not in ("0",)
                    if cls in class_map:
                        rows.append((class_map[cls], quad.reshape(4, 2), diff))
        a = empty_like_arrays(len(rows), n_s)
        for i, (t, quad, diff) in enumerate(rows):
            a["boxes"][i] = quad_to_box(quad)
            a["types"][i] = t
            a["ignore"][i] = diff
            a["gsd_m"][i] = gsd
        out.append(Sample(image_path=img, source=f"dota:{stem}", group=stem, **a))
    return out


# ----------------------------------------------------------------------------------------------
# near-duplicate-free split


def dhash(image_rgb_or_gray: np.ndarray) -> np.ndarray:
    """64-bit difference hash (bool [64]): grayscale 9x8 area-resized, horizontal gradient signs."""
    import cv2

    g = image_rgb_or_gray
    if g.ndim == 3:
        g = cv2.cvtColor(g, cv2.COLOR_RGB2GRAY)
    s = cv2.resize(g, (9, 8), interpolation=cv2.INTER_AREA).astype(np.int16)
    return (s[:, 1:] > s[:, :-1]).ravel()


def dhash_file(path: str) -> np.ndarray:
    import cv2

    g = cv2.imread(path, cv2.IMREAD_REDUCED_GRAYSCALE_4)
    if g is None:
        raise DatasetError(f"{path}: cannot decode image (missing or corrupt)")
    return dhash(g)


def split_near_duplicate_free(samples: Sequence[Sample], val_fraction: float = 0.2, seed: int = 0,
                              max_group_share: float = 0.25, block: int = 50, gap: int = 10,
                              hash_threshold: int = 8, hashes: Optional[np.ndarray] = None):
    """See the module docstring. ``hashes`` ([N, 64] bool) may be given (tests); otherwise
    they are computed from the image files (or loaded images)."""
    n = len(samples)
    rng = np.random.default_rng(seed)
    by_group: Dict[str, List[int]] = {}
    for i, s in enumerate(samples):
        by_group.setdefault(s.group, []).append(i)
    units: List[Tuple[str, List[int]]] = []  # (unit name, indices)
    big_groups = set()
    for g, idx in sorted(by_group.items()):
        if len(idx) > max_group_share * n and len(by_group) > 1 or len(by_group) == 1:
            big_groups.add(g)
            blocks: Dict[int, List[int]] = {}
            for i in idx:
                blocks.setdefault(samples[i].frame_index // block, []).append(i)
            for b, bi in sorted(blocks.items()):
                units.append((f"{g}#{b}", bi))
        else:
            units.append((g, idx))
    order = rng.permutation(len(units))
    target = val_fraction * n
    val_units = set()
    count = 0
    for k in order:
        if count >= target:
            break
        if count + len(units[k][1]) > 1.5 * target and count > 0:
            continue
        val_units.add(k)
        count += len(units[k][1])
    train_idx, val_idx = [], []
    for k, (_, idx) in enumerate(units):
        (val_idx if k in val_units else train_idx).extend(idx)
    # gap at block boundaries of split groups: drop validation frames close to a training frame
    train_frames: Dict[str, np.ndarray] = {}
    for g in big_groups:
        train_frames[g] = np.array([samples[i].frame_index for i in train_idx
                                    if samples[i].group == g])
    dropped_gap = []
    kept_val = []
    for i in val_idx:
        g = samples[i].group
        tf = train_frames.get(g)
        if tf is not None and len(tf) and np.abs(tf - samples[i].frame_index).min() <= gap:
            dropped_gap.append(i)
        else:
            kept_val.append(i)
    # perceptual-hash check
    if hashes is None:
        hashes = np.stack([dhash(s.image) if s.image is not None else dhash_file(s.image_path)
                           for s in samples])
    hashes = np.asarray(hashes, bool)
    dropped_hash = []
    final_val = []
    if train_idx:
        th = hashes[train_idx]
        for i in kept_val:
            d = (th != hashes[i][None]).sum(1).min()
            (dropped_hash if d <= hash_threshold else final_val).append(i)
    else:
        final_val = kept_val
    min_dist = None
    if train_idx and final_val:
        vh = hashes[final_val].astype(np.int16)
        th = hashes[train_idx].astype(np.int16)
        # Hamming distance as dot products: d = |a| + |b| - 2 a.b
        d = vh.sum(1)[:, None] + th.sum(1)[None, :] - 2 * vh @ th.T
        min_dist = int(d.min())
    report = {
        "total": n, "train": len(train_idx), "val": len(final_val),
        "val_dropped_gap": len(dropped_gap), "val_dropped_hash": len(dropped_hash),
        "train_groups": sorted({samples[i].group for i in train_idx}),
        "val_groups": sorted({samples[i].group for i in final_val}),
        "split_groups": sorted(big_groups), "hash_threshold_bits": hash_threshold,
        "min_val_train_hash_distance": min_dist,
        "train_boxes": int(sum(len(samples[i]) for i in train_idx)),
        "val_boxes": int(sum(len(samples[i]) for i in final_val)),
        # file stems, so other tools (vp_evaluate --val-list) evaluate exactly this split
        "val_stems": sorted(file_stem(samples[i].image_path) for i in final_val
                            if samples[i].image_path),
        # the images dropped from validation (gap, hash) are in neither list: they are too
        # close to a training frame to validate and may be too close to a validation frame to train
        "train_stems": sorted(file_stem(samples[i].image_path) for i in train_idx
                              if samples[i].image_path),
    }
    return [samples[i] for i in train_idx], [samples[i] for i in final_val], report


def split_from_file(samples: Sequence[Sample], path: str):
    """The split written by split_near_duplicate_free (split_real.py, a run's split.json):
    images whose file stem is in its ``val_stems`` validate; those in ``train_stems`` train
    (a file without that list: all other images). Lets a run use the evaluation's split
    exactly, also on a copy of the folder that holds only the training images."""
    import json

    try:
        with open(path) as f:
            doc = json.load(f)
        val_stems = set(doc["val_stems"])
        train_stems = set(doc["train_stems"]) if "train_stems" in doc else None
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise SystemExit(f"--real-split {path}: not a split file with val_stems ({e})")
    train, val = [], []
    for s in samples:
        stem = file_stem(s.image_path)
        if stem in val_stems:
            val.append(s)
        elif train_stems is None or stem in train_stems:
            train.append(s)
    report = {
        "total": len(samples), "train": len(train), "val": len(val), "from_file": path,
        "val_stems_missing": len(val_stems) - len(val),
        "train_boxes": int(sum(len(s) for s in train)),
        "val_boxes": int(sum(len(s) for s in val)),
        "val_stems": sorted(val_stems),
        "train_stems": sorted(train_stems) if train_stems is not None else None,
    }
    return train, val, report
