#!/usr/bin/python3
"""Post-training int8 quantizer: float ONNX CNN -> ONNX QDQ model for vp::inference.

Library + CLI. Run with Debian's Python (/usr/bin/python3: torch, onnx, numpy, opencv).

Pipeline (see tools/quantize/README.md for the full description):

1. ``prepare_float_model``: Constant nodes become initializers, shapes are inferred.
2. ``collect_ranges``: the float graph is run by ``Evaluator`` -- a small ONNX interpreter of
   the supported operators whose kernels are torch.nn.functional calls -- on the calibration
   inputs, and the range of every activation tensor is recorded (min/max, percentile or MSE).
   Running the *exported ONNX graph* (not the torch module) means no name mapping between
   torch and ONNX is needed, and any float ONNX file can be quantized.
3. ``quantize_model``: rewrites the graph in QDQ form:
     * graph input -> QuantizeLinear -> DequantizeLinear -> consumers;
     * every activation tensor: Q/DQ with a scalar scale and an int8 zero point
       (asymmetric, [-128, 127], range always includes 0);
     * Conv/Add followed by its only consumer Relu/Clip: no Q/DQ between them (fused);
     * Concat, Resize, MaxPool: all inputs and the output share one (scale, zero point)
       (union-find over tensors; the range is the union of the members' ranges);
     * Conv weights: int8 initializer, symmetric per output channel ([-127, 127], zp 0),
       DequantizeLinear(axis=0); ConvTranspose: axis=1; biases stay float;
     * graph outputs: the DequantizeLinear output carries the original output name;
     * metadata_props vp.input.channel_order / mean / scale, vp.model.name / version.
4. ``compare_models``: runs the float model and the QDQ model (fake-quant: Q/DQ evaluated in
   float, i.e. the int8 arithmetic up to the engine's bias quantization and rounding) on
   held-out inputs and reports the error per output.

Typical library use::

    import qdq
    cfg = qdq.QuantConfig(channel_order="rgb", mean=(0, 0, 0), scale=(1/255,)*3,
                          model_name="detector", model_version="3")
    float_model = qdq.export_torch(module, (1, 3, 512, 512), output_names=["obj", "reg"])
    calib = qdq.preprocess(images_uint8_nhwc, cfg)            # float NCHW batches
    qmodel = qdq.quantize_model(float_model, calib, cfg)
    print(qdq.format_report(qdq.compare_models(float_model, qmodel, test_inputs)))
    onnx.save(qmodel, "detector_int8.onnx")
"""

from __future__ import annotations

import argparse
import dataclasses
import glob
import io
import math
import os
import sys
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

import numpy as np
import onnx
from onnx import helper, numpy_helper

try:  # torch is the kernel library of the evaluator and the exporter; required.
    import torch
    import torch.nn.functional as F
except ImportError as exc:  # pragma: no cover
    raise SystemExit("qdq.py needs torch: run it with /usr/bin/python3 (Debian's Python)") from exc

OPSET = 13

# Operators the engine computes (their activation inputs are quantized).
COMPUTE_OPS = {
    "Conv", "ConvTranspose", "Relu", "Clip", "Add", "Mul", "Concat", "Resize", "MaxPool",
    "GlobalAveragePool", "Sigmoid",
}
# A Relu/Clip that is the only consumer of one of these is fused into it (no Q/DQ between).
FUSABLE_PRODUCERS = {"Conv", "Add"}
ACTIVATIONS = {"Relu", "Clip"}
# Inputs (by index) and the output of these ops share one (scale, zero point).
SHARED_PARAM_INPUTS = {"Concat": None, "Resize": (0,), "MaxPool": (0,)}  # None: all inputs
WEIGHT_AXIS = {"Conv": 0, "ConvTranspose": 1}


# ----------------------------------------------------------------------------------------------
# configuration


@dataclasses.dataclass
class QuantConfig:
    """What the quantizer needs besides the model and the calibration data.

    ``mean`` and ``scale`` are the input normalisation in 8-bit units, per channel in the
    model's channel order: x = (v - mean[c]) * scale[c]. They are written to the model's
    metadata and used by ``preprocess``.
    """

    channel_order: str = "rgb"  # "rgb" or "bgr": the channel order the model expects
    mean: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    scale: Tuple[float, float, float] = (1.0 / 255.0, 1.0 / 255.0, 1.0 / 255.0)
    model_name: str = "model"
    model_version: str = "1"
    method: str = "minmax"  # "minmax" | "percentile" | "mse"
    percentile: float = 99.99  # for method="percentile": keep [100-p, p] percent of values
    samples_per_tensor: int = 200_000  # reservoir size per tensor (percentile / mse)

    def __post_init__(self) -> None:
        if self.channel_order not in ("rgb", "bgr"):
            raise ValueError(f"channel_order must be 'rgb' or 'bgr', not {self.channel_order!r}")
        if self.method not in ("minmax", "percentile", "mse"):
            raise ValueError(f"method must be minmax, percentile or mse, not {self.method!r}")
        if len(self.mean) != 3 or len(self.scale) != 3:
            raise ValueError("mean and scale need 3 values")

    @classmethod
    def from_model(cls, model: onnx.ModelProto) -> "QuantConfig":
        """The configuration a QDQ model of ``quantize_model`` was made with (its metadata)."""
        meta = {p.key: p.value for p in model.metadata_props}
        try:
            return cls(channel_order=meta["vp.input.channel_order"],
                       mean=tuple(float(v) for v in meta["vp.input.mean"].split(",")),
                       scale=tuple(float(v) for v in meta["vp.input.scale"].split(",")),
                       model_name=meta["vp.model.name"], model_version=meta["vp.model.version"],
                       method=meta.get("vp.quantize.method", "minmax"))
        except KeyError as exc:
            raise ValueError(f"model metadata lacks {exc} (not written by quantize_model)") from exc


# ----------------------------------------------------------------------------------------------
# model preparation, export and input preprocessing


def export_torch(module: "torch.nn.Module", input_shape: Sequence[int], *,
                 input_name: str = "input", output_names: Optional[Sequence[str]] = None,
                 path: Optional[str] = None) -> onnx.ModelProto:
    """Exports a float torch module (eval mode, batch 1, static shape) to ONNX opset 13."""
    module = module.eval()
    example = torch.zeros(*input_shape, dtype=torch.float32)
    buffer = io.BytesIO()
    with torch.no_grad():
        torch.onnx.export(module, example, buffer, opset_version=OPSET, do_constant_folding=True,
                          input_names=[input_name],
                          output_names=list(output_names) if output_names else None)
    model = prepare_float_model(onnx.load_from_string(buffer.getvalue()))
    if path:
        onnx.save(model, path)
    return model


def prepare_float_model(model: onnx.ModelProto) -> onnx.ModelProto:
    """Constant nodes -> initializers; drops initializers from graph inputs; infers shapes."""
    model = onnx.ModelProto.FromString(model.SerializeToString())
    graph = model.graph
    kept = []
    for node in graph.node:
        if node.op_type == "Constant":
            value = next((a for a in node.attribute if a.name == "value"), None)
            if value is None:
                raise ValueError(f"Constant node '{node.name}' without a tensor 'value'")
            tensor = onnx.TensorProto()
            tensor.CopyFrom(value.t)
            tensor.name = node.output[0]
            graph.initializer.append(tensor)
        else:
            kept.append(node)
    del graph.node[:]
    graph.node.extend(kept)
    init_names = {t.name for t in graph.initializer}
    inputs = [i for i in graph.input if i.name not in init_names]
    del graph.input[:]
    graph.input.extend(inputs)
    for i, node in enumerate(graph.node):  # every node gets a name (error messages need one)
        if not node.name:
            node.name = f"{node.op_type}_{i}"
    del graph.value_info[:]
    model = onnx.shape_inference.infer_shapes(model)
    onnx.checker.check_model(model)
    return model


def input_shape_of(model: onnx.ModelProto) -> Tuple[int, int, int, int]:
    graph = model.graph
    if len(graph.input) != 1:
        raise ValueError(f"the model needs exactly one input, has {len(graph.input)}")
    dims = [d.dim_value for d in graph.input[0].type.tensor_type.shape.dim]
    if len(dims) != 4 or dims[0] != 1 or dims[1] != 3 or min(dims) <= 0:
        raise ValueError(f"input must be static [1, 3, H, W], is {dims}")
    return tuple(dims)  # type: ignore[return-value]


def preprocess(images: np.ndarray, cfg: QuantConfig) -> List[np.ndarray]:
    """uint8 images [N, H, W, 3] in the model's channel order -> list of float [1, 3, H, W]."""
    images = np.asarray(images)
    if images.ndim == 3:
        images = images[None]
    if images.dtype != np.uint8 or images.ndim != 4 or images.shape[3] != 3:
        raise ValueError(f"images must be uint8 [N, H, W, 3], got {images.dtype} {images.shape}")
    mean = np.asarray(cfg.mean, np.float32).reshape(1, 3, 1, 1)
    scale = np.asarray(cfg.scale, np.float32).reshape(1, 3, 1, 1)
    out = []
    for img in images:
        x = img.astype(np.float32).transpose(2, 0, 1)[None]
        out.append(((x - mean) * scale).astype(np.float32))
    return out


def load_images(paths: Iterable[str], width: int, height: int, channel_order: str) -> np.ndarray:
    """Reads image files (OpenCV), resizes to width x height, returns uint8 [N, H, W, 3]."""
    import cv2  # only the CLI's file loading needs OpenCV

    out = []
    for p in paths:
        img = cv2.imread(p, cv2.IMREAD_COLOR)
        if img is None:
            raise ValueError(f"cannot read image {p}")
        img = cv2.resize(img, (width, height), interpolation=cv2.INTER_AREA)
        if channel_order == "rgb":
            img = cv2.cvtColor(img, cv2.COLOR_BGR2RGB)
        out.append(img)
    if not out:
        raise ValueError("no calibration images")
    return np.stack(out)


def synthetic_images(n: int, height: int, width: int, seed: int) -> np.ndarray:
    """Random and smooth synthetic uint8 images [n, H, W, 3] (noise, blurred noise, gradients,
    blobs), for calibration when no real images are at hand. Deterministic in ``seed``."""
    import cv2

    rng = np.random.default_rng(seed)
    out = np.empty((n, height, width, 3), np.uint8)
    yy, xx = np.mgrid[0:height, 0:width].astype(np.float32)
    for i in range(n):
        kind = i % 4
        if kind == 0:  # white noise
            img = rng.integers(0, 256, (height, width, 3)).astype(np.float32)
        elif kind == 1:  # smooth noise: upsampled coarse noise
            cell = int(rng.integers(4, 17))
            coarse = rng.uniform(0, 255, (max(2, height // cell), max(2, width // cell), 3))
            img = cv2.resize(coarse.astype(np.float32), (width, height),
                             interpolation=cv2.INTER_CUBIC)
        elif kind == 2:  # linear gradients per channel
            img = np.empty((height, width, 3), np.float32)
            for c in range(3):
                a, b = rng.uniform(-1, 1, 2)
                g = a * xx / width + b * yy / height
                img[..., c] = 255 * (g - g.min()) / max(1e-6, float(np.ptp(g)))
        else:  # gaussian blobs on a background, plus a little noise
            img = np.full((height, width, 3), rng.uniform(0, 255, 3), np.float32)
            for _ in range(int(rng.integers(3, 9))):
                cy, cx = rng.uniform(0, height), rng.uniform(0, width)
                r = rng.uniform(2, max(3.0, min(height, width) / 4))
                w = np.exp(-((yy - cy) ** 2 + (xx - cx) ** 2) / (2 * r * r))[..., None]
                img = img * (1 - w) + w * rng.uniform(0, 255, 3)
            img += rng.normal(0, 8, img.shape)
        out[i] = np.clip(np.rint(img), 0, 255).astype(np.uint8)
    return out


# ----------------------------------------------------------------------------------------------
# evaluator: a tiny ONNX interpreter (float ops + Q/DQ) with torch kernels


def _attrs(node: onnx.NodeProto) -> Dict[str, object]:
    return {a.name: helper.get_attribute_value(a) for a in node.attribute}


def _pads4(node: onnx.NodeProto, attrs: Dict[str, object]) -> List[int]:
    if attrs.get("auto_pad", b"NOTSET") not in (b"NOTSET", "NOTSET"):
        raise ValueError(f"node '{node.name}' ({node.op_type}): auto_pad is not supported")
    pads = list(attrs.get("pads", [0, 0, 0, 0]))
    if len(pads) != 4:
        raise ValueError(f"node '{node.name}' ({node.op_type}): only 2-D ops are supported")
    return pads  # top, left, bottom, right


def _qparam_shape(param: "torch.Tensor", x: "torch.Tensor", axis: int) -> "torch.Tensor":
    if param.numel() == 1:
        return param.reshape(())
    shape = [1] * x.dim()
    shape[axis if axis >= 0 else axis + x.dim()] = param.numel()
    return param.reshape(shape)


class Evaluator:
    """Runs an ONNX graph of the supported operators in float (torch kernels, CPU).

    Supported: Conv, ConvTranspose, Relu, Clip, Add, Mul, Concat, Resize (linear/nearest),
    MaxPool, GlobalAveragePool, Sigmoid, Identity, Flatten, Reshape, QuantizeLinear and
    DequantizeLinear (per tensor and per axis; Q/DQ are evaluated exactly in float:
    round-half-to-even, saturation to the integer type).
    """

    def __init__(self, model: onnx.ModelProto):
        self.model = model
        self.consts: Dict[str, torch.Tensor] = {}
        for t in model.graph.initializer:
            arr = numpy_helper.to_array(t)
            self.consts[t.name] = torch.from_numpy(np.array(arr, copy=True))
        for node in model.graph.node:
            if node.op_type == "Constant":
                arr = numpy_helper.to_array(_attrs(node)["value"])
                self.consts[node.output[0]] = torch.from_numpy(np.array(arr, copy=True))

    def run(self, feeds: Dict[str, np.ndarray], keep_all: bool = False,
            observer=None) -> Dict[str, np.ndarray]:
        """Returns the graph outputs (or every tensor with keep_all) as numpy arrays.
        ``observer(name, tensor)`` is called for the graph inputs and every node output."""
        env: Dict[str, torch.Tensor] = dict(self.consts)
        for name, value in feeds.items():
            env[name] = torch.from_numpy(np.ascontiguousarray(value, dtype=np.float32))
            if observer:
                observer(name, env[name])
        with torch.no_grad():
            for node in self.model.graph.node:
                if node.op_type == "Constant":
                    continue
                ins = [env[n] if n else None for n in node.input]
                try:
                    outs = self.compute(node, ins)
                except KeyError:
                    raise
                except Exception as exc:
                    raise RuntimeError(f"node '{node.name}' ({node.op_type}): {exc}") from exc
                for name, value in zip(node.output, outs):
                    env[name] = value
                    if observer:
                        observer(name, value)
        names = env.keys() if keep_all else [o.name for o in self.model.graph.output]
        return {n: env[n].numpy() for n in names}

    def compute(self, node: onnx.NodeProto, ins: List[Optional["torch.Tensor"]]):
        """One node's outputs from its inputs (torch kernels; differentiable outside run())."""
        op = node.op_type
        a = _attrs(node)
        if op in ("Conv", "ConvTranspose"):
            x, w = ins[0].float(), ins[1].float()
            b = ins[2].float() if len(ins) > 2 and ins[2] is not None else None
            t, l, bo, r = _pads4(node, a)
            strides = list(a.get("strides", [1, 1]))
            dil = list(a.get("dilations", [1, 1]))
            group = int(a.get("group", 1))
            if op == "Conv":
                if (t, l) != (bo, r):
                    x = F.pad(x, (l, r, t, bo))
                    t = l = 0
                return [F.conv2d(x, w, b, strides, (t, l), dil, group)]
            if (t, l) != (bo, r):
                raise ValueError("asymmetric ConvTranspose pads are not supported")
            outpad = list(a.get("output_padding", [0, 0]))
            if "output_shape" in a:
                raise ValueError("ConvTranspose output_shape is not supported")
            return [F.conv_transpose2d(x, w, b, strides, (t, l), outpad, group, dil)]
        if op == "Relu":
            return [F.relu(ins[0])]
        if op == "Clip":
            lo = a.get("min", None)
            hi = a.get("max", None)
            if len(ins) > 1 and ins[1] is not None:
                lo = float(ins[1])
            if len(ins) > 2 and ins[2] is not None:
                hi = float(ins[2])
            return [torch.clamp(ins[0], min=lo, max=hi)]
        if op == "Add":
            return [ins[0] + ins[1]]
        if op == "Mul":
            return [ins[0] * ins[1]]
        if op == "Sigmoid":
            return [torch.sigmoid(ins[0])]
        if op == "Concat":
            return [torch.cat(ins, dim=int(a["axis"]))]
        if op == "Resize":
            x = ins[0]
            mode = a.get("mode", b"nearest")
            mode = mode.decode() if isinstance(mode, bytes) else mode
            ctm = a.get("coordinate_transformation_mode", b"half_pixel")
            ctm = ctm.decode() if isinstance(ctm, bytes) else ctm
            sizes = ins[3] if len(ins) > 3 and ins[3] is not None and ins[3].numel() else None
            scales = ins[2] if len(ins) > 2 and ins[2] is not None and ins[2].numel() else None
            if sizes is not None:
                out_hw = [int(v) for v in sizes[2:]]
            else:
                out_hw = [int(math.floor(x.shape[i + 2] * float(scales[i + 2]))) for i in range(2)]
            if mode == "linear":
                if ctm not in ("half_pixel", "pytorch_half_pixel", "align_corners"):
                    raise ValueError(f"Resize linear with {ctm} is not supported")
                return [F.interpolate(x, size=out_hw, mode="bilinear",
                                      align_corners=(ctm == "align_corners"))]
            if mode == "nearest" and ctm == "asymmetric":
                return [F.interpolate(x, size=out_hw, mode="nearest")]
            raise ValueError(f"Resize mode={mode} coordinate_transformation_mode={ctm}")
        if op == "MaxPool":
            t, l, bo, r = _pads4(node, a)
            x = ins[0]
            if (t, l) != (bo, r):
                x = F.pad(x, (l, r, t, bo), value=-math.inf)
                t = l = 0
            k = list(a["kernel_shape"])
            return [F.max_pool2d(x, k, list(a.get("strides", k)), (t, l),
                                 list(a.get("dilations", [1, 1])), bool(a.get("ceil_mode", 0)))]
        if op == "GlobalAveragePool":
            return [ins[0].mean(dim=(2, 3), keepdim=True)]
        if op == "Identity":
            return [ins[0]]
        if op == "Flatten":
            axis = int(a.get("axis", 1))
            return [ins[0].reshape(int(np.prod(ins[0].shape[:axis])), -1)]
        if op == "Reshape":
            return [ins[0].reshape([int(v) for v in ins[1]])]
        if op == "QuantizeLinear":
            x = ins[0].float()
            axis = int(a.get("axis", 1))
            s = _qparam_shape(ins[1].float(), x, axis)
            zp_t = ins[2] if len(ins) > 2 and ins[2] is not None else torch.zeros((), dtype=torch.uint8)
            lo, hi = (-128, 127) if zp_t.dtype == torch.int8 else (0, 255)
            zp = _qparam_shape(zp_t.float(), x, axis)
            return [torch.clamp(torch.round(x / s) + zp, lo, hi)]  # integers held in float
        if op == "DequantizeLinear":
            q = ins[0].float()
            axis = int(a.get("axis", 1))
            s = _qparam_shape(ins[1].float(), q, axis)
            zp = (_qparam_shape(ins[2].float(), q, axis)
                  if len(ins) > 2 and ins[2] is not None else 0.0)
            return [(q - zp) * s]
        raise ValueError(f"operator {op} is not supported")


# ----------------------------------------------------------------------------------------------
# calibration


class RangeCollector:
    """Observer for ``Evaluator.run``: min/max of every tensor, plus (percentile/mse) a random
    reservoir of values per tensor."""

    def __init__(self, names: Iterable[str], cfg: QuantConfig, seed: int = 0):
        self.names = set(names)
        self.cfg = cfg
        self.mins: Dict[str, float] = {}
        self.maxs: Dict[str, float] = {}
        self.samples: Dict[str, List[np.ndarray]] = {}
        self.rng = np.random.default_rng(seed)
        self.per_batch = 0

    def __call__(self, name: str, t: "torch.Tensor") -> None:
        if name not in self.names or not t.is_floating_point():
            return
        lo, hi = float(t.min()), float(t.max())
        self.mins[name] = min(lo, self.mins.get(name, lo))
        self.maxs[name] = max(hi, self.maxs.get(name, hi))
        if self.cfg.method != "minmax":
            flat = t.reshape(-1).numpy()
            k = min(flat.size, max(1, self.per_batch))
            idx = self.rng.choice(flat.size, size=k, replace=False) if k < flat.size else slice(None)
            self.samples.setdefault(name, []).append(np.array(flat[idx], np.float32))

    def ranges(self) -> Dict[str, Tuple[float, float]]:
        out = {}
        for name in self.mins:
            lo, hi = self.mins[name], self.maxs[name]
            if self.cfg.method != "minmax" and name in self.samples:
                vals = np.concatenate(self.samples[name])
                if self.cfg.method == "percentile":
                    p = self.cfg.percentile
                    lo, hi = float(np.percentile(vals, 100 - p)), float(np.percentile(vals, p))
                else:
                    lo, hi = _mse_range(vals, lo, hi)
            out[name] = (lo, hi)
        return out


def _mse_range(vals: np.ndarray, lo: float, hi: float) -> Tuple[float, float]:
    """Shrinks [lo, hi] by a common factor to minimise the int8 fake-quant MSE on ``vals``."""
    best, best_err = (lo, hi), math.inf
    for alpha in np.linspace(1.0, 0.2, 41):
        s, zp = qparams(lo * alpha, hi * alpha)
        q = np.clip(np.rint(vals / s) + zp, -128, 127)
        err = float(np.mean(((q - zp) * s - vals) ** 2))
        if err < best_err:
            best, best_err = (lo * alpha, hi * alpha), err
    return best


def activation_tensors(model: onnx.ModelProto) -> List[str]:
    """Graph inputs and node outputs (float activations, not initializers), in graph order."""
    init = {t.name for t in model.graph.initializer}
    names = [i.name for i in model.graph.input if i.name not in init]
    for node in model.graph.node:
        if node.op_type != "Constant":
            names.extend(o for o in node.output if o)
    return names


def collect_ranges(model: onnx.ModelProto, inputs: Sequence[np.ndarray],
                   cfg: QuantConfig) -> Dict[str, Tuple[float, float]]:
    """Runs the float model on every calibration input, returns {tensor: (min, max)}."""
    if not inputs:
        raise ValueError("no calibration inputs")
    in_name = model.graph.input[0].name
    collector = RangeCollector(activation_tensors(model), cfg)
    collector.per_batch = max(1, cfg.samples_per_tensor // len(inputs))
    ev = Evaluator(model)
    for x in inputs:
        ev.run({in_name: x}, observer=collector)
    return collector.ranges()


def ranges_of_qdq(qdq_model: onnx.ModelProto) -> Dict[str, Tuple[float, float]]:
    """{activation tensor: (lo, hi)} of a QDQ model this module wrote: the int8 range of each
    activation QuantizeLinear's scale and zero point, which ``qparams`` maps back to the same
    scale and zero point. Lets a re-export keep a shipped file's activation quantization."""
    init = {t.name: t for t in qdq_model.graph.initializer}
    out: Dict[str, Tuple[float, float]] = {}
    for node in qdq_model.graph.node:
        if node.op_type != "QuantizeLinear" or not node.name.endswith("_QuantizeLinear"):
            continue
        base = node.name[:-len("_QuantizeLinear")]
        s_t, zp_t = init.get(node.input[1]), init.get(node.input[2])
        if s_t is None or zp_t is None:
            continue
        s = numpy_helper.to_array(s_t)
        zp = numpy_helper.to_array(zp_t)
        if s.size != 1 or zp.size != 1:
            continue  # per-channel weights, not an activation
        s, zp = float(s.reshape(())), int(zp.reshape(()))
        out[base] = ((-128 - zp) * s, (127 - zp) * s)
    return out


def qparams(lo: float, hi: float) -> Tuple[float, int]:
    """Asymmetric int8 scale and zero point for [lo, hi] (extended to contain 0)."""
    lo, hi = min(float(lo), 0.0), max(float(hi), 0.0)
    if hi - lo < 1e-8:
        hi = lo + 1e-8 if hi - lo > 0 else lo + 1.0  # constant-zero tensor: any positive scale
    scale = (hi - lo) / 255.0
    zp = int(np.clip(np.rint(-128.0 - lo / scale), -128, 127))
    return float(np.float32(scale)), zp


# ----------------------------------------------------------------------------------------------
# QDQ rewrite


class _UnionFind:
    def __init__(self):
        self.parent: Dict[str, str] = {}

    def find(self, a: str) -> str:
        self.parent.setdefault(a, a)
        while self.parent[a] != a:
            self.parent[a] = self.parent[self.parent[a]]
            a = self.parent[a]
        return a

    def union(self, a: str, b: str) -> None:
        ra, rb = self.find(a), self.find(b)
        if ra != rb:
            self.parent[rb] = ra


def quantize_model(float_model: onnx.ModelProto, calib_inputs: Sequence[np.ndarray],
                   cfg: QuantConfig,
                   ranges: Optional[Dict[str, Tuple[float, float]]] = None) -> onnx.ModelProto:
    """Returns the QDQ model. ``calib_inputs``: float [1, 3, H, W] arrays (``preprocess``);
    ``ranges`` may be given instead (from ``collect_ranges``)."""
    model = prepare_float_model(float_model)
    input_shape_of(model)
    graph = model.graph
    if ranges is None:
        ranges = collect_ranges(model, calib_inputs, cfg)
    init = {t.name: t for t in graph.initializer}
    in_name = graph.input[0].name
    out_names = [o.name for o in graph.output]

    producers: Dict[str, onnx.NodeProto] = {}
    consumers: Dict[str, List[onnx.NodeProto]] = {}
    for node in graph.node:
        if node.op_type not in COMPUTE_OPS | {"Identity"}:
            raise ValueError(f"node '{node.name}' ({node.op_type}): operator not supported by "
                             f"the engine (supported: {', '.join(sorted(COMPUTE_OPS))})")
        for o in node.output:
            producers[o] = node
        for i in node.input:
            if i:
                consumers.setdefault(i, []).append(node)

    # 1. fused tensors: Conv/Add output whose only consumer is a Relu/Clip
    fused = set()
    for name, node in producers.items():
        cons = consumers.get(name, [])
        if (node.op_type in FUSABLE_PRODUCERS and len(cons) == 1 and
                cons[0].op_type in ACTIVATIONS and name not in out_names):
            fused.add(name)

    # 2. quantized activation tensors
    quantized = [n for n in activation_tensors(model) if n not in fused]
    for n in quantized:
        if n not in ranges:
            raise ValueError(f"no calibration range for tensor '{n}'")

    # 3. shared parameters: Concat / Resize / MaxPool inputs + output
    uf = _UnionFind()
    for n in quantized:
        uf.find(n)
    for node in graph.node:
        if node.op_type in SHARED_PARAM_INPUTS:
            idx = SHARED_PARAM_INPUTS[node.op_type]
            members = [node.input[i] for i in (idx if idx is not None else range(len(node.input)))]
            for m in members:
                if m in init:
                    raise ValueError(f"node '{node.name}' ({node.op_type}): constant input '{m}'")
                uf.union(node.output[0], m)
    group_range: Dict[str, Tuple[float, float]] = {}
    for n in quantized:
        root = uf.find(n)
        lo, hi = ranges[n]
        glo, ghi = group_range.get(root, (lo, hi))
        group_range[root] = (min(lo, glo), max(hi, ghi))
    params = {n: qparams(*group_range[uf.find(n)]) for n in quantized}

    # 4. rewrite
    new_nodes: List[onnx.NodeProto] = []
    new_inits: List[onnx.TensorProto] = [t for t in graph.initializer]
    rename: Dict[str, str] = {}  # activation name -> name its consumers read

    def qdq_nodes(src: str, dst: str, base: str) -> List[onnx.NodeProto]:
        s, zp = params[base]
        s_name, zp_name = f"{base}_scale", f"{base}_zero_point"
        new_inits.append(numpy_helper.from_array(np.array(s, np.float32), s_name))
        new_inits.append(numpy_helper.from_array(np.array(zp, np.int8), zp_name))
        q_out = f"{base}_QuantizeLinear_Output"
        return [
            helper.make_node("QuantizeLinear", [src, s_name, zp_name], [q_out],
                             name=f"{base}_QuantizeLinear"),
            helper.make_node("DequantizeLinear", [q_out, s_name, zp_name], [dst],
                             name=f"{base}_DequantizeLinear"),
        ]

    if in_name in params:
        dq = f"{in_name}_DequantizeLinear_Output"
        new_nodes.extend(qdq_nodes(in_name, dq, in_name))
        rename[in_name] = dq

    weight_dq: Dict[Tuple[str, int], str] = {}
    removed_inits = set()
    qset = set(quantized)
    for node in graph.node:
        node = onnx.NodeProto.FromString(node.SerializeToString())
        for k, name in enumerate(node.input):
            if name in rename:
                node.input[k] = rename[name]
        if node.op_type in WEIGHT_AXIS:
            wname = node.input[1]
            if wname not in init:
                raise ValueError(f"node '{node.name}' ({node.op_type}): weight is not constant")
            axis = WEIGHT_AXIS[node.op_type]
            key = (wname, axis)
            if key not in weight_dq:
                if node.op_type == "ConvTranspose" and int(_attrs(node).get("group", 1)) != 1:
                    raise ValueError(f"node '{node.name}': grouped ConvTranspose not supported")
                w = numpy_helper.to_array(init[wname]).astype(np.float32)
                red = tuple(i for i in range(w.ndim) if i != axis)
                absmax = np.abs(w).max(axis=red)
                scale = np.where(absmax > 0, absmax / 127.0, 1.0 / 127.0).astype(np.float32)
                bshape = [1] * w.ndim
                bshape[axis] = -1
                wq = np.clip(np.rint(w / scale.reshape(bshape)), -127, 127).astype(np.int8)
                new_inits.append(numpy_helper.from_array(wq, f"{wname}_quantized"))
                new_inits.append(numpy_helper.from_array(scale, f"{wname}_scale"))
                new_inits.append(numpy_helper.from_array(np.zeros(scale.shape, np.int8),
                                                         f"{wname}_zero_point"))
                dq_out = f"{wname}_DequantizeLinear_Output"
                new_nodes.append(helper.make_node(
                    "DequantizeLinear",
                    [f"{wname}_quantized", f"{wname}_scale", f"{wname}_zero_point"], [dq_out],
                    name=f"{wname}_DequantizeLinear", axis=axis))
                weight_dq[key] = dq_out
                removed_inits.add(wname)
            node.input[1] = weight_dq[key]
        outs_to_qdq = []
        for k, name in enumerate(node.output):
            if name in qset:
                if name in out_names:  # DQ output keeps the graph output's name
                    pre = f"{name}_float"
                    node.output[k] = pre
                    outs_to_qdq.append((pre, name, name))
                else:
                    dq = f"{name}_DequantizeLinear_Output"
                    outs_to_qdq.append((name, dq, name))
                    rename[name] = dq
        new_nodes.append(node)
        for src, dst, base in outs_to_qdq:
            new_nodes.extend(qdq_nodes(src, dst, base))

    still_used = {i for n in new_nodes for i in n.input}
    new_inits = [t for t in new_inits if t.name not in removed_inits or t.name in still_used]
    del graph.node[:]
    graph.node.extend(new_nodes)
    del graph.initializer[:]
    graph.initializer.extend(new_inits)
    del graph.value_info[:]

    meta = {
        "vp.input.channel_order": cfg.channel_order,
        "vp.input.mean": ",".join(_fmt(v) for v in cfg.mean),
        "vp.input.scale": ",".join(_fmt(v) for v in cfg.scale),
        "vp.model.name": cfg.model_name,
        "vp.model.version": str(cfg.model_version),
        "vp.quantize.method": cfg.method,
        "vp.quantize.calibration_inputs": str(len(calib_inputs)) if calib_inputs else "ranges",
    }
    del model.metadata_props[:]
    for k, v in meta.items():
        model.metadata_props.append(onnx.StringStringEntryProto(key=k, value=v))
    model.producer_name = "vp tools/quantize/qdq.py"
    model.producer_version = "1"
    model = onnx.shape_inference.infer_shapes(model)
    onnx.checker.check_model(model)
    return model


def _fmt(v: float) -> str:
    return repr(float(np.float32(v)))


# ----------------------------------------------------------------------------------------------
# verification


def compare_models(float_model: onnx.ModelProto, qdq_model: onnx.ModelProto,
                   inputs: Sequence[np.ndarray]) -> Dict[str, Dict[str, float]]:
    """Float vs QDQ (fake-quant) outputs over ``inputs``. Per output: max_abs, mean_abs,
    range (of the float output), rel_max = max_abs / range, sqnr_db, q_step (output scale)."""
    fe, qe = Evaluator(float_model), Evaluator(qdq_model)
    in_name = float_model.graph.input[0].name
    q_in = qdq_model.graph.input[0].name
    steps = {}
    init = {t.name: t for t in qdq_model.graph.initializer}
    for node in qdq_model.graph.node:
        if node.op_type == "DequantizeLinear" and node.input[1] in init:
            steps[node.output[0]] = float(numpy_helper.to_array(init[node.input[1]]).max())
    acc: Dict[str, Dict[str, list]] = {}
    for x in inputs:
        fo = fe.run({in_name: x})
        qo = qe.run({q_in: x})
        for name, ref in fo.items():
            d = acc.setdefault(name, {"ref": [], "err": []})
            d["ref"].append(ref.ravel())
            d["err"].append((qo[name] - ref).ravel())
    report = {}
    for name, d in acc.items():
        ref = np.concatenate(d["ref"]).astype(np.float64)
        err = np.concatenate(d["err"]).astype(np.float64)
        rng = float(ref.max() - ref.min())
        sig = float(np.mean(ref ** 2))
        noise = float(np.mean(err ** 2))
        report[name] = {
            "max_abs": float(np.abs(err).max()),
            "mean_abs": float(np.abs(err).mean()),
            "range": rng,
            "rel_max": float(np.abs(err).max()) / rng if rng > 0 else float("nan"),
            "sqnr_db": 10 * math.log10(sig / noise) if noise > 0 else float("inf"),
            "q_step": steps.get(name, float("nan")),
        }
    return report


def strip_activation_qdq(qdq_model: onnx.ModelProto) -> onnx.ModelProto:
    """The QDQ graph in float: activation QuantizeLinear/DequantizeLinear become Identity,
    weight DequantizeLinear stay (dequantized int8 weights). This is what the engine's float
    backends (XnnpackFp32, OpenCvFp32) compute on a QDQ file."""
    model = onnx.ModelProto.FromString(qdq_model.SerializeToString())
    init = {t.name for t in model.graph.initializer}
    for node in model.graph.node:
        if node.op_type in ("QuantizeLinear", "DequantizeLinear") and node.input[0] not in init:
            node.op_type = "Identity"
            del node.input[1:]
            del node.attribute[:]
    return model


def format_report(report: Dict[str, Dict[str, float]]) -> str:
    lines = ["| output | float range | max abs err | mean abs err | max err / range | SQNR dB | output step |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for name, r in report.items():
        lines.append(f"| {name} | {r['range']:.4g} | {r['max_abs']:.4g} | {r['mean_abs']:.4g} | "
                     f"{100 * r['rel_max']:.2f} % | {r['sqnr_db']:.1f} | {r['q_step']:.4g} |")
    return "\n".join(lines)


def summarize(model: onnx.ModelProto) -> str:
    """One line: node counts by op type."""
    counts: Dict[str, int] = {}
    for n in model.graph.node:
        counts[n.op_type] = counts.get(n.op_type, 0) + 1
    return ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))


# ----------------------------------------------------------------------------------------------
# CLI


def _floats3(text: str) -> Tuple[float, float, float]:
    vals = []
    for v in text.split(","):
        v = v.strip()
        vals.append(1.0 / float(v[2:]) if v.startswith("1/") else float(v))
    if len(vals) == 1:
        vals *= 3
    if len(vals) != 3:
        raise argparse.ArgumentTypeError("need 1 or 3 comma-separated values")
    return tuple(vals)  # type: ignore[return-value]


def main(argv: Optional[Sequence[str]] = None) -> int:
    p = argparse.ArgumentParser(
        description="Quantize a float ONNX CNN (opset 13, input [1,3,H,W]) to int8 QDQ form "
                    "for vp::inference. See tools/quantize/README.md.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("model", help="float ONNX model (e.g. from torch.onnx.export, opset 13)")
    p.add_argument("-o", "--output", required=True, help="QDQ ONNX model to write")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--calib", nargs="+", metavar="IMG_OR_GLOB",
                     help="calibration image files or globs (read with OpenCV, resized to W x H)")
    src.add_argument("--calib-synthetic", type=int, metavar="N",
                     help="calibrate on N synthetic images (random, smooth noise, gradients, "
                          "blobs) -- only for tests and benchmarks")
    p.add_argument("--channel-order", choices=["rgb", "bgr"], default="rgb")
    p.add_argument("--mean", type=_floats3, default=(0.0, 0.0, 0.0),
                   help="per-channel mean in 8-bit units, model channel order ('m' or 'm0,m1,m2')")
    p.add_argument("--scale", type=_floats3, default=(1 / 255, 1 / 255, 1 / 255),
                   help="per-channel scale ('s', 's0,s1,s2'; '1/255' accepted)")
    p.add_argument("--name", default=None, help="vp.model.name (default: file stem)")
    p.add_argument("--version", default="1", help="vp.model.version")
    p.add_argument("--method", choices=["minmax", "percentile", "mse"], default="minmax")
    p.add_argument("--percentile", type=float, default=99.99)
    p.add_argument("--check", nargs="*", metavar="IMG_OR_GLOB", default=None,
                   help="after quantizing, compare float vs QDQ outputs on these images "
                        "(no value: 8 synthetic images not used in calibration)")
    args = p.parse_args(argv)

    float_model = prepare_float_model(onnx.load(args.model))
    _, _, h, w = input_shape_of(float_model)
    cfg = QuantConfig(channel_order=args.channel_order, mean=args.mean, scale=args.scale,
                      model_name=args.name or os.path.splitext(os.path.basename(args.model))[0],
                      model_version=args.version, method=args.method, percentile=args.percentile)

    def images_from(patterns: Sequence[str]) -> np.ndarray:
        paths: List[str] = []
        for pat in patterns:
            hits = sorted(glob.glob(pat))
            paths.extend(hits if hits else [pat])
        return load_images(paths, w, h, cfg.channel_order)

    calib_imgs = (images_from(args.calib) if args.calib
                  else synthetic_images(args.calib_synthetic, h, w, seed=1))
    qmodel = quantize_model(float_model, preprocess(calib_imgs, cfg), cfg)
    onnx.save(qmodel, args.output)
    print(f"wrote {args.output} ({os.path.getsize(args.output)} bytes): {summarize(qmodel)}")
    if args.check is not None:
        test_imgs = images_from(args.check) if args.check else synthetic_images(8, h, w, seed=1001)
        print(format_report(compare_models(float_model, qmodel, preprocess(test_imgs, cfg))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
