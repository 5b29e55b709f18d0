"""Losses of the detector and the crop classifier (seed 000 section 3.6, CenterNet).

Contract (all functions take torch tensors and return a scalar tensor; an empty selection
gives 0 with a gradient path, never NaN):

* ``focal_heatmap_loss(logits, target, weight)``: CenterNet's penalty-reduced focal loss
  (alpha 2, beta 4), normalised by the number of peaks (>= 1); ``weight`` 0 masks ignore regions.
* ``detector_loss(outputs, batch, ...)``: heatmap + L1 centre offset + L1 log size (rotated
  boxes) + direction (L1 on (cos, sin) of the normalised prediction where the direction is
  known; on the doubled angle (cos 2a, sin 2a) where only the axis is known) + the
  axis-aligned enclosing-box loss (L1 on log w, log h of the box enclosing the predicted rotated
  box, for every object with an axis-aligned box: the real images' only size supervision) and,
  for the single-stage variant, type cross-entropy and the shape loss read at the centre cell.
  Returns (total, {name: float}).
* ``shape_loss_l1(pred, gamma)``: V_L1, seed Eq. 5: mean over vehicles of sum_s (g^ - g)^2.
* ``ShapeLossL2(asm)``: V_L2, seed Eq. 6: mean over vehicles and keypoints of
  ||M(g^)_k - M(g)_k||_2 in metres (all 36 keypoints, or ``keypoints=EVAL_KEYPOINTS``).
  Exactly 0 at the truth (safe norm), positive otherwise.
* ``crop_loss(outputs, batch, shape_loss)``: type CE + shape (V_L1 or V_L2) + flip BCE +
  refine L1 (scaled by ``model.REFINE_SCALE``).
Rows whose type is -1 or gamma is NaN are left out of the respective terms.
"""

from __future__ import annotations

from typing import Dict, Optional, Sequence

import torch
import torch.nn.functional as F

from detector.asm import Asm
from detector.model import REFINE_OFFSET, REFINE_SCALE


def _zero(ref: torch.Tensor) -> torch.Tensor:
    return ref.sum() * 0.0


def focal_heatmap_loss(logits, target, weight=None, alpha: float = 2.0, beta: float = 4.0):
    p = torch.sigmoid(logits).clamp(1e-4, 1 - 1e-4)
    pos = target.eq(1).float()
    neg = 1.0 - pos
    w = torch.ones_like(target) if weight is None else weight
    pos_loss = -torch.log(p) * (1 - p) ** alpha * pos
    neg_loss = -torch.log(1 - p) * p ** alpha * (1 - target) ** beta * neg * w
    n = pos.sum().clamp(min=1.0)
    return (pos_loss.sum() + neg_loss.sum()) / n


def gather(feat: torch.Tensor, ind: torch.Tensor) -> torch.Tensor:
    """feat [B, C, h, w], ind [B, K] -> [B, K, C]."""
    b, c = feat.shape[:2]
    f = feat.view(b, c, -1).permute(0, 2, 1)
    return f.gather(1, ind.unsqueeze(-1).expand(-1, -1, c))


def shape_loss_l1(pred: torch.Tensor, gamma: torch.Tensor) -> torch.Tensor:
    """V_L1 (Eq. 5). pred, gamma [N, n_s]."""
    if pred.shape[0] == 0:
        return _zero(pred)
    return ((pred - gamma) ** 2).sum(-1).mean()


class ShapeLossL2:
    """V_L2 (Eq. 6) through the ASM: M(g^) - M(g) = sum_s (g^_s - g_s) sigma_s e_s."""

    def __init__(self, asm: Asm, keypoints: Optional[Sequence[int]] = None):
        _, basis = asm.torch_basis()  # [n_s, 36, 3]
        if keypoints is not None:
            basis = basis[:, list(keypoints)]
        self.basis = basis

    def __call__(self, pred: torch.Tensor, gamma: torch.Tensor) -> torch.Tensor:
        if pred.shape[0] == 0:
            return _zero(pred)
        basis = self.basis.to(pred.device, pred.dtype)
        d = torch.einsum("ns,skc->nkc", pred - gamma, basis)  # [N, K, 3]
        sq = (d ** 2).sum(-1)
        # safe norm: exactly 0 (and zero gradient) at the truth, sqrt elsewhere
        nz = sq > 0
        norm = torch.where(nz, torch.sqrt(torch.where(nz, sq, torch.ones_like(sq))),
                           torch.zeros_like(sq))
        return norm.mean()


def make_shape_loss(kind: str, asm: Asm):
    if kind == "l1":
        return shape_loss_l1
    if kind == "l2":
        return ShapeLossL2(asm)
    raise ValueError(f"shape loss must be 'l1' (V_L1) or 'l2' (V_L2), not {kind!r}")


def _dir_loss(pred, target, known):
    """pred [M, 2] raw (cos, sin); target [M, 2] unit; known [M] bool (else axis only)."""
    u = pred / pred.norm(dim=-1, keepdim=True).clamp(min=1e-6)
    full = (u - target).abs().sum(-1)
    c2, s2 = u[:, 0] ** 2 - u[:, 1] ** 2, 2 * u[:, 0] * u[:, 1]
    t2c, t2s = target[:, 0] ** 2 - target[:, 1] ** 2, 2 * target[:, 0] * target[:, 1]
    axis = (c2 - t2c).abs() + (s2 - t2s).abs()
    # keep the raw vector near unit length (int8 range, well-defined angle)
    norm_reg = 0.1 * (pred.norm(dim=-1) - 1.0).abs()
    return torch.where(known, full, axis) + norm_reg


def detector_loss(out: Dict[str, torch.Tensor], batch: Dict[str, torch.Tensor],
                  shape_loss=None, weights: Optional[Dict[str, float]] = None):
    wts = {"heatmap": 1.0, "offset": 1.0, "size": 1.0, "direction": 1.0, "aa": 1.0,
           "type": 0.5, "shape": 0.5}
    if weights:
        wts.update(weights)
    terms: Dict[str, torch.Tensor] = {}
    terms["heatmap"] = focal_heatmap_loss(out["heatmap"], batch["heatmap"], batch["hm_weight"])
    mask = batch["mask"] > 0
    ind = batch["ind"]
    off = gather(out["offset"], ind)[mask]
    terms["offset"] = (F.l1_loss(off, batch["offset"][mask], reduction="none").sum(-1).mean()
                       if off.shape[0] else _zero(out["offset"]))
    size = gather(out["size"], ind)[mask]
    direc = gather(out["direction"], ind)[mask]
    rot = batch["rot"][mask] > 0
    if rot.any():
        terms["size"] = (size[rot] - batch["log_size"][mask][rot]).abs().sum(-1).mean()
        terms["direction"] = _dir_loss(direc[rot], batch["direction"][mask][rot],
                                       batch["dir_known"][mask][rot] > 0).mean()
    else:
        terms["size"] = _zero(out["size"])
        terms["direction"] = _zero(out["direction"])
    if off.shape[0]:
        l = torch.exp(size[:, 0])
        w = torch.exp(size[:, 1])
        u = direc / direc.norm(dim=-1, keepdim=True).clamp(min=1e-6)
        ac, as_ = u[:, 0].abs(), u[:, 1].abs()
        aw = (l * ac + w * as_).clamp(min=1e-3)
        ah = (l * as_ + w * ac).clamp(min=1e-3)
        pred_aa = torch.stack([torch.log(aw), torch.log(ah)], -1)
        # rotated boxes already have their own size loss: the AA term only for axis-aligned rows
        aa_rows = ~rot
        terms["aa"] = ((pred_aa[aa_rows] - batch["log_aa"][mask][aa_rows]).abs().sum(-1).mean()
                       if aa_rows.any() else _zero(size))
    else:
        terms["aa"] = _zero(out["size"])
    if "type" in out:
        t = batch["type"][mask]
        logits = gather(out["type"], ind)[mask]
        known = t >= 0
        terms["type"] = (F.cross_entropy(logits[known], t[known]) if known.any()
                         else _zero(out["type"]))
        g = batch["gamma"][mask]
        gk = ~torch.isnan(g).any(-1)
        sl = shape_loss or shape_loss_l1
        terms["shape"] = sl(gather(out["shape"], ind)[mask][gk], g[gk])
    total = sum(wts[k] * v for k, v in terms.items())
    return total, {k: float(v.detach()) for k, v in terms.items()}


def crop_loss(out: Dict[str, torch.Tensor], batch: Dict[str, torch.Tensor], shape_loss,
              weights: Optional[Dict[str, float]] = None):
    wts = {"type": 1.0, "shape": 1.0, "flip": 1.0, "refine": 1.0, "vehicle": 1.0}
    if weights:
        wts.update(weights)
    terms = {}
    logits = out["type_logits"].flatten(1)
    t = batch["type"]
    known = t >= 0
    terms["type"] = F.cross_entropy(logits[known], t[known]) if known.any() else _zero(logits)
    g = batch["gamma"]
    gk = ~torch.isnan(g).any(-1)
    terms["shape"] = shape_loss(out["shape"].flatten(1)[gk], g[gk])
    # Verifier crops (batch["full"] False: a mined box, vehicle or not) train only the
    # verifier head; their type is -1 and gamma NaN, so those terms skip them already.
    full = batch["full"] if "full" in batch else torch.ones_like(t, dtype=torch.bool)
    # Heading crops (real vehicles whose only label is the driving direction) train the flip
    # output and nothing else of the full targets.
    flip_known = full | batch["flip_known"] if "flip_known" in batch else full
    terms["flip"] = F.binary_cross_entropy_with_logits(out["flip_logit"].flatten()[flip_known],
                                                       batch["flip"].float()[flip_known])
    sc = torch.tensor(REFINE_SCALE, device=logits.device)
    of = torch.tensor(REFINE_OFFSET, device=logits.device)
    pred = out["refine"].flatten(1)[full] * sc + of
    terms["refine"] = ((pred - batch["refine"][full]).abs() / sc).sum(-1).mean()
    if "vehicle_logit" in out and "vehicle" in batch:
        terms["vehicle"] = F.binary_cross_entropy_with_logits(out["vehicle_logit"].flatten(),
                                                              batch["vehicle"].float())
    total = sum(wts[k] * v for k, v in terms.items())
    return total, {k: float(v.detach()) for k, v in terms.items()}
