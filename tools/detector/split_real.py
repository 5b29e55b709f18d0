#!/usr/bin/python3
"""Writes the near-duplicate-free train/validation split of a YOLO image folder as JSON.

    tools/detector/split_real.py --real ../shared/data/real/cats-madison --out split.json [--seed 0]

The split is the one train.py uses with the same --seed (datasets.split_near_duplicate_free:
whole clips to one side, block cuts with a frame gap in the large clips, then a dHash check);
the JSON's ``val_stems`` lists the validation file stems for ``vp_evaluate --val-list``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys

if __package__ in (None, ""):
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from detector.datasets import read_yolo, split_near_duplicate_free  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--real", required=True, help="YOLO folder (images/, labels/)")
    p.add_argument("--out", required=True, help="JSON file to write")
    p.add_argument("--seed", type=int, default=0, help="the training run's --seed")
    args = p.parse_args(argv)
    _, _, report = split_near_duplicate_free(read_yolo(args.real), seed=args.seed)
    with open(args.out, "w") as f:
        json.dump(report, f, indent=1)
    print(f"{args.out}: {report['train']} train / {report['val']} validation images")
    return 0


if __name__ == "__main__":
    sys.exit(main())
