#!/usr/bin/env bash
# Unpacks a pack_simulator.sh archive and renders 2-frame training sequences (seeds
# FIRST .. LAST-1, with make_sim_data.sh: its scenes and size) on N cores for at most SECONDS.
# Finished sequences land in OUTDIR; one cut off by the time limit is dropped.
#
#   tools/detector/device/render.sh PACK.tar.xz OUTDIR SECONDS [FIRST=1000] [LAST=2000] [N=nproc]
set -uo pipefail
if [[ $# -lt 3 || "$1" == "--help" || "$1" == "-h" ]]; then
  sed -n '2,6p' "$0" | sed 's/^# \{0,1\}//'
  exit $([[ $# -lt 3 ]] && echo 2 || echo 0)
fi
pack=$1 out=$2 seconds=$3 first=${4:-1000} last=${5:-2000} n=${6:-$(nproc)}
tmp=$(mktemp -d)
mkdir -p "$out" "$tmp/partial"
tar -xJf "$pack" -C "$tmp" || { echo "render.sh: cannot unpack $pack" >&2; exit 1; }
export LD_LIBRARY_PATH=$tmp/simpkg/lib SIM=$tmp/simpkg/vp_simulate OUT=$out PARTIAL=$tmp/partial
"$SIM" --help >/dev/null 2>&1 || { echo "render.sh: vp_simulate does not start here" >&2; exit 1; }
# Each seed through make_sim_data.sh (its scene rule and frame size), into a folder of its own
# that moves to OUTDIR only when complete.
make=$(cd "$(dirname "$0")/.." && pwd)/make_sim_data.sh
worker() {  # worker K: seeds first+K, first+K+n, ...
  local s
  for ((s = first + $1; s < last; s += n)); do
    VP_SIMULATE=$SIM THREADS=1 "$make" "$PARTIAL/$s" "$s" 1 2 >/dev/null 2>&1 &&
      mv "$PARTIAL/$s"/* "$OUT/"
  done
}
export -f worker
export first last n make
t0=$(date +%s)
for ((k = 0; k < n; k++)); do timeout "$seconds" bash -c "worker $k" & done
wait
echo "render.sh: $(ls "$out" | wc -l) sequences in $out after $(($(date +%s) - t0)) s"
rm -rf "$tmp"
