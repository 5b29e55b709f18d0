#!/usr/bin/python3
"""Copies the training side of a real-image split (YOLO folder) with its split file, to carry
to a machine that must not see the validation images (e.g. a lent GPU machine).

    tools/detector/device/pack_real_split.py --real ../shared/data/real/cats-madison \\
        --split split.json --out DIR [--max-mib 56]

The split file is split_real.py's (``train_stems``, ``val_stems``). ``--max-mib`` leaves out
every k-th training image, evenly, until the images fit (a transfer limit); train.py then reads
DIR with ``--real DIR --real-split DIR/split.json``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys

if __package__ in (None, ""):
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))

from detector.datasets import file_stem, read_yolo, split_from_file  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--real", required=True, help="YOLO folder (images/, labels/)")
    p.add_argument("--split", required=True, help="split_real.py's JSON (with train_stems)")
    p.add_argument("--out", required=True, help="folder to create")
    p.add_argument("--max-mib", type=float, default=0.0, help="size limit of the images (0: none)")
    a = p.parse_args(argv)
    train, _, report = split_from_file(read_yolo(a.real), a.split)
    if report["train_stems"] is None:
        raise SystemExit(f"{a.split}: no train_stems (write it with tools/detector/split_real.py)")
    images = sorted(s.image_path for s in train)  # the training side, in file order
    sizes = [os.path.getsize(f) for f in images]
    limit = a.max_mib * 2**20 if a.max_mib > 0 else float("inf")

    def kept(k):  # every k-th image left out (k = 0: none)
        return [i for i in range(len(images)) if k == 0 or (i + 1) % k != 0]

    for k in [0] + list(range(len(images), 1, -1)):
        keep = kept(k)
        if sum(sizes[i] for i in keep) <= limit:
            break
    else:
        raise SystemExit(f"--max-mib {a.max_mib}: even half of the images do not fit")
    os.makedirs(os.path.join(a.out, "images"))
    os.makedirs(os.path.join(a.out, "labels"))
    for i in keep:
        shutil.copy(images[i], os.path.join(a.out, "images"))
        label = os.path.join(a.real, "labels", file_stem(images[i]) + ".txt")
        if os.path.isfile(label):
            shutil.copy(label, os.path.join(a.out, "labels"))
    shutil.copy(a.split, os.path.join(a.out, "split.json"))
    mib = sum(sizes[i] for i in keep) / 2**20
    print(f"{a.out}: {len(keep)} of {len(images)} training images ({mib:.1f} MiB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
