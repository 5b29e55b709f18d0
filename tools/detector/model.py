"""The detector networks (PyTorch), built only from operators the int8 engine runs.

Contract
--------
Two models, each exported as its own ONNX (opset 13, input [1, 3, H, W] float = normalised
8-bit RGB image, ``NORMALIZATION`` below; docs/inference.md lists the allowed operators:
Conv (+BN folded at export, + Relu), Add, Resize nearest x2, Sigmoid - nothing else is used).

``Detector`` (first stage, whole frame at the working resolution, default 672 x 512 = the
2592 x 2048 camera frame downscaled 4x to 648 x 512, ~12 cm GSD at 90 m, padded right to a
multiple of 32). Compact MobileNetV2-style backbone (inverted residuals, ReLU) to stride 32,
FPN-lite (1x1 laterals, nearest x2 up-sampling + Add) down to stride 4, CenterNet-style dense
heads at stride 4. Outputs (NCHW, H/4 x W/4):

============ === ===================================================================
name         ch  meaning at a cell (feature coords f = (u - 1.5) / 4 for stride 4)
============ === ===================================================================
heatmap      1   vehicle centre score (Sigmoid in the exported model; logits in training)
offset       2   sub-cell centre offset (du, dv) in cells, centre = cell + offset
size         2   log(length_px), log(width_px) at the working resolution
direction    2   (cos a, sin a) of the driving direction, not normalised (decode: atan2)
type         7   (single-stage variant only) type logits at the centre cell
shape        n_s (single-stage variant only) ASM gamma at the centre cell
============ === ===================================================================

``CropNet`` (second stage): for each detection, the application cuts a rotated,
direction-aligned patch of the full-resolution image, ``CROP_H x CROP_W`` = 48 x 96 px at
``CROP_GSD_M`` = 6 cm/px (5.76 m x 2.88 m), vehicle pointing +x (right), its left side up;
see ``crops.py``. Outputs (all [1, C, 1, 1]): ``type_logits`` (7), ``shape`` (n_s gamma),
``flip_logit`` (1: > 0 means the crop's +x is the vehicle's *rear*: turn the heading by
180 deg), ``refine`` (5: du_m, dv_m of the true centre in the crop frame (x forward, y
right/down), d_angle rad (axis residual, true - crop, in (-pi/2, pi/2]), length_m, width_m).
The last layers are convolutions whose kernel covers the whole 3 x 6 map (an exact
"fully connected" layer that keeps front/back layout, unlike a global pool).

``macs(model, (h, w))`` counts multiply-accumulates of the convolutions (BN folded).
"""

from __future__ import annotations

from typing import Dict, Tuple

import torch
import torch.nn as nn
import torch.nn.functional as F

NUM_TYPES = 7
STRIDE = 4
CROP_H, CROP_W = 48, 96
CROP_GSD_M = 0.06
# Normalisation written into the ONNX metadata (vp.input.*): x = (v - mean) * scale, RGB order.
NORMALIZATION = dict(channel_order="rgb", mean=(128.0, 128.0, 128.0), scale=(1 / 64.0,) * 3)
DEFAULT_INPUT_HW = (512, 672)


def normalize(images_uint8: torch.Tensor) -> torch.Tensor:
    """uint8/float [B, 3, H, W] RGB 0..255 -> the network input."""
    m = torch.tensor(NORMALIZATION["mean"], dtype=torch.float32, device=images_uint8.device)
    s = torch.tensor(NORMALIZATION["scale"], dtype=torch.float32, device=images_uint8.device)
    return (images_uint8.float() - m.view(1, 3, 1, 1)) * s.view(1, 3, 1, 1)


class ConvBN(nn.Sequential):
    def __init__(self, cin, cout, k=3, stride=1, groups=1, relu=True):
        layers = [nn.Conv2d(cin, cout, k, stride, (k - 1) // 2 if isinstance(k, int) else 0,
                            groups=groups, bias=False), nn.BatchNorm2d(cout)]
        if relu:
            layers.append(nn.ReLU(inplace=True))
        super().__init__(*layers)


class InvertedResidual(nn.Module):
    def __init__(self, cin, cout, stride, expand):
        super().__init__()
        mid = cin * expand
        self.use_res = stride == 1 and cin == cout
        layers = []
        if expand != 1:
            layers.append(ConvBN(cin, mid, 1))
        layers += [ConvBN(mid, mid, 3, stride, groups=mid), ConvBN(mid, cout, 1, relu=False)]
        self.body = nn.Sequential(*layers)

    def forward(self, x):
        y = self.body(x)
        return x + y if self.use_res else y


class SepConv(nn.Sequential):
    """Depthwise 3x3 + pointwise, both with BN + ReLU."""

    def __init__(self, cin, cout):
        super().__init__(ConvBN(cin, cin, 3, groups=cin), ConvBN(cin, cout, 1))


class Head(nn.Sequential):
    def __init__(self, cin, mid, cout, bias_init=0.0):
        last = nn.Conv2d(mid, cout, 1)
        nn.init.normal_(last.weight, std=0.01)
        nn.init.constant_(last.bias, bias_init)
        super().__init__(SepConv(cin, mid), last)


class Detector(nn.Module):
    def __init__(self, n_s: int = 3, width: int = 48, single_stage: bool = False):
        super().__init__()
        self.n_s = n_s
        self.single_stage = single_stage
        self.export_mode = False
        self.stem = ConvBN(3, 16, 3, 2)                                         # /2
        self.s4 = nn.Sequential(InvertedResidual(16, 24, 2, 3), InvertedResidual(24, 24, 1, 3))
        self.s8 = nn.Sequential(InvertedResidual(24, 32, 2, 3), InvertedResidual(32, 32, 1, 3))
        self.s16 = nn.Sequential(InvertedResidual(32, 64, 2, 4), InvertedResidual(64, 64, 1, 4),
                                 InvertedResidual(64, 64, 1, 4))
        self.s32 = nn.Sequential(InvertedResidual(64, 96, 2, 4), InvertedResidual(96, 96, 1, 4))
        self.lat32 = ConvBN(96, width, 1)
        self.lat16 = ConvBN(64, width, 1)
        self.lat8 = ConvBN(32, width, 1)
        self.lat4 = ConvBN(24, width, 1)
        self.smooth8 = SepConv(width, width)
        self.smooth4 = SepConv(width, width)
        self.hm = Head(width, 32, 1, bias_init=-4.6)  # prior 0.01
        self.offset = Head(width, 32, 2)
        self.size = Head(width, 32, 2, bias_init=3.0)
        self.direction = Head(width, 32, 2)
        if single_stage:
            self.type_head = Head(width, 48, NUM_TYPES)
            self.shape_head = Head(width, 32, n_s)

    @staticmethod
    def _up(x):
        return F.interpolate(x, scale_factor=2.0, mode="nearest")

    def features(self, x):
        c2 = self.stem(x)
        c4 = self.s4(c2)
        c8 = self.s8(c4)
        c16 = self.s16(c8)
        c32 = self.s32(c16)
        p32 = self.lat32(c32)
        p16 = self.lat16(c16) + self._up(p32)
        p8 = self.smooth8(self.lat8(c8) + self._up(p16))
        p4 = self.smooth4(self.lat4(c4) + self._up(p8))
        return p4

    def forward(self, x) -> Dict[str, torch.Tensor]:
        p4 = self.features(x)
        hm = self.hm(p4)
        out = {"heatmap": torch.sigmoid(hm) if self.export_mode else hm,
               "offset": self.offset(p4), "size": self.size(p4),
               "direction": self.direction(p4)}
        if self.single_stage:
            out["type"] = self.type_head(p4)
            out["shape"] = self.shape_head(p4)
        return out

    def output_names(self):
        names = ["heatmap", "offset", "size", "direction"]
        return names + (["type", "shape"] if self.single_stage else [])


class CropNet(nn.Module):
    """The second stage. With ``verifier`` it also outputs ``vehicle_logit``: whether the crop
    shows a vehicle at all (the first stage's box may sit on a planter, a shadow or a roof
    fixture), trained on mined false detections (train.py --verifier-samples). With
    ``verifier_edge`` a second verifier output, ``vehicle_logit_edge``, on the same features:
    the one the application uses for vehicles cut by the frame's border
    (verifier_ensemble.py --edge-base)."""

    def __init__(self, n_s: int = 3, verifier: bool = False, flip_branch: bool = False,
                 verifier_branch: bool = False, verifier_width: int = 192,
                 verifier_edge: bool = False):
        super().__init__()
        if verifier_branch and not verifier:
            raise ValueError("CropNet: verifier_branch needs verifier")
        if verifier_edge and not verifier:
            raise ValueError("CropNet: verifier_edge needs verifier")
        self.n_s = n_s
        self.verifier = verifier
        self.flip_branch = flip_branch
        self.verifier_branch = verifier_branch
        self.verifier_edge = verifier_edge
        self.export_mode = False
        self.body = nn.Sequential(
            ConvBN(3, 24, 3, 2),                       # 24 x 48
            SepConv(24, 32),
            ConvBN(32, 32, 3, 2, groups=32), ConvBN(32, 64, 1),   # 12 x 24
            SepConv(64, 64),
            ConvBN(64, 64, 3, 2, groups=64), ConvBN(64, 96, 1),   # 6 x 12
            SepConv(96, 96),
            ConvBN(96, 96, 3, 2, groups=96), ConvBN(96, 128, 1),  # 3 x 6
        )
        self.fc = nn.Sequential(nn.Conv2d(128, 192, (CROP_H // 16, CROP_W // 16)),
                                nn.ReLU(inplace=True))
        self.type_logits = nn.Conv2d(192, NUM_TYPES, 1)
        self.shape = nn.Conv2d(192, n_s, 1)
        self.flip_logit = nn.Conv2d(192, 1, 1)
        self.refine = nn.Conv2d(192, 5, 1)
        heads = [self.type_logits, self.shape, self.flip_logit, self.refine]
        if verifier:
            self.vehicle_logit = nn.Conv2d(verifier_width if verifier_branch else 192, 1, 1)
            heads.append(self.vehicle_logit)
        if verifier_edge:
            self.vehicle_logit_edge = nn.Conv2d(verifier_width if verifier_branch else 192, 1, 1)
            heads.append(self.vehicle_logit_edge)
        for m in heads:
            nn.init.normal_(m.weight, std=0.01)
            nn.init.zeros_(m.bias)
        if flip_branch:
            # Front/back from its own fully connected layer on the body's map, so that it can
            # learn from real crops that carry only a direction (train.py --heading-samples
            # --flip-head-only) while type, shape, refinement and verifier stay as they are.
            self.flip_fc = nn.Sequential(nn.Conv2d(128, 192, (CROP_H // 16, CROP_W // 16)),
                                         nn.ReLU(inplace=True))
        if verifier_branch:
            # The verifier from its own fully connected layer likewise (train.py
            # --verifier-branch --verifier-head-only): more capacity for "vehicle or not" than a
            # single output on the shared features, which type, shape and refinement keep. A
            # wider branch (verifier_width 384) holds two verifiers side by side, their logits
            # averaged by the head (verifier_ensemble.py).
            self.verifier_fc = nn.Sequential(nn.Conv2d(128, verifier_width,
                                                       (CROP_H // 16, CROP_W // 16)),
                                             nn.ReLU(inplace=True))

    def start_flip_branch_from_shared(self) -> None:
        """Copies the shared fully connected layer into the flip branch: the branch then gives
        exactly the shared flip output, the starting point of its fine-tuning."""
        self.flip_fc[0].load_state_dict(self.fc[0].state_dict())

    def start_verifier_branch_from_shared(self) -> None:
        """Copies the shared fully connected layer into the verifier branch: the branch then
        gives exactly the shared verifier output, the starting point of its fine-tuning."""
        self.verifier_fc[0].load_state_dict(self.fc[0].state_dict())

    def forward(self, x) -> Dict[str, torch.Tensor]:
        b = self.body(x)
        f = self.fc(b)
        flip_in = self.flip_fc(b) if self.flip_branch else f
        verifier_in = self.verifier_fc(b) if self.verifier_branch else f
        out = {"type_logits": self.type_logits(f), "shape": self.shape(f),
               "flip_logit": self.flip_logit(flip_in), "refine": self.refine(f)}
        if self.verifier:
            out["vehicle_logit"] = self.vehicle_logit(verifier_in)
        if self.verifier_edge:
            out["vehicle_logit_edge"] = self.vehicle_logit_edge(verifier_in)
        return out

    @classmethod
    def from_state_dict(cls, state: Dict[str, torch.Tensor], n_s: int) -> "CropNet":
        """A CropNet with the weights of a checkpoint's ``crop`` entry, with the verifier head
        when the checkpoint has one."""
        net = cls(n_s=n_s, verifier="vehicle_logit.weight" in state,
                  flip_branch="flip_fc.0.weight" in state,
                  verifier_branch="verifier_fc.0.weight" in state,
                  verifier_width=int(state["verifier_fc.0.weight"].shape[0])
                  if "verifier_fc.0.weight" in state else 192,
                  verifier_edge="vehicle_logit_edge.weight" in state)
        net.load_state_dict(state)
        return net

    def output_names(self):
        return ["type_logits", "shape", "flip_logit", "refine"] + (
            ["vehicle_logit"] if self.verifier else []) + (
            ["vehicle_logit_edge"] if self.verifier_edge else [])


# refine output scaling: raw * REFINE_SCALE = (du_m, dv_m, d_angle_rad, length_m, width_m)
REFINE_SCALE = (0.5, 0.5, 0.2, 1.0, 1.0)
REFINE_OFFSET = (0.0, 0.0, 0.0, 4.5, 1.8)


def macs(model: nn.Module, input_hw: Tuple[int, int]) -> Dict[str, int]:
    """Multiply-accumulates of every Conv2d for one [1, 3, H, W] input: {'total', per module}."""
    counts: Dict[str, int] = {}
    hooks = []

    def hook(name):
        def fn(mod, inp, out):
            kh, kw = mod.kernel_size
            cin = mod.in_channels // mod.groups
            counts[name] = int(out.numel() * cin * kh * kw)
        return fn

    for name, mod in model.named_modules():
        if isinstance(mod, nn.Conv2d):
            hooks.append(mod.register_forward_hook(hook(name)))
    was_training = model.training
    model.eval()
    with torch.no_grad():
        model(torch.zeros(1, 3, *input_hw))
    model.train(was_training)
    for h in hooks:
        h.remove()
    counts["total"] = sum(counts.values())
    return counts
