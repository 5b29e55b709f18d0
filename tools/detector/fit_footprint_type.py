#!/usr/bin/python3
"""Fit the footprint type evidence (perception/footprint_type.hpp) to a crop network.

The application weighs each lifted car's type probabilities by its ground footprint:
``log p_t += a_t * clamp((L - 4.6 m) / 0.4 m) + b_t * clamp((ln(L / W) - ln 2.35) / 0.1)``
over the six car types (Large untouched; clamp to +-2.5). This tool fits a and b for the crop
network the runs were made with: it matches each run's detections (``<sequence>_detections.csv``,
docs/detections_file.md: type probabilities and the lifted ``length_m`` / ``width_m``) to the
sequence's ground truth (``datasets.read_sequence``: the training's reader and ignore rule) with
seed 000's rule (rotated IoU >= 0.5), leaves out detections at the
frame edge and those most likely Large, as the application does, and minimises the multinomial
log-loss of the weighed probabilities plus --l2 times the weights' squares. Run the application
with the evidence off so the probabilities are the crop network's own::

  scripts/eval_tracking.sh --build build/ci --set perception.footprint_type=false RUN DATA/tune/*
  tools/detector/fit_footprint_type.py --run RUN --data DATA/tune \\
      [--check RUN2 --check-data DATA/val ...] [--folds 3] [--types estate,compact,sports,sedan]

Prints the fitted weights as the C++ defaults of FootprintTypeOptions, the matched vehicles and
the top-1 type accuracy (OA-1) before and after on the fitting runs, on each --check pair, and
with --folds K the gain over K sequence folds (fit on the others, counted on the fold) — choose
--l2 with that, not with the check sets.

Run with Debian's Python (/usr/bin/python3).
"""
from __future__ import annotations

import argparse
import csv
import glob
import os
import sys
from typing import List, Sequence, Tuple

import numpy as np
import torch

if __package__ in (None, ""):
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from detector.asm import TYPES  # noqa: E402
from detector.datasets import DatasetError, read_sequence  # noqa: E402
from detector.evaluate import match  # noqa: E402

CARS = TYPES.index("large")  # the car types come first
REFERENCE_LENGTH_M, LENGTH_SCALE_M = 4.6, 0.4
REFERENCE_ASPECT, ASPECT_SCALE = 2.35, 0.1
MAX_TERM = 2.5
BOX = ("box_cx_px", "box_cy_px", "box_length_px", "box_width_px", "box_angle_rad")


class FitError(Exception):
    pass


def _rows(path: str) -> List[dict]:
    try:
        with open(path, newline="") as f:
            return list(csv.DictReader(line for line in f if not line.startswith("#")))
    except OSError as e:
        raise FitError(f"{path}: {e.strerror}") from None


def _float(row: dict, key: str, path: str, line: int) -> float:
    try:
        return float(row[key])
    except (KeyError, TypeError, ValueError):
        raise FitError(f"{path}: row {line}: column '{key}' missing or not a number") from None


def matched_pairs(run_dir: str, data_dir: str) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(features [N, 9]: 7 probabilities, length_m, width_m; truth type [N]; sequence index [N])
    of the matched lifted detections inside the frame whose most likely type is a car. The
    references and their ignore rule are datasets.read_sequence's (the training's)."""
    paths = sorted(glob.glob(os.path.join(run_dir, "*_detections.csv")))
    if not paths:
        raise FitError(f"{run_dir}: no <sequence>_detections.csv files")
    feats, truth, seqs = [], [], []
    for s, path in enumerate(paths):
        seq = os.path.basename(path)[: -len("_detections.csv")]
        try:
            samples = read_sequence(os.path.join(data_dir, seq))
        except (DatasetError, OSError) as e:
            raise FitError(str(e)) from None
        by_frame: dict = {}
        for line, r in enumerate(_rows(path), start=2):
            by_frame.setdefault(int(_float(r, "frame_id", path, line)), []).append((line, r))
        for sample in samples:
            dets = by_frame.get(sample.frame_index, [])
            if not dets or not len(sample):
                continue
            p = np.array([[_float(r, k, path, n) for k in BOX] for n, r in dets])
            score = np.array([_float(r, "score", path, n) for n, r in dets])
            pairs, _, _ = match(p, score, sample.boxes, sample.ignore, 0.5)
            for pi, gi in pairs:
                line, r = dets[pi]
                probs = [_float(r, "p_" + t, path, line) for t in TYPES]
                if (r.get("at_frame_edge") == "1" or int(np.argmax(probs)) == CARS
                        or r.get("lift_status") != "ok"):
                    continue
                feats.append(probs + [_float(r, "length_m", path, line),
                                      _float(r, "width_m", path, line)])
                truth.append(int(sample.types[gi]))
                seqs.append(s)
    if not feats:
        raise FitError(f"{run_dir}: no lifted car detection matched the ground truth of {data_dir}")
    return np.array(feats), np.array(truth), np.array(seqs)


def terms(x: np.ndarray) -> np.ndarray:
    """[N, 2]: the clamped length and aspect terms of features x."""
    length, width = x[:, 7], x[:, 8]
    t = np.stack([(length - REFERENCE_LENGTH_M) / LENGTH_SCALE_M,
                  (np.log(length / width) - np.log(REFERENCE_ASPECT)) / ASPECT_SCALE], 1)
    return np.clip(t, -MAX_TERM, MAX_TERM)


def weighed_logits(x: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Log-probabilities of the six car types moved by weights w [6, 2] (Large not compared:
    only car detections are fitted)."""
    return np.log(np.clip(x[:, :CARS], 1e-30, 1.0)) + terms(x) @ w.T


def fit(x: np.ndarray, y: np.ndarray, l2: float, types: Sequence[int] = range(CARS)) -> np.ndarray:
    """Weights [6, 2] minimising the log-loss over the car types plus l2 * |w|^2; only the rows
    of `types` are fitted, the others stay 0."""
    keep = y < CARS  # a car typed as one of the cars; a Large reference cannot be fixed here
    logp = torch.tensor(np.log(np.clip(x[keep, :CARS], 1e-30, 1.0)), dtype=torch.float64)
    t = torch.tensor(terms(x[keep]), dtype=torch.float64)
    target = torch.tensor(y[keep])
    free = torch.tensor(sorted(set(types)), dtype=torch.long)
    w = torch.zeros(len(free), 2, dtype=torch.float64, requires_grad=True)
    opt = torch.optim.LBFGS([w], max_iter=500, line_search_fn="strong_wolfe")

    def weights() -> torch.Tensor:
        return torch.zeros(CARS, 2, dtype=torch.float64).index_copy(0, free, w)

    def closure():
        opt.zero_grad()
        loss = torch.nn.functional.cross_entropy(logp + t @ weights().T, target) + \
            l2 * (w ** 2).sum()
        loss.backward()
        return loss

    opt.step(closure)
    return weights().detach().numpy()


def accuracy(x: np.ndarray, y: np.ndarray, w: np.ndarray) -> Tuple[float, float]:
    return float((x[:, :CARS].argmax(1) == y).mean()), float(
        (weighed_logits(x, w).argmax(1) == y).mean())


def fold_gain(x: np.ndarray, y: np.ndarray, seq: np.ndarray, folds: int, l2: float,
              types: Sequence[int] = range(CARS)) -> int:
    """Vehicles typed right more (or fewer) when each of `folds` sequence folds is weighed
    with the weights fitted on the others."""
    order = np.random.default_rng(0).permutation(np.unique(seq))
    gain = 0
    for part in np.array_split(order, folds):
        test = np.isin(seq, part)
        w = fit(x[~test], y[~test], l2, types)
        gain += int((weighed_logits(x[test], w).argmax(1) == y[test]).sum()) - int(
            (x[test, :CARS].argmax(1) == y[test]).sum())
    return gain


def cpp_defaults(w: np.ndarray) -> str:
    def row(values) -> str:
        return ", ".join(f"{v:.4f}" for v in values) + ", 0.0"
    return (f"lengthWeight{{{row(w[:, 0])}}}\naspectWeight{{{row(w[:, 1])}}}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="See the module docstring (--help of the source) for "
                                        "the details.")
    ap.add_argument("--run", required=True, action="append",
                    help="application run folder (<sequence>_detections.csv); repeatable")
    ap.add_argument("--data", required=True, action="append",
                    help="the folder of the sequences of the --run at the same position")
    ap.add_argument("--check", action="append", default=[],
                    help="a held-out run folder to report OA-1 on; repeatable")
    ap.add_argument("--check-data", action="append", default=[],
                    help="the sequences' folder of the --check at the same position")
    ap.add_argument("--l2", type=float, default=0.01, help="weight penalty (default 0.01)")
    ap.add_argument("--types", default="estate,compact,sports,sedan",
                    help="the car types whose weights are fitted, comma-separated (the others "
                         "stay 0; default estate,compact,sports,sedan: the shipped weights leave "
                         "suv and van alone, whose boundary the footprint mostly shifts)")
    ap.add_argument("--folds", type=int, default=0,
                    help="also report the gain over this many sequence folds (0: not)")
    a = ap.parse_args(argv)
    if len(a.run) != len(a.data) or len(a.check) != len(a.check_data):
        ap.error("each --run needs one --data and each --check one --check-data")
    if not a.l2 >= 0.0:
        ap.error("--l2 must be >= 0")
    names = [n.strip() for n in a.types.split(",") if n.strip()]
    unknown = [n for n in names if n not in TYPES[:CARS]]
    if unknown or not names:
        ap.error(f"--types: not car types: {', '.join(unknown) or '(none)'} "
                 f"(choose from {', '.join(TYPES[:CARS])})")
    types = [TYPES.index(n) for n in names]
    try:
        parts = [matched_pairs(r, d) for r, d in zip(a.run, a.data)]
        x = np.concatenate([p[0] for p in parts])
        y = np.concatenate([p[1] for p in parts])
        seq = np.concatenate([p[2] + 10000 * i for i, p in enumerate(parts)])
        w = fit(x, y, a.l2, types)
        before, after = accuracy(x, y, w)
        print(f"fitted on {len(y)} lifted car detections: OA-1 {100 * before:.1f} -> "
              f"{100 * after:.1f} %")
        if a.folds > 1:
            print(f"gain over {a.folds} sequence folds: {fold_gain(x, y, seq, a.folds, a.l2, types):+d} "
                  f"of {len(y)} vehicles")
        for r, d in zip(a.check, a.check_data):
            cx, cy, _ = matched_pairs(r, d)
            b, c = accuracy(cx, cy, w)
            print(f"{r}: {len(cy)} lifted car detections, OA-1 {100 * b:.1f} -> {100 * c:.1f} %")
        print("FootprintTypeOptions defaults:\n" + cpp_defaults(w))
    except FitError as e:
        print(f"fit_footprint_type: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
