#!/usr/bin/env bash
# Packs vp_simulate with the shared libraries it loads into one .tar.xz, so that a machine
# without the project's build dependencies (a lent GPU machine, x86-64 Linux) can render
# training sequences itself (render.sh). glibc's own libraries are left out: the target's are
# used. About 48 MB for Debian 12's build (OpenCV pulls in GDAL and its dependencies).
#
#   tools/detector/device/pack_simulator.sh OUT.tar.xz [VP_SIMULATE]
set -euo pipefail
if [[ $# -lt 1 || "$1" == "--help" || "$1" == "-h" ]]; then
  sed -n '2,7p' "$0" | sed 's/^# \{0,1\}//'
  exit $([[ $# -lt 1 ]] && echo 2 || echo 0)
fi
out=$1
root=$(cd "$(dirname "$0")/../../.." && pwd)
sim=${2:-$root/build/ci/tools/simulator/vp_simulate}
[[ -x "$sim" ]] || { echo "pack_simulator.sh: $sim not found; build first" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/simpkg/lib"
strip -o "$work/simpkg/vp_simulate" "$sim"
ldd "$sim" | awk '/=>/ {print $3}' |
  grep -v -E '/(libc|libm|libpthread|libdl|librt)\.so|ld-linux' |
  while read -r lib; do cp -L "$lib" "$work/simpkg/lib/"; done
tar -cJf "$out" -C "$work" simpkg
echo "pack_simulator.sh: $(du -h "$out" | cut -f1) in $out ($(ls "$work/simpkg/lib" | wc -l) libraries)"
