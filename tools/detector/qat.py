#!/usr/bin/python3
"""Quantization-aware fine-tuning of an exported first stage, and its int8 export.

    tools/detector/train.py --qat-from EXPORTDIR --data ... --out RUNDIR [train options]
    tools/detector/qat.py --checkpoint RUNDIR/checkpoint.pt --out NEWEXPORTDIR

Why
---
Post-training calibration leaves the int8 first stage ~0.6 F1 points behind the same weights
in float (model card, v5). Fine-tuning the weights *through* the int8 rounding lets them settle
where the rounding costs least. This module does it on the exported graphs themselves, so no
mapping between torch modules and ONNX tensors is needed and the fine-tuned network is exactly
the one the engine runs:

Contract
--------
* ``QatDetector.from_export(dir)`` reads ``dir/detector_fp32.onnx`` (the float graph, batch
  norm folded) and ``dir/detector_int8.onnx`` (its QDQ rewrite by tools/quantize/qdq.py). The
  float graph's Conv weights and biases become the trainable parameters. Forward runs the float
  graph with torch kernels and, wherever the QDQ graph has a Q/DQ pair, int8 fake quantization:
  activations with the QDQ graph's fixed (scale, zero point) — the calibration is not moved —
  and Conv weights symmetric per output channel, the scale taken from the current weights as
  qdq.py does at export. Gradients pass straight through the rounding and stop where a value
  saturates (the usual straight-through estimator).
* The output is what ``losses.detector_loss`` expects from ``model.Detector`` in training:
  heatmap *logits* (the input of the graph's Sigmoid, fake-quantized as the engine has it),
  offset, size, direction. The graph's input is the normalised image (``model.normalize``).
* ``QatDetector.export(out_dir)`` writes ``detector_fp32.onnx`` (the trained float weights in
  the original graph) and ``detector_int8.onnx`` = qdq.quantize_model of it with the *same*
  activation ranges, so the engine computes what was trained (up to its bias quantization).
  Without training, the export reproduces the input QDQ file's weights and scales exactly
  (tests/test_qat.py).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
from typing import Dict, List, Tuple

if __package__ in (None, ""):
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np
import onnx
import torch
import torch.nn as nn
from onnx import numpy_helper

from detector.asm import REPO_ROOT

sys.path.insert(0, os.path.join(REPO_ROOT, "tools", "quantize"))
import qdq  # noqa: E402

INT8_MIN, INT8_MAX = -128, 127
WEIGHT_MAX = 127  # symmetric weights: [-127, 127], as qdq.quantize_model


def fake_quant_activation(x: torch.Tensor, scale: float, zero_point: int) -> torch.Tensor:
    """int8 quantize + dequantize with fixed parameters; straight-through gradient inside the
    representable range, zero where the value saturates."""
    q = torch.round(x / scale) + zero_point
    inside = (q >= INT8_MIN) & (q <= INT8_MAX)
    y = (torch.clamp(q, INT8_MIN, INT8_MAX) - zero_point) * scale
    return y.detach() + (x - x.detach()) * inside.to(x.dtype)


def fake_quant_weight(w: torch.Tensor, axis: int) -> torch.Tensor:
    """Symmetric per-channel int8 fake quantization along ``axis`` (scale = max|w| / 127, from
    the current weights, not trained); straight-through gradient."""
    red = tuple(i for i in range(w.dim()) if i != axis)
    absmax = w.detach().abs().amax(dim=red, keepdim=True)
    # float32 division as numpy does it in qdq.quantize_model, so the export matches exactly
    scale = torch.where(absmax > 0, absmax / WEIGHT_MAX, torch.full_like(absmax, 1.0 / WEIGHT_MAX))
    wq = torch.clamp(torch.round(w / scale), -WEIGHT_MAX, WEIGHT_MAX) * scale
    return w + (wq - w).detach()


def _activation_params(qmodel: onnx.ModelProto, names: List[str]) -> Dict[str, Tuple[float, int]]:
    """(scale, zero point) of every activation tensor that the QDQ graph quantizes."""
    init = {t.name: t for t in qmodel.graph.initializer}
    out = {}
    for n in names:
        s, zp = init.get(f"{n}_scale"), init.get(f"{n}_zero_point")
        if s is not None and zp is not None:
            out[n] = (float(numpy_helper.to_array(s)), int(numpy_helper.to_array(zp)))
    return out


class QatDetector(nn.Module):
    """The exported first stage as a trainable module with int8 fake quantization."""

    def __init__(self, float_model: onnx.ModelProto, qdq_model: onnx.ModelProto):
        super().__init__()
        self.float_model = qdq.prepare_float_model(float_model)
        self.qdq_model = qdq_model
        graph = self.float_model.graph
        self.input_name = graph.input[0].name
        self.output_names = [o.name for o in graph.output]
        self.act_params = _activation_params(qdq_model, qdq.activation_tensors(self.float_model))
        if self.input_name not in self.act_params:
            raise ValueError("the QDQ model does not quantize the graph input: not a qdq.py export")
        self.evaluator = qdq.Evaluator(self.float_model)  # op kernels; its constants are read below
        self.param_index: Dict[str, int] = {}
        self.weight_axis: Dict[str, int] = {}
        self.params = nn.ParameterList()
        for node in graph.node:
            if node.op_type not in qdq.WEIGHT_AXIS:
                continue
            for k, name in enumerate(node.input[1:3], start=1):
                if name and name not in self.evaluator.consts:
                    raise ValueError(f"node '{node.name}' ({node.op_type}): input '{name}' is not "
                                     "a constant of the graph (shared by torch.onnx.export?)")
                if name and name not in self.param_index:
                    self.param_index[name] = len(self.params)
                    self.params.append(nn.Parameter(self.evaluator.consts[name].clone().float()))
                if k == 1:
                    self.weight_axis[name] = qdq.WEIGHT_AXIS[node.op_type]
        self.sigmoid_inputs = {n.output[0]: n.input[0] for n in graph.node
                               if n.op_type == "Sigmoid" and n.output[0] in self.output_names}
        missing = [n for n in self.sigmoid_inputs.values() if n not in self.act_params]
        if missing:
            raise ValueError(f"QDQ model does not quantize the Sigmoid inputs {missing}")

    @classmethod
    def from_export(cls, export_dir: str, name: str = "detector") -> "QatDetector":
        paths = [os.path.join(export_dir, f"{name}_{kind}.onnx") for kind in ("fp32", "int8")]
        for p in paths:
            if not os.path.isfile(p):
                raise SystemExit(f"--qat-from {export_dir}: no {os.path.basename(p)} (an "
                                 "export.py output folder is expected)")
        return cls(onnx.load(paths[0]), onnx.load(paths[1]))

    def _tensor(self, name: str, env: Dict[str, torch.Tensor]) -> torch.Tensor:
        if name in self.param_index:
            p = self.params[self.param_index[name]]
            return fake_quant_weight(p, self.weight_axis[name]) if name in self.weight_axis else p
        return env[name]

    def forward(self, x: torch.Tensor) -> Dict[str, torch.Tensor]:
        env: Dict[str, torch.Tensor] = dict(self.evaluator.consts)
        s, zp = self.act_params[self.input_name]
        env[self.input_name] = fake_quant_activation(x, s, zp)
        for node in self.float_model.graph.node:
            ins = [self._tensor(n, env) if n else None for n in node.input]
            outs = self.evaluator.compute(node, ins)
            for name, value in zip(node.output, outs):
                if name in self.act_params:
                    value = fake_quant_activation(value, *self.act_params[name])
                env[name] = value
        out = {}
        for name in self.output_names:
            out[name] = env[self.sigmoid_inputs[name]] if name in self.sigmoid_inputs else env[name]
        return out

    def trained_float_model(self) -> onnx.ModelProto:
        """The float graph with the current weights."""
        model = onnx.ModelProto.FromString(self.float_model.SerializeToString())
        for t in model.graph.initializer:
            if t.name in self.param_index:
                value = self.params[self.param_index[t.name]].detach().cpu().numpy()
                t.CopyFrom(numpy_helper.from_array(value.astype(np.float32), t.name))
        return model

    def fixed_ranges(self) -> Dict[str, Tuple[float, float]]:
        """Activation ranges that make qdq.qparams give back exactly the fixed parameters."""
        return {n: ((INT8_MIN - zp) * s, (INT8_MAX - zp) * s) for n, (s, zp) in self.act_params.items()}

    def export(self, out_dir: str, version_suffix: str = "") -> Tuple[str, str]:
        cfg = qdq.QuantConfig.from_model(self.qdq_model)
        cfg = dataclasses.replace(cfg, model_version=cfg.model_version + version_suffix)
        fp32 = self.trained_float_model()
        qm = qdq.quantize_model(fp32, [], cfg, ranges=self.fixed_ranges())
        os.makedirs(out_dir, exist_ok=True)
        paths = (os.path.join(out_dir, "detector_fp32.onnx"), os.path.join(out_dir, "detector_int8.onnx"))
        onnx.save(fp32, paths[0])
        onnx.save(qm, paths[1])
        return paths


def main(argv=None) -> int:
    p = argparse.ArgumentParser(
        description="Export a quantization-aware fine-tuned first stage (train.py --qat-from) "
                    "to detector_fp32.onnx + detector_int8.onnx.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--checkpoint", required=True, help="checkpoint.pt of a train.py --qat-from run")
    p.add_argument("--out", required=True, help="folder to write (outside the repository)")
    args = p.parse_args(argv)
    from detector.train import _check_out_dir

    _check_out_dir(args.out)
    ck = torch.load(args.checkpoint, map_location="cpu")
    source = ck.get("args", {}).get("qat_from")
    if not source:
        raise SystemExit(f"{args.checkpoint}: not a train.py --qat-from checkpoint")
    model = QatDetector.from_export(source)
    model.load_state_dict(ck["detector"])
    paths = model.export(args.out, version_suffix=f"+qat{ck['step']}")
    print(f"wrote {paths[0]} and {paths[1]} ({ck['step']} QAT steps from {source})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
