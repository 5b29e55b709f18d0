#!/usr/bin/env bash
# DDS throughput and latency on this machine (loopback), ours beside Cyclone's ddsperf:
#   scripts/bench_dds.sh [DURATION_S]          (default 20; BUILD=build/ci by default)
# 1. vp_bench_dds writes 200 vehicle states per frame at 10 Hz, as the app does, to 4
#    vp_rsu_subscriber processes; each reports received/expected and the latency from the
#    source timestamp (median, p99).
# 2. ddsperf: the same load shape (200 keys, keep-last 1, bursts of 200 samples of 236 bytes at
#    10 Hz) to 4 "ddsperf sub" processes, then ping/pong at 10 Hz for the round-trip latency.
# Needs cyclonedds-tools (ddsperf). Every process uses a loopback-only Cyclone configuration
# and its own domain, so nothing leaves the machine.
set -euo pipefail
cd "$(dirname "$0")/.."
duration="${1:-20}"
build="${BUILD:-build/ci}"
vehicles=200
rate=10
readers=4
size=236 # serialised VehicleState (XCDR2: encapsulation + DHEADER + fields)

command -v ddsperf >/dev/null || { echo "bench_dds: ddsperf not found (apt-get install cyclonedds-tools)" >&2; exit 1; }
if [ -f "$build/build.ninja" ]; then
  cmake --build "$build" --target vp_bench_dds vp_rsu_subscriber -j"${JOBS:-2}" >/dev/null
fi
bench="$build/tests/bench/vp_bench_dds"
rsu="$build/tools/rsu_subscriber/vp_rsu_subscriber"
[ -x "$bench" ] && [ -x "$rsu" ] || { echo "bench_dds: build $bench and $rsu first" >&2; exit 1; }

export CYCLONEDDS_URI='<CycloneDDS><Domain Id="any"><General><Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>60</MaxAutoParticipantIndex><Peers><Peer Address="127.0.0.1"/></Peers></Discovery></Domain></CycloneDDS>'
out="$(mktemp -d /tmp/bench_dds.XXXXXX)"
base=$((100 + RANDOM % 100))
expected=$((vehicles * duration * rate))
echo "bench_dds: $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg); logs in $out"

# --- ours ------------------------------------------------------------------------------------
pids=()
for i in $(seq 1 $readers); do
  "$rsu" --domain "$base" --partition "bench_$$" --out /dev/null --until-writers-gone \
    --duration-s $((duration + 60)) 2>"$out/rsu_$i.err" &
  pids+=($!)
done
"$bench" --domain "$base" --partition "bench_$$" --vehicles $vehicles --rate-hz $rate \
  --duration-s "$duration" --readers $readers | tee "$out/bench.txt"
wait "${pids[@]}"

# --- ddsperf ---------------------------------------------------------------------------------
pids=()
for i in $(seq 1 $readers); do
  ddsperf -i $((base + 1)) -n $vehicles -k 1 -D $((duration + 8)) sub waitset >"$out/ddsperf_sub_$i.log" 2>&1 &
  pids+=($!)
done
ddsperf -i $((base + 1)) -n $vehicles -k 1 -D "$duration" -Qminmatch:$readers -Qinitwait:30 \
  pub ${rate}Hz burst $vehicles size $size >"$out/ddsperf_pub.log" 2>&1 || true
wait "${pids[@]}" || true
ddsperf -i $((base + 2)) -D $((duration + 8)) pong >"$out/ddsperf_pong.log" 2>&1 &
pong=$!
ddsperf -i $((base + 2)) -D "$duration" -Qminmatch:1 -Qinitwait:30 ping ${rate}Hz size $size >"$out/ddsperf_ping.log" 2>&1 || true
kill "$pong" 2>/dev/null || true
wait "$pong" 2>/dev/null || true

# --- side by side ----------------------------------------------------------------------------
echo
echo "load: $vehicles samples x $rate Hz for ${duration} s = $expected samples per subscriber, $readers subscribers, loopback"
printf '%-12s %-26s %-22s %-22s\n' "subscriber" "received / expected" "latency median" "latency p99"
for i in $(seq 1 $readers); do
  line=$(grep -o 'latency n=[0-9]* median=[0-9.]* ms p99=[0-9.]* ms' "$out/rsu_$i.err" | tail -1 || true)
  n=$(sed 's/.*latency n=\([0-9]*\).*/\1/' <<<"$line")
  med=$(sed 's/.*median=\([0-9.]*\) ms.*/\1/' <<<"$line")
  p99=$(sed 's/.*p99=\([0-9.]*\) ms.*/\1/' <<<"$line")
  printf '%-12s %-26s %-22s %-22s\n' "vp rsu $i" "$n / $expected" "$med ms (one way)" "$p99 ms (one way)"
done
for i in $(seq 1 $readers); do
  # "ddsperf sub" prints once a second: "... size S total N lost L delta ... rate R kS/s".
  last=$( (grep -o 'total [0-9]* lost [0-9]*' "$out/ddsperf_sub_$i.log" || true) | tail -1)
  total=$(awk '{print $2}' <<<"$last")
  lost=$(awk '{print $4}' <<<"$last")
  printf '%-12s %-26s %s\n' "ddsperf $i" "${total:-0} / $expected" "lost (sequence gaps) ${lost:-?}"
done
# "ddsperf ping" prints per second: "... 50% Xus 90% Yus 99% Zus ..." (round trip).
pingcol() { # the per-second values of column "$1" (e.g. 50%), in microseconds, sorted
  (grep -E 'size [0-9]+ mean' "$out/ddsperf_ping.log" || true) |
    awk -v col="$1" '{for (i = 1; i <= NF; i++) if ($i == col) print $(i + 1) + 0}' | sort -n
}
seconds=$(pingcol 50% | wc -l)
median=$(pingcol 50% | awk -v n="$seconds" 'NR == int((n + 1) / 2)')
worst=$(pingcol 99% | tail -1)
stats="median of per-second medians ${median:-?} us, worst per-second p99 ${worst:-?} us ($seconds s)"
echo "ddsperf ping/pong ($size bytes, ${rate} Hz) round trip: $stats"
echo "(ours: one way from the source timestamp, through the RSU's take loop; ddsperf: round trip)"
