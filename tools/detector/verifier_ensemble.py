#!/usr/bin/env python3
"""Two verifiers in one crop network: their vehicle logits averaged.

The crop network's verifier (``vehicle_logit``: does the crop show a vehicle?) decides on the
cars and the background whose probability lies near its threshold, and two verifiers trained
on different data disagree there in different ways: one refuses two-tone and dark cars, the
other lets roof fixtures through. This tool writes a checkpoint whose verifier is the mean of
the logits of two checkpoints' verifiers, exactly, with no new operator in the exported graph:
the verifier branch becomes a fully connected layer twice as wide (each verifier's own layer,
or the shared one of a checkpoint without a branch, side by side) and the head takes half of
each verifier's head over its half. Everything else (both stages' other weights) is the
``--base`` checkpoint's; the two verifiers must sit on the same crop-network body (a branch
trained with ``train.py --verifier-head-only`` on top of the base does).

  verifier_ensemble.py --base A.pt --other B.pt --out AB.pt [--weight W] [--edge-base]

``--weight`` is B's share of the mean (default 0.5). With ``--edge-base`` the network also
outputs ``vehicle_logit_edge``: A's verifier alone, exactly (a second head over the same branch,
A's head over A's half and zero over B's), which the application uses for vehicles cut by the
frame's border — so that the mean decides inside the frame and the border keeps A's decisions.
The result exports with ``export.py`` like any checkpoint (``CropNet.from_state_dict`` reads the
branch's width and the second head).
"""
from __future__ import annotations

import argparse
import os
import sys
from typing import Dict, Tuple

import torch

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _verifier_parts(crop: Dict[str, torch.Tensor], name: str) -> Tuple[torch.Tensor, ...]:
    """(fc weight, fc bias, head weight, head bias) of one checkpoint's verifier: its own branch
    when it has one, else the shared fully connected layer."""
    if "vehicle_logit.weight" not in crop:
        raise SystemExit(f"verifier_ensemble.py: {name}: the crop network has no verifier "
                         "(vehicle_logit)")
    fc = "verifier_fc.0" if "verifier_fc.0.weight" in crop else "fc.0"
    return (crop[f"{fc}.weight"], crop[f"{fc}.bias"], crop["vehicle_logit.weight"],
            crop["vehicle_logit.bias"])


def merge(base: Dict[str, torch.Tensor], other: Dict[str, torch.Tensor],
          weight: float, edge_base: bool = False) -> Dict[str, torch.Tensor]:
    """The base crop network's state with a verifier branch holding both verifiers, whose head
    gives (1 - weight) x base's logit + weight x other's; with ``edge_base`` also the head
    ``vehicle_logit_edge`` giving base's logit alone."""
    # Both verifiers must read the same features, the body's (each brings its own fully
    # connected layer into the branch).
    for key in [k for k in base if k.startswith("body.")]:
        if key not in other or not torch.equal(base[key], other[key]):
            raise SystemExit(f"verifier_ensemble.py: the two crop networks differ in {key}: "
                             "their verifiers do not read the same features")
    fa, ba, ha, hba = _verifier_parts(base, "--base")
    fb, bb, hb, hbb = _verifier_parts(other, "--other")
    if fa.shape != fb.shape:
        raise SystemExit(f"verifier_ensemble.py: verifier layers of different shapes "
                         f"({tuple(fa.shape)} vs {tuple(fb.shape)})")
    out = dict(base)
    out["verifier_fc.0.weight"] = torch.cat([fa, fb], dim=0)
    out["verifier_fc.0.bias"] = torch.cat([ba, bb], dim=0)
    out["vehicle_logit.weight"] = torch.cat([(1.0 - weight) * ha, weight * hb], dim=1)
    out["vehicle_logit.bias"] = (1.0 - weight) * hba + weight * hbb
    if edge_base:
        out["vehicle_logit_edge.weight"] = torch.cat([ha, torch.zeros_like(hb)], dim=1)
        out["vehicle_logit_edge.bias"] = hba.clone()
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--base", required=True, help="checkpoint whose weights the result keeps")
    p.add_argument("--other", required=True, help="checkpoint whose verifier joins base's")
    p.add_argument("--out", required=True, help="checkpoint to write")
    p.add_argument("--weight", type=float, default=0.5, help="--other's share of the mean, [0, 1]")
    p.add_argument("--edge-base", action="store_true",
                   help="also output --base's verifier alone (vehicle_logit_edge), the one the "
                        "application uses for vehicles cut by the frame's border")
    a = p.parse_args(argv)
    if not 0.0 <= a.weight <= 1.0:
        raise SystemExit(f"verifier_ensemble.py: --weight must be in [0, 1], got {a.weight}")
    cks = []
    for path in (a.base, a.other):
        try:
            ck = torch.load(path, map_location="cpu", weights_only=False)
        except (OSError, RuntimeError) as e:
            raise SystemExit(f"verifier_ensemble.py: {path}: {e}") from None
        if not isinstance(ck, dict) or "crop" not in ck or ck["crop"] is None:
            raise SystemExit(f"verifier_ensemble.py: {path}: not a checkpoint with a crop network")
        cks.append(ck)
    out = {k: v for k, v in cks[0].items() if not k.startswith("opt_")}
    out["crop"] = merge(cks[0]["crop"], cks[1]["crop"], a.weight, a.edge_base)
    torch.save(out, a.out)
    print(f"verifier_ensemble.py: {a.out}: verifier = {1 - a.weight:g} x {a.base} + "
          f"{a.weight:g} x {a.other} (branch {out['crop']['verifier_fc.0.weight'].shape[0]} wide)"
          + (f"; at the frame's border {a.base}'s alone" if a.edge_base else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
