#!/usr/bin/python3
"""Turns shipped ONNX files back into a training checkpoint, so that a next round can start
from the shipped weights when the training run's own checkpoint is gone.

    tools/detector/import_onnx.py --detector models/detector/detector_int8.onnx \
        --crop models/detector/crop_int8.onnx --out RUNDIR/checkpoint.pt \
        [--calib-data SEQDIR ...] [--calib-count 32]

Contract
--------
* Input: ``export.py``'s files, float (``*_fp32.onnx``) or QDQ int8 (``*_int8.onnx``): every Conv
  reads its weight either as a float initializer or through a DequantizeLinear of an int8
  initializer (per channel), and its bias as a float initializer. The int8 weights are
  dequantized ((q - zero_point) * scale): the checkpoint holds what the int8 file computes with,
  not the float weights it was quantized from.
* Conv nodes are matched to the PyTorch model's ``Conv2d`` modules in execution order (a forward
  pass with hooks gives the module order; ONNX keeps the graph in that order), each pair checked
  for kernel shape, groups, stride and padding. The model is ``Detector`` resp. ``CropNet``
  (with the verifier head when the file has a ``vehicle_logit`` output, and the border's second
  verifier head when it has ``vehicle_logit_edge``).
* Batch norm was folded into the convolutions at export. A Conv2d followed by a BatchNorm2d
  (``ConvBN``) gets the folded weight W and the BN gets running statistics (m, v) of the
  convolution's output W x on the calibration inputs, gamma = sqrt(v + eps), beta = m + b
  (b = the folded bias): in eval mode BN(W x) = W x + b exactly, and in train mode, where BN
  uses the batch's own statistics, it is close to that on data like the calibration inputs, so
  fine-tuning starts where the file is. Without calibration inputs (m, v) = (0, 1 - eps).
* Check: the imported modules (eval mode) are run against ``qdq.Evaluator`` on the file with its
  activation Q/DQ removed (what the float backends compute); the largest difference relative to
  each output's range is printed and the import fails above 1e-3.
* Output: a checkpoint with the keys ``export.load_run`` and ``train.py --init-from`` read
  (``detector``, ``crop``, ``n_s``, ``single_stage``, ``step``, ``args``), and ``imported_from``.
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import Dict, List, Optional, Tuple

if __package__ in (None, ""):
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np
import onnx
import torch
import torch.nn as nn

from detector.asm import REPO_ROOT
from detector.model import CROP_H, CROP_W, CropNet, Detector, normalize

sys.path.insert(0, os.path.join(REPO_ROOT, "tools", "quantize"))
import qdq  # noqa: E402

MAX_RELATIVE_ERROR = 1e-3  # of an output's range; float rounding is ~1e-6


def conv_weights(model: onnx.ModelProto) -> List[Tuple[onnx.NodeProto, np.ndarray, Optional[np.ndarray]]]:
    """(Conv node, float weight, float bias or None) in graph order. A weight or bias must be
    constant: an initializer or a DequantizeLinear of one, evaluated by ``qdq.Evaluator``."""
    init = {t.name for t in model.graph.initializer}
    producer = {o: n for n in model.graph.node for o in n.output}
    env = qdq.Evaluator(model).run(
        {model.graph.input[0].name: np.zeros(qdq.input_shape_of(model), np.float32)}, keep_all=True)

    def value(name: str, what: str, node: onnx.NodeProto) -> np.ndarray:
        src = producer.get(name)
        if name in init or (src is not None and src.op_type == "DequantizeLinear"
                            and src.input[0] in init):
            return env[name].astype(np.float32)
        raise ValueError(f"Conv '{node.name or node.output[0]}': its {what} '{name}' is neither an "
                         "initializer nor a DequantizeLinear of one")

    out = []
    for node in model.graph.node:
        if node.op_type != "Conv":
            continue
        w = value(node.input[1], "weight", node)
        b = value(node.input[2], "bias", node) if len(node.input) > 2 and node.input[2] else None
        out.append((node, w, b))
    return out


def convs_in_order(module: nn.Module, input_hw: Tuple[int, int]) -> List[Tuple[str, nn.Conv2d]]:
    """(name, Conv2d) in the order a forward pass calls them."""
    order: List[Tuple[str, nn.Conv2d]] = []
    hooks = [m.register_forward_hook(lambda mod, i, o, n=n: order.append((n, mod)))
             for n, m in module.named_modules() if isinstance(m, nn.Conv2d)]
    was = module.training
    module.eval()
    try:
        with torch.no_grad():
            module(torch.zeros(1, 3, *input_hw))
    except RuntimeError as exc:
        raise ValueError(f"{type(module).__name__} does not run at the file's input size "
                         f"{input_hw[0]} x {input_hw[1]}: {str(exc).splitlines()[0]}") from None
    finally:
        module.train(was)
        for h in hooks:
            h.remove()
    return order


def following_batchnorm(module: nn.Module, conv_name: str) -> Optional[nn.BatchNorm2d]:
    """The BatchNorm2d right after ``conv_name`` in its Sequential (ConvBN), if any."""
    parent_name, _, idx = conv_name.rpartition(".")
    if not idx.isdigit():
        return None
    parent = module.get_submodule(parent_name) if parent_name else module
    nxt = str(int(idx) + 1)
    bn = getattr(parent, nxt, None) if isinstance(parent, nn.Sequential) else None
    return bn if isinstance(bn, nn.BatchNorm2d) else None


def load_into(module: nn.Module, model: onnx.ModelProto, input_hw: Tuple[int, int],
              calib: Optional[torch.Tensor] = None) -> int:
    """Copies the file's convolutions into ``module`` (see the contract); returns their count."""
    convs = conv_weights(model)
    order = convs_in_order(module, input_hw)
    if len(convs) != len(order):
        raise ValueError(f"the file has {len(convs)} Conv nodes, the model {len(order)} Conv2d")
    folded: List[Tuple[nn.Conv2d, nn.BatchNorm2d, torch.Tensor]] = []
    with torch.no_grad():
        for (node, w, b), (name, conv) in zip(convs, order):
            a = qdq._attrs(node)
            pads = qdq._pads4(node, a)
            checks = {"weight shape": (tuple(w.shape), tuple(conv.weight.shape)),
                      "groups": (int(a.get("group", 1)), conv.groups),
                      "strides": (tuple(a.get("strides", [1, 1])), tuple(conv.stride)),
                      "pads": (tuple(pads[:2]), tuple(conv.padding))}
            for what, (got, want) in checks.items():
                if got != want:
                    raise ValueError(f"Conv '{node.output[0]}' -> module '{name}': {what} {got} "
                                     f"in the file, {want} in the model")
            conv.weight.copy_(torch.from_numpy(w))
            bias = torch.from_numpy(b) if b is not None else torch.zeros(w.shape[0])
            bn = following_batchnorm(module, name)
            if bn is None:
                if conv.bias is None:
                    raise ValueError(f"module '{name}' has neither a bias nor a batch norm for "
                                     f"the bias of Conv '{node.output[0]}'")
                conv.bias.copy_(bias)
                continue
            if conv.bias is not None:
                raise ValueError(f"module '{name}': a Conv2d with a bias before a batch norm")
            # Identity + bias first (exact in eval mode), statistics below.
            bn.running_mean.zero_()
            bn.running_var.fill_(1.0 - bn.eps)
            bn.weight.fill_(1.0)
            bn.bias.copy_(bias)
            folded.append((conv, bn, bias))
        if calib is not None and folded:
            stats: Dict[int, Tuple[torch.Tensor, torch.Tensor]] = {}
            hooks = [conv.register_forward_hook(
                lambda mod, i, o, k=k: stats.__setitem__(
                    k, (o.mean(dim=(0, 2, 3)), o.var(dim=(0, 2, 3), unbiased=False))))
                for k, (conv, _, _) in enumerate(folded)]
            was = module.training
            module.eval()
            module(calib)
            module.train(was)
            for h in hooks:
                h.remove()
            for k, (conv, bn, bias) in enumerate(folded):
                m, v = stats[k]
                v = v.clamp_min(1e-6)
                bn.running_mean.copy_(m)
                bn.running_var.copy_(v)
                bn.weight.copy_(torch.sqrt(v + bn.eps))
                bn.bias.copy_(m + bias)
    return len(convs)


def check_against_file(module: nn.Module, model: onnx.ModelProto, x: torch.Tensor) -> Dict[str, float]:
    """Largest |torch - file| per output, relative to the larger of the file output's range
    over the inputs and its largest magnitude."""
    ev = qdq.Evaluator(qdq.strip_activation_qdq(model))
    inp = model.graph.input[0].name
    module.eval()
    module.export_mode = True
    with torch.no_grad():
        got = module(x)
    module.export_mode = False
    refs: Dict[str, list] = {}
    for i in range(x.shape[0]):
        for k, r in ev.run({inp: x[i:i + 1].numpy()}).items():
            refs.setdefault(k, []).append(r)
    errs = {}
    for k, rs in refs.items():
        r = np.concatenate(rs)
        span = max(float(r.max() - r.min()), float(np.abs(r).max()), 1e-6)
        errs[k] = float(np.abs(got[k].numpy() - r).max()) / span
    return errs


def load_model(path: str) -> onnx.ModelProto:
    """The ONNX file at ``path``, or a ValueError naming it."""
    if not os.path.isfile(path):
        raise ValueError(f"no file '{path}'")
    try:
        return onnx.load(path)
    except Exception as exc:  # protobuf's DecodeError and friends: not an ONNX file
        raise ValueError(f"'{path}' is not an ONNX model ({type(exc).__name__}: {exc})") from None


def input_hw_of(model: onnx.ModelProto) -> Tuple[int, int]:
    return tuple(qdq.input_shape_of(model)[2:])  # type: ignore[return-value]


def normalized(images_uint8: np.ndarray) -> torch.Tensor:
    """uint8 NHWC RGB images -> the network input (NCHW, ``model.normalize``)."""
    return normalize(torch.from_numpy(np.ascontiguousarray(images_uint8)).permute(0, 3, 1, 2))


def import_files(detector_path: str, crop_path: Optional[str], n_s: int,
                 calib_det: Optional[np.ndarray] = None, calib_crop: Optional[np.ndarray] = None,
                 log=print) -> dict:
    det_model = load_model(detector_path)
    hw = input_hw_of(det_model)
    det = Detector(n_s=n_s)
    x_det = normalized(calib_det) if calib_det is not None and len(calib_det) else None
    n = load_into(det, det_model, hw, x_det)
    check_x = x_det[:2] if x_det is not None else torch.randn(1, 3, *hw)
    errs = check_against_file(det, det_model, check_x)
    log(f"detector: {n} convolutions from {detector_path}; largest relative difference "
        + ", ".join(f"{k} {v:.1e}" for k, v in errs.items()))
    bad = {k: v for k, v in errs.items() if v > MAX_RELATIVE_ERROR}
    crop = None
    if crop_path:
        crop_model = load_model(crop_path)
        if input_hw_of(crop_model) != (CROP_H, CROP_W):
            raise ValueError(f"{crop_path}: input {input_hw_of(crop_model)}, the crop network "
                             f"takes {(CROP_H, CROP_W)}")
        outputs = {o.name for o in crop_model.graph.output}
        verifier = "vehicle_logit" in outputs
        verifier_edge = "vehicle_logit_edge" in outputs  # a second verifier for the border
        n_convs = sum(node.op_type == "Conv" for node in crop_model.graph.node)
        plain = len(convs_in_order(CropNet(n_s=n_s, verifier=verifier,
                                           verifier_edge=verifier_edge), (CROP_H, CROP_W)))
        # Each branch (front/back, verifier) is one more fully connected Conv of the same shape;
        # with one extra Conv the file's outputs tell which branch it is.
        extra = n_convs - plain
        layouts = [(f, v) for v in (False, True) for f in (False, True)
                   if f + v == extra and (verifier or not v)]
        if not layouts:
            raise ValueError(f"{crop_path}: {n_convs} Conv nodes fit no crop network layout "
                             f"({plain} without branches, at most {plain + 2})")
        x_crop = normalized(calib_crop) if calib_crop is not None and len(calib_crop) else None
        check_x = x_crop[:8] if x_crop is not None else torch.randn(4, 3, CROP_H, CROP_W)
        # The fully connected Convs (shared, branches) are 192 wide; a verifier branch holding
        # two verifiers averaged (verifier_ensemble.py) is wider: the widest of them.
        fc_shape = (128, CROP_H // 16, CROP_W // 16)
        verifier_width = max(w.shape[0] for _, w, _ in conv_weights(crop_model)
                             if tuple(w.shape[1:]) == fc_shape)
        for flip_branch, verifier_branch in layouts:
            crop = CropNet(n_s=n_s, verifier=verifier, flip_branch=flip_branch,
                           verifier_branch=verifier_branch, verifier_width=verifier_width,
                           verifier_edge=verifier_edge)
            n = load_into(crop, crop_model, (CROP_H, CROP_W), x_crop)
            errs = check_against_file(crop, crop_model, check_x)
            if max(errs.values()) <= MAX_RELATIVE_ERROR:
                break
        log(f"crop network: {n} convolutions from {crop_path}"
            f"{' (with the verifier head)' if crop.verifier else ''}; largest relative "
            "difference " + ", ".join(f"{k} {v:.1e}" for k, v in errs.items()))
        bad.update({f"crop {k}": v for k, v in errs.items() if v > MAX_RELATIVE_ERROR})
    if bad:
        raise ValueError("the imported model does not compute what the file computes: "
                         + ", ".join(f"{k} {v:.1e}" for k, v in bad.items()))
    step = 0
    for m in [det_model] + ([crop_model] if crop_path else []):
        meta = {p.key: p.value for p in m.metadata_props}
        if meta.get("vp.model.version", "").isdigit():
            step = max(step, int(meta["vp.model.version"]))
    return {"detector": det.state_dict(), "crop": crop.state_dict() if crop else None,
            "n_s": n_s, "single_stage": False, "shape_loss": "l1", "step": step,
            "args": {}, "imported_from": [detector_path] + ([crop_path] if crop_path else [])}


def parse_args(argv=None):
    p = argparse.ArgumentParser(
        description="Rebuild a training checkpoint from exported ONNX files (float or int8 QDQ).",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--detector", required=True, help="first-stage ONNX file")
    p.add_argument("--crop", default=None, help="crop-network ONNX file")
    p.add_argument("--out", required=True, help="checkpoint path to write")
    p.add_argument("--calib-data", nargs="*", default=[],
                   help="sequences whose frames and ground-truth crops set the batch-norm "
                        "statistics (without: identity statistics)")
    p.add_argument("--calib-count", type=int, default=32, help="frames drawn for the statistics")
    p.add_argument("--working-width", type=int, default=648)
    p.add_argument("--asm", default=None, help="ASM file (n_s); default: the shipped one")
    p.add_argument("--seed", type=int, default=0)
    return p.parse_args(argv)


def main(argv=None) -> int:
    args = parse_args(argv)
    from detector.asm import load_asm
    from detector.export import calibration_images

    asm = load_asm(args.asm) if args.asm else load_asm()
    calib_det = calib_crop = None
    try:
        if args.calib_data:
            ns = argparse.Namespace(calib_data=args.calib_data, calib_real=None,
                                    calib_real_split=None, calib_count=args.calib_count,
                                    working_width=args.working_width, calib_verifier_samples=[])
            hw = input_hw_of(load_model(args.detector))
            calib_det, calib_crop = calibration_images(ns, hw, asm.n_s,
                                                       np.random.default_rng(args.seed))
        ck = import_files(args.detector, args.crop, asm.n_s, calib_det, calib_crop)
    except (ValueError, OSError) as exc:
        raise SystemExit(f"import_onnx.py: {exc}")
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    torch.save(ck, args.out)
    print(f"wrote {args.out} (step {ck['step']})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
