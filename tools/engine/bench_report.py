#!/usr/bin/python3
"""Combines the engine benchmark (Google Benchmark JSON), the PyTorch baselines
(bench_torch.py --json) and the measured int8 peak (peak_int8 output) into one Markdown table.
Used by scripts/bench_engine.sh.

Peak = per-core MAC throughput measured by tools/engine/peak_int8.cpp (independent
instruction streams, no memory traffic) x number of cores:
  VNNI peak        vpdpbusd zmm, 64 int8 MACs per instruction;
  kernel-ISA peak  vpmaddwd zmm + vpaddd zmm per 32 MACs (int8 sign-extended to int16), the
                   instruction pair of XNNPACK 2022-02's avx512skx QS8/QC8 GEMM kernels.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import sys


def parse_peak(path: str) -> dict:
    peak = {}
    with open(path) as f:
        for line in f:
            parts = line.split()
            if len(parts) == 4:
                name, _, ipn, gmacs = parts
                peak[name] = (float(ipn), float(gmacs))
    return peak


def engine_rows(path: str) -> list:
    with open(path) as f:
        data = json.load(f)
    rows, errors = [], []
    for b in data.get("benchmarks", []):
        name = b.get("run_name", b["name"])
        m = re.match(r"engine/(\w+)/threads:(\d+)", name)
        if not m:
            continue
        if b.get("error_occurred"):
            errors.append(f"{m.group(1)} threads {m.group(2)}: {b.get('error_message')}")
            continue
        agg = b.get("aggregate_name")
        if agg not in (None, "median"):
            continue
        if agg is None and any(r["key"] == (m.group(1), int(m.group(2))) for r in rows):
            continue  # no aggregates: keep the first run
        unit = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[b.get("time_unit", "ns")]
        ms = b["real_time"] * unit
        gmac = b.get("GMAC", float("nan"))
        rows.append({"key": (m.group(1), int(m.group(2))), "backend": f"vp engine {m.group(1)}",
                     "threads": int(m.group(2)), "median_ms": ms, "gmacs": gmac / (ms * 1e-3),
                     "macs": gmac * 1e9})
    return rows + [{"error": e} for e in errors]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--engine-json", required=True)
    p.add_argument("--torch-json")
    p.add_argument("--peak", required=True, help="peak_int8 output (several runs: max is used)")
    p.add_argument("--cores", type=int, default=os.cpu_count())
    p.add_argument("--model", default="")
    p.add_argument("--out", help="also write the Markdown here")
    args = p.parse_args()

    peak = parse_peak(args.peak)
    vnni_core = peak["vpdpbusd_zmm"][1]
    isa_core = peak["vpmaddwd+vpaddd_zmm"][1]
    clock = peak.get("clock_ghz", (float("nan"), 0))[0]
    vnni, isa = vnni_core * args.cores, isa_core * args.cores

    rows = engine_rows(args.engine_json)
    errors = [r["error"] for r in rows if "error" in r]
    rows = [r for r in rows if "error" not in r]
    order = {"XnnpackInt8": 0, "DnnlInt8": 1, "XnnpackFp32": 2, "OpenCvFp32": 3}
    rows.sort(key=lambda r: (order.get(r["key"][0], 9), r["threads"]))
    torch_macs = None
    if args.torch_json and os.path.exists(args.torch_json):
        with open(args.torch_json) as f:
            tj = json.load(f)
        torch_macs = tj["macs"]
        rows += tj["rows"]

    cpu = platform.processor() or "cpu"
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name"))
    except (OSError, StopIteration):
        pass
    try:
        load = open("/proc/loadavg").read().split()[:3]
    except OSError:
        load = ["?"]
    engine_macs = next((r["macs"] for r in rows if "macs" in r and r["backend"].startswith("vp")),
                       None)
    lines = [
        f"## Engine benchmark: {os.path.basename(args.model) or 'model'}",
        "",
        f"CPU: {cpu}, {args.cores} cores, measured clock ~{clock:.2f} GHz (nominal 2.1 GHz); "
        f"load average at the end {' '.join(load)}.",
        f"MACs per run: engine {engine_macs / 1e9 if engine_macs else float('nan'):.4f} G"
        + (f", torch count {torch_macs / 1e9:.4f} G" if torch_macs else "") + ".",
        f"Int8 peak ({args.cores} cores, measured by tools/engine/peak_int8.cpp): "
        f"VNNI (vpdpbusd zmm, 64 MAC/instr, {peak['vpdpbusd_zmm'][0]:.2f} instr/ns/core) "
        f"= **{vnni:.0f} GMAC/s**; kernel-ISA (vpmaddwd+vpaddd zmm, 32 MAC/pair, "
        f"{peak['vpmaddwd+vpaddd_zmm'][0]:.2f} pairs/ns/core) = **{isa:.0f} GMAC/s**.",
        "",
        "| backend | threads | median ms | GMAC/s | % of VNNI peak | % of kernel-ISA peak |",
        "| --- | ---: | ---: | ---: | ---: | ---: |",
    ]
    for r in rows:
        lines.append(f"| {r['backend']} | {r['threads']} | {r['median_ms']:.2f} | "
                     f"{r['gmacs']:.1f} | {100 * r['gmacs'] / vnni:.1f} % | "
                     f"{100 * r['gmacs'] / isa:.1f} % |")
    lines += ["", "Peaks are for the whole CPU (all cores); a 1-thread run can reach at most "
              f"1/{args.cores} of them. fp32 rows are shown against the same int8 peaks."]
    if errors:
        lines += ["", "Failed: " + "; ".join(errors)]
    text = "\n".join(lines) + "\n"
    sys.stdout.write(text)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
