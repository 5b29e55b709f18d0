#!/usr/bin/python3
"""PyTorch baselines for the engine benchmark, on the same architecture as the bench model
(tools/engine/test_models.py MobileNetV2Backbone, 512 x 512, same seeded weights):

  torch fp32                 eager float
  torch int8 (onednn)        eager-mode post-training static quantization (torch.ao.quantization:
  torch int8 (qnnpack)       fuse Conv+ReLU, prepare, calibrate, convert), per quantized engine

Debian's torch build has the quantized engines ['qnnpack', 'onednn'] (no 'fbgemm'); onednn is
the x86 one. Threads 1 and 2 (torch.set_num_threads). Median latency over --runs runs after
--warmup runs. GMAC/s uses the MAC count of the architecture (test_models.count_macs:
Conv: Cout*Hout*Wout*Cin/groups*kh*kw), the same definition as the engine's totalMacs().

Output: a Markdown table on stdout; --json FILE also writes the rows for scripts/bench_engine.sh.
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import statistics
import sys
import time

import numpy as np
import torch

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(HERE)), "tools", "quantize"))

import qdq  # noqa: E402
import test_models  # noqa: E402
from make_test_models import NORMALIZATION  # noqa: E402


def time_model(model, x, threads: int, warmup: int, runs: int) -> float:
    torch.set_num_threads(threads)
    with torch.inference_mode():
        for _ in range(warmup):
            model(x)
        times = []
        for _ in range(runs):
            t0 = time.perf_counter()
            model(x)
            times.append(time.perf_counter() - t0)
    return statistics.median(times) * 1e3


def quantize_torch(float_model, engine: str, calib) -> torch.nn.Module:
    from torch.ao.quantization import convert, get_default_qconfig, prepare

    torch.backends.quantized.engine = engine
    m = test_models.fuse_conv_relu(copy.deepcopy(float_model).eval())
    m.qconfig = get_default_qconfig(engine)
    prepare(m, inplace=True)
    with torch.inference_mode():
        for x in calib:
            m(x)
    convert(m, inplace=True)
    return m


def sqnr_db(ref: torch.Tensor, out: torch.Tensor) -> float:
    noise = float(((out - ref) ** 2).mean())
    return 10 * np.log10(float((ref ** 2).mean()) / noise) if noise > 0 else float("inf")


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    p.add_argument("--runs", type=int, default=20)
    p.add_argument("--warmup", type=int, default=3)
    p.add_argument("--engines", nargs="+", default=["onednn", "qnnpack"])
    p.add_argument("--json", help="write the rows as JSON here")
    args = p.parse_args()

    torch.manual_seed(0)
    model = test_models.build("bench")
    shape = model.input_shape
    macs, _ = test_models.count_macs(model, shape)
    cfg = qdq.QuantConfig(**NORMALIZATION["bench"])
    calib = [torch.from_numpy(a) for a in
             qdq.preprocess(qdq.synthetic_images(8, shape[2], shape[3], seed=1), cfg)]
    x = torch.from_numpy(qdq.preprocess(qdq.synthetic_images(1, shape[2], shape[3], seed=99),
                                        cfg)[0])
    with torch.inference_mode():
        ref = model(x)

    rows = []
    variants = [("torch fp32", model, None)]
    print(f"supported quantized engines: {torch.backends.quantized.supported_engines}",
          file=sys.stderr)
    for engine in args.engines:
        if engine not in torch.backends.quantized.supported_engines:
            print(f"skipping {engine}: not in this torch build", file=sys.stderr)
            continue
        try:
            qm = quantize_torch(model, engine, calib)
            with torch.inference_mode():
                err = sqnr_db(ref, qm(x))
            variants.append((f"torch int8 ({engine})", qm, engine))
            print(f"torch int8 ({engine}): SQNR vs float {err:.1f} dB", file=sys.stderr)
        except Exception as exc:  # report, keep the other variants
            print(f"torch int8 ({engine}) failed: {exc}", file=sys.stderr)

    for label, m, engine in variants:
        if engine:
            torch.backends.quantized.engine = engine
        for t in args.threads:
            ms = time_model(m, x, t, args.warmup, args.runs)
            rows.append({"backend": label, "threads": t, "median_ms": ms,
                         "gmacs": macs / (ms * 1e-3) / 1e9, "macs": macs})
            print(f"{label:24s} threads={t}: {ms:8.2f} ms  {rows[-1]['gmacs']:7.1f} GMAC/s",
                  file=sys.stderr)

    print(f"model: MobileNetV2Backbone {shape}, {macs / 1e9:.3f} GMAC, torch {torch.__version__}, "
          f"median of {args.runs} runs after {args.warmup} warm-up\n")
    print("| backend | threads | median ms | GMAC/s |")
    print("| --- | ---: | ---: | ---: |")
    for r in rows:
        print(f"| {r['backend']} | {r['threads']} | {r['median_ms']:.2f} | {r['gmacs']:.1f} |")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"macs": macs, "rows": rows}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
