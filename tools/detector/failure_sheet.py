#!/usr/bin/python3
"""Contact sheet of detector failures on real images, for the model card.

Reads a failure list that ``eval_rotated_real.py`` wrote (``--list-reversed``, ``--list-false``
or ``--list-missed``; or ``eval_large_real.py --list-failures``: CSV with an ``image`` column and a label box ``cx_px cy_px length_px
width_px heading_rad`` and/or a detection box ``det_cx_px det_cy_px det_length_px det_width_px
det_angle_rad``, pixels, the project's image convention; a box whose fields are all empty is
absent from that row) and draws one tile per row: the image
around the box, the label in green and the detection in red, each with an arrow from its centre
to its front, and the image's stem below. Tiles are cut around the label box where there is
one, else around the detection, scaled so that a box fills about half of the tile.

  tools/detector/failure_sheet.py --root ../shared/data/real/bev-intersection-de \\
      --list false.csv --out false.jpg [--tile-px 160] [--columns 8] [--max 48]

Run with Debian's Python (/usr/bin/python3).
"""
from __future__ import annotations

import argparse
import csv
import math
import os
import sys
from typing import Dict, List, Optional, Tuple

import cv2
import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from detector.eval_rotated_real import image_path  # noqa: E402

LABEL_KEYS = ("cx_px", "cy_px", "length_px", "width_px", "heading_rad")
DETECTION_KEYS = ("det_cx_px", "det_cy_px", "det_length_px", "det_width_px", "det_angle_rad")
GREEN, RED = (60, 200, 60), (40, 40, 230)


class SheetError(Exception):
    """A failure list or image that cannot be drawn; the message names the file and row."""


def box_of(row: Dict[str, str], keys: Tuple[str, ...], where: str) -> Optional[np.ndarray]:
    if not all(k in row for k in keys) or all(not row[k] for k in keys):
        return None  # no such box in this list, or none in this row (all fields empty)
    try:
        box = np.array([float(row[k]) for k in keys])
    except ValueError:
        raise SheetError(f"{where}: not a number in {[row[k] for k in keys]}") from None
    if not np.all(np.isfinite(box)) or box[2] <= 0 or box[3] <= 0:
        raise SheetError(f"{where}: box sizes must be finite and > 0")
    return box


def read_list(path: str) -> List[Tuple[str, Optional[np.ndarray], Optional[np.ndarray]]]:
    """[(image stem, label box or None, detection box or None)] of a failure list."""
    rows = []
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        if reader.fieldnames is None or "image" not in reader.fieldnames:
            raise SheetError(f"{path}: no 'image' column (a list from eval_rotated_real.py?)")
        for line_no, row in enumerate(reader, start=2):
            where = f"{path}:{line_no}"
            label, det = box_of(row, LABEL_KEYS, where), box_of(row, DETECTION_KEYS, where)
            if label is None and det is None:
                raise SheetError(f"{where}: neither a label box ({', '.join(LABEL_KEYS)}) nor a "
                                 f"detection box ({', '.join(DETECTION_KEYS)})")
            rows.append((row["image"], label, det))
    return rows


def draw_box(img: np.ndarray, box: np.ndarray, colour, scale: float, origin: np.ndarray) -> None:
    cx, cy, length, width, angle = box
    centre = (np.array([cx, cy]) - origin) * scale
    forward = np.array([math.cos(angle), math.sin(angle)])
    side = np.array([-forward[1], forward[0]])
    half_l, half_w = 0.5 * length * scale, 0.5 * width * scale
    corners = [centre + sl * half_l * forward + sw * half_w * side
               for sl, sw in ((1, 1), (1, -1), (-1, -1), (-1, 1))]
    cv2.polylines(img, [np.round(np.array(corners)).astype(np.int32)], True, colour, 1, cv2.LINE_AA)
    tip = centre + half_l * forward
    cv2.arrowedLine(img, tuple(int(v) for v in np.round(centre)), tuple(int(v) for v in np.round(tip)),
                    colour, 1, cv2.LINE_AA, tipLength=0.3)


def tile(image: np.ndarray, stem: str, label, det, tile_px: int) -> np.ndarray:
    anchor = label if label is not None else det
    extent = 2.0 * max(anchor[2], anchor[3])  # the box fills about half of the tile
    scale = tile_px / extent
    origin = anchor[:2] - 0.5 * extent
    # The affine warp cuts and scales in one step and pads outside the image with grey.
    m = np.array([[scale, 0, -origin[0] * scale], [0, scale, -origin[1] * scale]])
    out = cv2.warpAffine(image, m, (tile_px, tile_px), flags=cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=(90, 90, 90))
    if label is not None:
        draw_box(out, label, GREEN, scale, origin)
    if det is not None:
        draw_box(out, det, RED, scale, origin)
    caption = np.full((16, tile_px, 3), 255, np.uint8)
    cv2.putText(caption, stem[-22:], (2, 12), cv2.FONT_HERSHEY_SIMPLEX, 0.35, (0, 0, 0), 1, cv2.LINE_AA)
    return np.vstack([out, caption])


def find_image(root: str, stem: str) -> str:
    path = image_path(root, stem)
    if path is None:
        raise SheetError(f"{root}/images: no image for '{stem}'")
    return path


def sheet(root: str, rows, tile_px: int, columns: int) -> np.ndarray:
    images: Dict[str, np.ndarray] = {}
    tiles = []
    for stem, label, det in rows:
        if stem not in images:
            path = find_image(root, stem)
            img = cv2.imread(path, cv2.IMREAD_COLOR)
            if img is None:
                raise SheetError(f"{path}: not an image OpenCV reads")
            images[stem] = img
        tiles.append(tile(images[stem], stem, label, det, tile_px))
    blank = np.full_like(tiles[0], 255)
    while len(tiles) % columns:
        tiles.append(blank)
    return np.vstack([np.hstack(tiles[i:i + columns]) for i in range(0, len(tiles), columns)])


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--root", required=True, help="folder with images/ (the real set)")
    p.add_argument("--list", required=True,
                   help="failure list CSV from eval_rotated_real.py or eval_large_real.py")
    p.add_argument("--out", required=True, help="picture to write (.jpg or .png)")
    p.add_argument("--tile-px", type=int, default=160, help="side of one tile in pixels")
    p.add_argument("--columns", type=int, default=8, help="tiles per row")
    p.add_argument("--max", type=int, default=48, help="draw at most this many rows (0: all)")
    a = p.parse_args(argv)
    if a.tile_px < 32 or a.columns < 1 or a.max < 0:
        p.error("--tile-px must be >= 32, --columns >= 1, --max >= 0")
    try:
        rows = read_list(a.list)
        if not rows:
            raise SheetError(f"{a.list}: no failures listed")
        if a.max:
            rows = rows[:a.max]
        picture = sheet(a.root, rows, a.tile_px, a.columns)
    except (SheetError, OSError) as e:
        print(f"failure_sheet.py: {e}", file=sys.stderr)
        return 1
    if not cv2.imwrite(a.out, picture, [cv2.IMWRITE_JPEG_QUALITY, 85]):
        print(f"failure_sheet.py: {a.out}: could not write (extension .jpg or .png?)", file=sys.stderr)
        return 1
    print(f"failure_sheet.py: {len(rows)} tiles -> {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
