#!/usr/bin/env bash
# The main job of a fresh machine: installs the dependencies, builds the release binaries, and
# runs the firmware app on a recorded sequence, publishing vehicle states over DDS on loopback
# to a roadside-unit subscriber (vp_rsu_subscriber) in another process.
#   scripts/run.sh [SEQUENCE_DIR] [-- extra vp_firmware_app options]
# Without SEQUENCE_DIR a short sequence (20 frames, 2592 x 2048) is rendered with vp_simulate
# into $OUT (default build/run). Outputs there: states.csv (what the subscriber received),
# tracks.csv (the app's trajectory CSV), traffic/ (the traffic files), bev.png (the subscriber's
# bird's-eye view with the site's gates and counts), app.log, subscriber.log.
# docs/firmware_app.md explains the figures, docs/traffic.md the traffic counts.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ "${1:-}" = "--help" ] || [ "${1:-}" = "-h" ]; then
  sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//'
  exit 0
fi
sequence=""
if [ $# -gt 0 ] && [ "$1" != "--" ]; then
  sequence="$1"
  shift
fi
[ "${1:-}" = "--" ] && shift

scripts/setup.sh
cmake --preset release >/dev/null
cmake --build --preset release -j "$(nproc)" --target vp_firmware_app vp_simulate vp_rsu_subscriber
bin=build/release
out="${OUT:-build/run}"
mkdir -p "$out" "$out/traffic"

if [ -z "$sequence" ]; then
  sequence="$out/sequence"
  if [ ! -f "$sequence/frames.csv" ]; then
    rm -rf "$sequence"
    echo "run: rendering a 20-frame sequence into $sequence (vp_simulate, seed 1)"
    "$bin/tools/simulator/vp_simulate" --scene intersection --seed 1 --frames 20 \
      --threads "$(nproc)" --out "$sequence"
  fi
fi

# DDS on the loopback interface only: nothing leaves the machine.
export CYCLONEDDS_URI='<CycloneDDS><Domain Id="any"><General><Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>30</MaxAutoParticipantIndex><Peers><Peer Address="127.0.0.1"/></Peers></Discovery></Domain></CycloneDDS>'

# The sequence's site map (gates, lanes, zones) is drawn by the subscriber with the counts.
site_args=()
[ -f "$sequence/site.geojson" ] && site_args=(--site "$sequence/site.geojson")
"$bin/tools/rsu_subscriber/vp_rsu_subscriber" --config config/default.yaml --out "$out/states.csv" \
  --bev-png "$out/bev.png" "${site_args[@]}" \
  --until-writers-gone --duration-s 900 2>"$out/subscriber.log" &
subscriber=$!
trap 'kill "$subscriber" 2>/dev/null || true' EXIT
sleep 1

echo "run: vp_firmware_app on $sequence (log: $out/app.log)"
status=0
"$bin/firmware_app/vp_firmware_app" --config config/default.yaml --sequence "$sequence" \
  --trajectory-csv "$out/tracks.csv" --traffic-dir "$out/traffic" "$@" \
  2> >(tee "$out/app.log" >&2) || status=$?
wait "$subscriber" || true
trap - EXIT

states=$(grep -c '^state,' "$out/states.csv" || true)
disposed=$(grep -c '^disposed,' "$out/states.csv" || true)
tracks=$(awk -F, '$1 == "state" { print $3 }' "$out/states.csv" | sort -u | wc -l)
echo "run: vp_firmware_app exit $status; $(grep -o 'frames_in=[0-9]* processed=[0-9]* dropped=[0-9]*' "$out/app.log" | tail -1)"
echo "run: the subscriber received $states vehicle states of $tracks tracks and $disposed disposals ($out/states.csv)"
# Latency at the roadside unit (reception - measurement time) of each frame's last state, median
# over the frames, beside the app's own capture -> publish median (docs/dds.md, "Timestamps").
rsu_latency=$(awk -F, '$1 == "state" { if (!($4 in last) || $5 > last[$4]) last[$4] = $5 }
  END { for (t in last) print last[t] }' "$out/states.csv" | sort -g |
  awk '{ v[NR] = $1 } END { if (NR) printf "%.1f", (NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2) }')
app_e2e=$(grep -o 'e2e_median_ms=[0-9.]*' "$out/app.log" | tail -1 | cut -d= -f2 || true)
# Traffic: the gate counts the subscriber received (totals over the periods) and the files.
traffic=$(grep -o 'traffic totals: .*' "$out/subscriber.log" | tail -1 || true)
[ -n "$traffic" ] && echo "run: the subscriber's $traffic ($out/traffic/traffic_counts.csv, $out/bev.png)"
[ -n "$rsu_latency" ] && echo "run: latency at the subscriber ${rsu_latency} ms (median over frames of each frame's last state); the app's capture -> publish ${app_e2e:-?} ms"
exit "$status"
