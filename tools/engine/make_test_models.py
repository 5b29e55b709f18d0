#!/usr/bin/python3
"""Writes the engine's QDQ test models (tests/fixtures/models/) or the benchmark model.

    tools/engine/make_test_models.py                       # test models -> tests/fixtures/models
    tools/engine/make_test_models.py --out DIR             # elsewhere
    tools/engine/make_test_models.py --bench [OUTDIR]      # bench model (default /tmp/vp_bench_models)

Deterministic: fixed weights (tools/engine/test_models.py, seeded), calibration on synthetic
images (random + smooth; tools/quantize/qdq.py synthetic_images, seed 1) that are not the
check images (seed 1001). For every model it also checks that the ONNX evaluator reproduces
the torch module (float) and prints the float-vs-QDQ (fake-quant) error table.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import sys

import numpy as np
import onnx
import torch

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(ROOT, "tools", "quantize"))

import qdq  # noqa: E402
import test_models  # noqa: E402

# Input normalisation per model (8-bit units, model channel order); the three differ on purpose
# so that the engine's metadata handling is exercised.
NORMALIZATION = {
    "conv_blocks": dict(channel_order="rgb", mean=(0.0, 0.0, 0.0), scale=(1 / 255,) * 3),
    "fpn_heads": dict(channel_order="bgr", mean=(127.5, 127.5, 127.5), scale=(1 / 127.5,) * 3),
    "classifier": dict(channel_order="rgb", mean=(123.675, 116.28, 103.53),
                       scale=(1 / 58.395, 1 / 57.12, 1 / 57.375)),
    "bench": dict(channel_order="rgb", mean=(123.675, 116.28, 103.53),
                  scale=(1 / 58.395, 1 / 57.12, 1 / 57.375)),
}
FP32_COMMIT_LIMIT = 10_000_000  # sanity limit for --fp32


def write_references(qmodel: onnx.ModelProto, cfg: qdq.QuantConfig, out_dir: str, stem: str,
                     h: int, w: int) -> list:
    """<stem>_input.png (an 8-bit test image; cv::imread gives it as BGR) and the outputs the
    engine should produce on it, raw little-endian float32, the model's outputs concatenated
    in graph order, each in NHWC order (as Engine::output(i).data):
      <stem>_ref_int8.bin  QDQ graph with Q/DQ evaluated (fake-quant): XnnpackInt8 target,
                           expect agreement within about one output quantization step;
      <stem>_ref_fp32.bin  QDQ graph with activation Q/DQ dropped, int8 weights dequantized:
                           XnnpackFp32 / OpenCvFp32 target, agreement to float rounding."""
    import cv2

    img = qdq.synthetic_images(4, h, w, seed=7)[3]  # smooth blobs + noise, not a calib image
    png = os.path.join(out_dir, f"{stem}_input.png")
    cv2.imwrite(png, img)
    bgr = cv2.imread(png, cv2.IMREAD_COLOR)
    model_order = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB) if cfg.channel_order == "rgb" else bgr
    x = qdq.preprocess(model_order, cfg)[0]
    in_name = qmodel.graph.input[0].name
    written = [png]
    for tag, model in (("int8", qmodel), ("fp32", qdq.strip_activation_qdq(qmodel))):
        outs = qdq.Evaluator(model).run({in_name: x})
        data = b"".join(np.ascontiguousarray(outs[o.name].transpose(0, 2, 3, 1), "<f4").tobytes()
                        for o in qmodel.graph.output)
        path = os.path.join(out_dir, f"{stem}_ref_{tag}.bin")
        with open(path, "wb") as f:
            f.write(data)
        written.append(path)
    return written


def make(name: str, out_dir: str, n_calib: int, n_check: int, write_fp32: bool,
         file_stem: str, write_refs: bool = False) -> dict:
    torch.manual_seed(0)
    module = test_models.build(name)
    shape = tuple(module.input_shape)
    _, _, h, w = shape
    cfg = qdq.QuantConfig(model_name=file_stem, model_version="1", **NORMALIZATION[name])
    float_model = qdq.export_torch(module, shape, output_names=module.output_names)

    calib = qdq.preprocess(qdq.synthetic_images(n_calib, h, w, seed=1), cfg)
    check = qdq.preprocess(qdq.synthetic_images(n_check, h, w, seed=1001), cfg)

    # the evaluator must reproduce torch on the float graph
    ev = qdq.Evaluator(float_model)
    with torch.no_grad():
        ref = module(torch.from_numpy(check[0]))
    ref = ref if isinstance(ref, tuple) else (ref,)
    got = ev.run({float_model.graph.input[0].name: check[0]})
    for oname, r in zip(module.output_names, ref):
        diff = float(np.abs(got[oname] - r.numpy()).max())
        if diff > 1e-4 * max(1.0, float(r.abs().max())):
            raise SystemExit(f"{name}: evaluator differs from torch on '{oname}' by {diff}")

    qmodel = qdq.quantize_model(float_model, calib, cfg)
    path = os.path.join(out_dir, f"{file_stem}.onnx")
    onnx.save(qmodel, path)
    with open(path, "rb") as f:  # the checksum file the engine verifies (sha256sum's format)
        digest = hashlib.sha256(f.read()).hexdigest()
    with open(path + ".sha256", "w", encoding="ascii") as f:
        f.write(f"{digest}  {os.path.basename(path)}\n")
    info = {"path": path, "size": os.path.getsize(path), "ops": qdq.summarize(qmodel)}
    if write_fp32:
        fpath = os.path.join(out_dir, f"{file_stem}_fp32.onnx")
        data = float_model.SerializeToString()
        if len(data) < FP32_COMMIT_LIMIT:
            onnx.save(float_model, fpath)
            info["fp32"] = (fpath, len(data))
    macs, _ = test_models.count_macs(module, shape)
    info["macs"] = macs
    info["report"] = qdq.compare_models(float_model, qmodel, check)
    if write_refs:
        info["refs"] = write_references(qmodel, cfg, out_dir, file_stem, h, w)
    print(f"== {name}: {path} ({info['size']} bytes, {macs / 1e6:.2f} MMAC, input {shape})")
    print(f"   ops: {info['ops']}")
    if "fp32" in info:
        print(f"   float original: {info['fp32'][0]} ({info['fp32'][1]} bytes)")
    print(qdq.format_report(info["report"]))
    return info


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", default=os.path.join(ROOT, "tests", "fixtures", "models"),
                   help="output folder for the test models")
    p.add_argument("--bench", nargs="?", const="/tmp/vp_bench_models", default=None,
                   metavar="OUTDIR", help="write the benchmark model instead "
                   "(mobilenetv2_512.onnx, default folder /tmp/vp_bench_models)")
    p.add_argument("--only", nargs="*", help="test models to write (default: all)")
    p.add_argument("--fp32", action="store_true",
                   help="also write the float originals <name>_fp32.onnx (not committed)")
    args = p.parse_args()
    torch.set_num_threads(max(1, os.cpu_count() or 1))
    if args.bench:
        os.makedirs(args.bench, exist_ok=True)
        make("bench", args.bench, n_calib=8, n_check=2, write_fp32=False,
             file_stem="mobilenetv2_512")
        return 0
    os.makedirs(args.out, exist_ok=True)
    for name in args.only or list(test_models.TEST_MODELS):
        make(name, args.out, n_calib=32, n_check=8, write_fp32=args.fp32, file_stem=name,
             write_refs=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
