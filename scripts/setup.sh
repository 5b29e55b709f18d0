#!/usr/bin/env bash
# Installs everything the project needs to build and test, from Debian 12 packages only.
# Idempotent: safe to run again; packages already present are left as they are.
#   scripts/setup.sh           build and test dependencies (C++)
#   scripts/setup.sh --python  also Debian's Python stack for training, model tools and the
#                              PyTorch side of the engine benchmark (python3-torch etc.)
#   scripts/setup.sh --fuzz    also clang and its libFuzzer/sanitizer runtime (libclang-rt-14-dev)
#                              for scripts/fuzz.sh (docs/fuzzing.md); CI's g++ build needs neither
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config git python3
  libeigen3-dev libopencv-dev libyaml-cpp-dev libgeographiclib-dev
  libtiff-dev libgeotiff-dev
  libxnnpack-dev libpthreadpool-dev libonnx-dev libprotobuf-dev libdnnl-dev ocl-icd-opencl-dev
  libgtest-dev libgmock-dev googletest libbenchmark-dev
  clang-format
  cyclonedds-dev cyclonedds-tools libcycloneddsidl0
)

for option in "$@"; do
  case "$option" in
    --python) PACKAGES+=(python3 python3-torch python3-onnx python3-numpy python3-opencv) ;;
    --fuzz) PACKAGES+=(clang libclang-rt-14-dev) ;;
    *) echo "setup: unknown option $option (--python, --fuzz)" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages already installed"
  exit 0
fi

SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
echo "setup: installing ${missing[*]}"
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "setup: done"
