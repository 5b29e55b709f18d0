#!/usr/bin/python3
"""Exports a trained run to ONNX (float) and int8 QDQ files the engine loads, and reports MACs.

    tools/detector/export.py --checkpoint RUNDIR/checkpoint.pt --out EXPORTDIR
        [--calib-data SEQDIR ...] [--calib-real DIR] [--calib-count 32]
        [--calib-verifier-samples CSV ...]
        [--input-size 672x512] [--eval-data SEQDIR ...] [--engine-bench build/release/tests/bench/vp_bench_engine]

Contract
--------
* Writes EXPORTDIR/{detector,crop}_fp32.onnx (opset 13, BN folded) and
  EXPORTDIR/{detector,crop}_int8.onnx (tools/quantize/qdq.py: per-channel int8 weights,
  calibrated activation Q/DQ, metadata vp.input.* = model.NORMALIZATION, vp.model.name
  ``vp_detector`` / ``vp_vehicle_crop``), beside each int8 file its checksum
  ``<name>_int8.onnx.sha256`` (sha256sum's format; the engine verifies it at load) and
  EXPORTDIR/export_report.json (MACs, per camera
  megapixel, parameter counts, operator counts, float-vs-QDQ error per output, optional
  detection metrics of fp32 and int8 (fake-quant) on ``--eval-data``, optional engine run).
* ``engine_ops_only(model)`` walks an ONNX graph and returns the operators outside the engine's
  list (docs/inference.md); export fails if any appears.
* Calibration: working-resolution frames (resized + padded exactly as at run time) from
  ``--calib-data`` sequences and ``--calib-real`` images; crops from the sequences' ground truth.
  Without any, synthetic images (tests only).
* ``--engine-bench PATH`` runs the C++ engine benchmark on each int8 file
  (``--benchmark_filter=Int8/threads:1``) to prove that the engine loads and runs it.
"""

from __future__ import annotations

import argparse
import glob
import hashlib
import json
import math
import os
import subprocess
import sys
from typing import Dict, List, Optional, Sequence

if __package__ in (None, ""):
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import numpy as np
import onnx
import torch

from detector.asm import REPO_ROOT
from detector.model import (CROP_H, CROP_W, DEFAULT_INPUT_HW, NORMALIZATION, CropNet, Detector)

sys.path.insert(0, os.path.join(REPO_ROOT, "tools", "quantize"))
import qdq  # noqa: E402

ENGINE_OPS = {"Conv", "ConvTranspose", "Add", "Mul", "Concat", "Resize", "MaxPool",
              "GlobalAveragePool", "Sigmoid", "Tanh", "Relu", "Clip"}
PLUMBING = {"Identity", "Constant", "QuantizeLinear", "DequantizeLinear"}
CAMERA_PIXELS = 2592 * 2048


def engine_ops_only(model: onnx.ModelProto) -> List[str]:
    """Names 'node (op)' of nodes the engine cannot run (empty list: all fine)."""
    bad = []
    for n in model.graph.node:
        if n.op_type not in ENGINE_OPS | PLUMBING:
            bad.append(f"{n.name} ({n.op_type})")
        elif n.op_type == "Resize":
            a = {x.name: onnx.helper.get_attribute_value(x) for x in n.attribute}
            mode = a.get("mode", b"nearest")
            if mode not in (b"nearest", b"linear"):
                bad.append(f"{n.name} (Resize mode {mode!r})")
        elif n.op_type == "Concat":
            a = {x.name: onnx.helper.get_attribute_value(x) for x in n.attribute}
            if a.get("axis") != 1:
                bad.append(f"{n.name} (Concat axis {a.get('axis')})")
    return bad


def onnx_macs(model: onnx.ModelProto) -> int:
    """MACs of Conv/ConvTranspose nodes from the inferred shapes."""
    m = onnx.shape_inference.infer_shapes(model)
    shapes = {}
    for vi in list(m.graph.value_info) + list(m.graph.output) + list(m.graph.input):
        shapes[vi.name] = [d.dim_value for d in vi.type.tensor_type.shape.dim]
    init = {t.name: list(t.dims) for t in m.graph.initializer}
    total = 0
    for n in m.graph.node:
        if n.op_type == "Conv":
            w = init.get(n.input[1])
            out = shapes.get(n.output[0])
            if w and out:
                total += int(np.prod(out)) * int(np.prod(w[1:]))
    return total


def op_counts(model: onnx.ModelProto) -> Dict[str, int]:
    c: Dict[str, int] = {}
    for n in model.graph.node:
        c[n.op_type] = c.get(n.op_type, 0) + 1
    return c


def load_run(checkpoint: str):
    ck = torch.load(checkpoint, map_location="cpu")
    det = Detector(n_s=ck["n_s"], single_stage=ck.get("single_stage", False))
    det.load_state_dict(ck["detector"])
    crop = None
    if ck.get("crop") is not None:
        crop = CropNet.from_state_dict(ck["crop"], n_s=ck["n_s"])
    return ck, det.eval(), (crop.eval() if crop else None)


def working_canvas(image: np.ndarray, hw, scale: float) -> np.ndarray:
    import cv2

    h, w = image.shape[:2]
    nw, nh = min(hw[1], int(round(w * scale))), min(hw[0], int(round(h * scale)))
    small = cv2.resize(image, (nw, nh), interpolation=cv2.INTER_AREA)
    canvas = np.full((hw[0], hw[1], 3), 128, np.uint8)  # padded as at run time (mean grey)
    canvas[:nh, :nw] = small
    return canvas


def calibration_images(args, hw, n_s: int, rng, verifier: bool = False) -> (np.ndarray, np.ndarray):
    """(detector canvases [N, H, W, 3], crops [M, CROP_H, CROP_W, 3]) uint8 RGB. For a crop
    network with the verifier head a third of the crops show no vehicle (rows of
    --calib-verifier-samples), so that the int8 range of vehicle_logit covers negative values."""
    from detector import crops as cropmod
    from detector.datasets import read_sequence, read_yolo, split_from_file
    from detector.train import estimate_gsd

    dets, cps = [], []
    seq = []
    for d in args.calib_data or []:
        seq.extend(read_sequence(d, n_s=n_s))
    real = read_yolo(args.calib_real, n_s=n_s) if args.calib_real else []
    if real and args.calib_real_split:  # calibrate on training images only
        real = split_from_file(real, args.calib_real_split)[0]
    n = args.calib_count
    pick_seq = [seq[i] for i in rng.permutation(len(seq))[:max(0, n - min(len(real), n // 3))]]
    pick_real = [real[i] for i in rng.permutation(len(real))[:n - len(pick_seq)]] if real else []
    for s in pick_seq:
        s = s.loaded()
        dets.append(working_canvas(s.image, hw, args.working_width / s.image.shape[1]))
        for j in rng.permutation(len(s))[:4]:
            if math.isfinite(s.gsd_m[j]) and not s.ignore[j]:
                cen, ang, g, _, _ = cropmod.jittered_crop_target(s.boxes[j], s.gsd_m[j], rng)
                cps.append(cropmod.extract_crop(s.image, cen, ang, g))
    for s in pick_real:
        s = s.loaded()
        gsd = estimate_gsd(s)
        dets.append(working_canvas(s.image, hw, gsd / 0.12 if math.isfinite(gsd) else 0.4))
    if not dets:
        dets = list(qdq.synthetic_images(8, hw[0], hw[1], seed=1))
    if not cps:
        cps = list(qdq.synthetic_images(16, CROP_H, CROP_W, seed=2))
    cps = cps[:max(16, n * 2)]
    if verifier and args.calib_verifier_samples:
        from detector.datasets import load_image
        from detector.train import read_verifier_samples

        rows = [r for p in args.calib_verifier_samples for r in read_verifier_samples(p)
                if r[-1] == 0]
        extra = []
        for i in rng.permutation(len(rows))[:max(8, len(cps) // 2)]:
            path, cx, cy, length, width, angle, gsd, _ = rows[i]
            extra.append(cropmod.extract_crop(load_image(path), (cx, cy), angle, gsd))
        # Interleaved, so that both the calibration and the check share of the list hold some.
        mixed = []
        for k in range(max(len(cps), len(extra))):
            mixed += cps[k:k + 1] + extra[k:k + 1]
        cps = mixed
    return np.stack(dets), np.stack(cps)


class OnnxDetector:
    """Callable like the torch Detector (batch 1 each call), evaluating an ONNX graph with
    qdq.Evaluator: fp32 graphs exactly, QDQ graphs with int8 fake quantization."""

    def __init__(self, model: onnx.ModelProto):
        self.ev = qdq.Evaluator(model)
        self.inp = model.graph.input[0].name

    def __call__(self, x: torch.Tensor) -> Dict[str, torch.Tensor]:
        outs: Dict[str, list] = {}
        for i in range(x.shape[0]):
            r = self.ev.run({self.inp: x[i:i + 1].cpu().numpy()})
            for k, v in r.items():
                outs.setdefault(k, []).append(v)
        return {k: torch.from_numpy(np.concatenate(v)) for k, v in outs.items()}


def evaluate_onnx(det_model, crop_model, samples, hw, working_width) -> dict:
    from detector.evaluate import Predictor, evaluate_samples

    w = samples[0].loaded().image.shape[1]
    pred = Predictor(OnnxDetector(det_model), OnnxDetector(crop_model) if crop_model else None,
                     scale=working_width / w, heatmap_is_prob=True, pad_to=hw)
    return evaluate_samples(pred, samples)


def run_engine_bench(bench: str, model_path: str) -> dict:
    cmd = [bench, f"--model={model_path}", "--benchmark_filter=Int8/threads:1",
           "--benchmark_min_time=0.1"]
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return {"command": " ".join(cmd), "ok": False, "error": str(exc)}
    return {"command": " ".join(cmd), "ok": p.returncode == 0, "returncode": p.returncode,
            "output": (p.stdout + p.stderr)[-3000:]}


def export(args) -> dict:
    from detector.train import _check_out_dir

    _check_out_dir(args.out)
    os.makedirs(args.out, exist_ok=True)
    w, h = (int(v) for v in args.input_size.lower().split("x"))
    hw = (h, w)
    if h % 32 or w % 32:
        raise SystemExit(f"--input-size {args.input_size}: width and height must be multiples of 32")
    ck, det, crop = load_run(args.checkpoint)
    n_s = ck["n_s"]
    rng = np.random.default_rng(args.seed)
    cfg_common = dict(NORMALIZATION, method=args.method)
    report: dict = {"checkpoint": args.checkpoint, "input_size": [w, h], "models": {}}
    calib_det, calib_crop = calibration_images(args, hw, n_s, rng,
                                               verifier=crop is not None and crop.verifier)
    half = max(1, len(calib_det) * 3 // 4)
    jobs = [("detector", det, hw, calib_det, "vp_detector")]
    if crop is not None:
        jobs.append(("crop", crop, (CROP_H, CROP_W), calib_crop, "vp_vehicle_crop"))
    kept_ranges = {}
    for path_kept in args.ranges_from:
        try:
            model_kept = onnx.load(path_kept)
        except OSError as exc:
            raise SystemExit(f"--ranges-from {path_kept}: {exc}") from None
        meta = {p.key: p.value for p in model_kept.metadata_props}
        kind = {"vp_detector": "detector", "vp_vehicle_crop": "crop"}.get(meta.get("vp.model.name", ""))
        if kind is None:
            raise SystemExit(f"--ranges-from {path_kept}: metadata vp.model.name is "
                             f"'{meta.get('vp.model.name', '')}', not vp_detector or vp_vehicle_crop")
        file_ranges = qdq.ranges_of_qdq(model_kept)
        if not file_ranges:
            raise SystemExit(f"--ranges-from {path_kept}: no activation QuantizeLinear nodes")
        kept_ranges[kind] = (path_kept, file_ranges)
    qmodels = {}
    for name, module, shape, calib, model_name in jobs:
        module.export_mode = True
        fp32 = qdq.export_torch(module, (1, 3, *shape), output_names=module.output_names(),
                                path=os.path.join(args.out, f"{name}_fp32.onnx"))
        bad = engine_ops_only(fp32)
        if bad:
            raise SystemExit(f"{name}: operators the engine does not run: {', '.join(bad)}")
        cfg = qdq.QuantConfig(model_name=model_name, model_version=str(ck["step"]), **cfg_common)
        n_cal = max(1, len(calib) * 3 // 4) if len(calib) > 1 else 1
        cal_in = qdq.preprocess(calib[:n_cal], cfg)
        chk_in = qdq.preprocess(calib[n_cal:] if len(calib) > n_cal else calib[:1], cfg)
        ranges = None
        kept = kept_ranges.get(name)
        if kept is not None:
            ranges = qdq.collect_ranges(qdq.prepare_float_model(fp32), cal_in, cfg)
            path_kept, file_ranges = kept
            missing = [t for t in file_ranges if t not in ranges]
            if missing:
                raise SystemExit(f"--ranges-from {path_kept}: tensor '{missing[0]}' is not in the "
                                 f"exported {name} (another network?)")
            ranges.update(file_ranges)
            print(f"{name}: {len(file_ranges)} of {len(ranges)} activation ranges from {path_kept}, "
                  f"the rest (fused into their activation, not quantized) calibrated")
        qm = qdq.quantize_model(fp32, cal_in, cfg, ranges)
        bad = engine_ops_only(qm)
        if bad:
            raise SystemExit(f"{name} QDQ: operators the engine does not run: {', '.join(bad)}")
        path = os.path.join(args.out, f"{name}_int8.onnx")
        onnx.save(qm, path)
        write_checksum(path)
        qmodels[name] = qm
        macs = onnx_macs(fp32)
        entry = {"fp32": os.path.join(args.out, f"{name}_fp32.onnx"), "int8": path,
                 "input": [1, 3, *shape], "macs": macs,
                 "params": int(sum(p.numel() for p in module.parameters())),
                 "ops_int8": op_counts(qm), "calibration_inputs": n_cal,
                 "check_inputs": len(chk_in),
                 "fp32_vs_int8": qdq.compare_models(fp32, qm, chk_in)}
        if name == "detector":
            entry["macs_per_camera_megapixel"] = macs / (CAMERA_PIXELS / 1e6)
            entry["macs_per_working_megapixel"] = macs / (h * w / 1e6)
        else:
            entry["macs_per_vehicle"] = macs
        report["models"][name] = entry
        print(f"{name}: {macs / 1e6:.1f} MMAC, {entry['params']} parameters, wrote {path}")
        print(qdq.format_report(entry["fp32_vs_int8"]))
        if args.engine_bench:
            entry["engine"] = run_engine_bench(args.engine_bench, path)
            print(f"engine: {'ok' if entry['engine']['ok'] else 'FAILED'}: {entry['engine'].get('output', entry['engine'].get('error'))[-600:]}")
    if args.eval_data:
        from detector.datasets import read_sequence

        samples = []
        for d in args.eval_data:
            samples.extend(read_sequence(d, n_s=n_s))
        fp32_det = onnx.load(os.path.join(args.out, "detector_fp32.onnx"))
        fp32_crop = onnx.load(os.path.join(args.out, "crop_fp32.onnx")) if crop else None
        report["eval_fp32"] = evaluate_onnx(fp32_det, fp32_crop, samples, hw, args.working_width)
        report["eval_int8"] = evaluate_onnx(qmodels["detector"], qmodels.get("crop"), samples, hw,
                                            args.working_width)
        print("fp32:", json.dumps(report["eval_fp32"]))
        print("int8:", json.dumps(report["eval_int8"]))
    with open(os.path.join(args.out, "export_report.json"), "w") as f:
        json.dump(report, f, indent=1, default=float)
    return report


def parse_args(argv=None):
    p = argparse.ArgumentParser(description="Export a detector run to ONNX + int8 QDQ.",
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--checkpoint", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--input-size", default=f"{DEFAULT_INPUT_HW[1]}x{DEFAULT_INPUT_HW[0]}",
                   help="detector input WxH (multiples of 32)")
    p.add_argument("--working-width", type=int, default=648,
                   help="width the camera frame is resized to before padding")
    p.add_argument("--calib-data", nargs="*", default=[])
    p.add_argument("--calib-real", default=None)
    p.add_argument("--calib-real-split", default=None,
                   help="split JSON (split_real.py): calibrate only on its training images")
    p.add_argument("--calib-count", type=int, default=32)
    p.add_argument("--calib-verifier-samples", nargs="*", default=[], metavar="CSV",
                   help="with a verifier crop network: background rows of these mine_negatives.py "
                        "lists join the crop calibration (the vehicle_logit range must cover them)")
    p.add_argument("--method", choices=["minmax", "percentile", "mse"], default="minmax")
    p.add_argument("--ranges-from", nargs="*", default=[], metavar="QDQ_ONNX",
                   help="keep the activation quantization of these int8 files of the same networks "
                        "(e.g. models/detector/detector_int8.onnx) instead of calibrating it: a "
                        "fine-tune's export then differs from the file in its weights only")
    p.add_argument("--eval-data", nargs="*", default=[])
    p.add_argument("--engine-bench", default=None, help="path of vp_bench_engine")
    p.add_argument("--seed", type=int, default=0)
    return p.parse_args(argv)


def write_checksum(path: str) -> str:
    """Writes PATH.sha256 in sha256sum's format ("<hex>  <file name>"); returns the digest.

    The engine refuses a model whose bytes do not match it (src/perception/inference/
    model_checksum.hpp), so a copy corrupted on its way to the drone fails at start-up."""
    with open(path, "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()
    with open(path + ".sha256", "w", encoding="ascii") as f:
        f.write(f"{digest}  {os.path.basename(path)}\n")
    return digest


def main(argv=None) -> int:
    export(parse_args(argv))
    return 0


if __name__ == "__main__":
    sys.exit(main())
