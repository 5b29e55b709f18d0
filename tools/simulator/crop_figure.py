#!/usr/bin/python3
"""Side-by-side figure of small square crops: one row per --row, each crop IMAGE@CX,CY,HALF
(pixel centre and half size in the source image), scaled to --tile pixels. The docs use it to
put simulated objects beside real frames without storing the real frames (only the small
composite is written). Run with Debian's Python (/usr/bin/python3, OpenCV).

  tools/simulator/crop_figure.py --tile 200 --out docs/images/x.jpg \
      --row "a.png@100,120,80" "b.jpg@300,40,60" --row "c.png@50,50,50" "d.png@20,20,20"
"""
from __future__ import annotations

import argparse
import sys

import cv2
import numpy as np


def crop(spec: str, tile: int) -> np.ndarray:
    path, _, box = spec.rpartition("@")
    try:
        cx, cy, half = (int(v) for v in box.split(","))
    except ValueError:
        sys.exit(f"crop_figure: '{spec}': expected IMAGE@CX,CY,HALF")
    image = cv2.imread(path, cv2.IMREAD_COLOR)
    if image is None:
        sys.exit(f"crop_figure: cannot read image '{path}'")
    h, w = image.shape[:2]
    x0, y0 = max(0, cx - half), max(0, cy - half)
    x1, y1 = min(w, cx + half), min(h, cy + half)
    if x1 - x0 < 4 or y1 - y0 < 4:
        sys.exit(f"crop_figure: '{spec}': the crop lies outside the {w} x {h} image")
    return cv2.resize(image[y0:y1, x0:x1], (tile, tile), interpolation=cv2.INTER_AREA)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--row", nargs="+", action="append", required=True)
    parser.add_argument("--tile", type=int, default=200)
    parser.add_argument("--gap", type=int, default=4)
    parser.add_argument("--quality", type=int, default=85)
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    columns = max(len(r) for r in args.row)
    step = args.tile + args.gap
    canvas = np.full((len(args.row) * step - args.gap, columns * step - args.gap, 3), 255,
                     np.uint8)
    for i, row in enumerate(args.row):
        for j, spec in enumerate(row):
            canvas[i * step:i * step + args.tile, j * step:j * step + args.tile] = crop(spec,
                                                                                        args.tile)
    if not cv2.imwrite(args.out, canvas, [cv2.IMWRITE_JPEG_QUALITY, args.quality]):
        sys.exit(f"crop_figure: cannot write '{args.out}'")
    return 0


if __name__ == "__main__":
    sys.exit(main())
