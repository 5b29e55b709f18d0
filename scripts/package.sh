#!/usr/bin/env bash
# Builds the Debian packages (CPack DEB): vehicle-perception (drone: app, systemd unit,
# config, models) and vehicle-perception-rsu (roadside unit: vp_rsu_subscriber).
# docs/deployment.md describes them; scripts/test_package.sh installs and tests them.
set -euo pipefail

usage() {
  cat <<'EOF'
Usage: scripts/package.sh [options]

Configures a Release build without tests, builds only what the packages hold, and runs
CPack. Prints each package's path, size, Depends and contents.

Options:
  --build-dir DIR   build folder (default: build-pkg in the repository; for the arm64
                    cross build scripts/cross_build_arm64.sh passes its own)
  --out DIR         where the .deb files go (default: <build-dir>/packages)
  --release N       Debian revision, the N in <version>-N (default 1)
  --jobs N          parallel compile jobs (default 2; the build runs under nice -n 10)
  --cmake-arg ARG   extra argument for the configure step (repeatable), e.g.
                    --cmake-arg -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-aarch64-linux-gnu.cmake
  --skip-setup      do not run scripts/setup.sh first
  -h, --help        this text

Needs the build dependencies (scripts/setup.sh installs them) and dpkg-dev (for
dpkg-shlibdeps, part of build-essential). Idempotent: re-running rebuilds what changed.
EOF
}

cd "$(dirname "$0")/.."
ROOT="$PWD"
BUILD_DIR="$ROOT/build-pkg"
OUT_DIR=""
RELEASE=1
JOBS=2
SETUP=1
CMAKE_ARGS=()

while [ $# -gt 0 ]; do
  case "$1" in
    --build-dir) BUILD_DIR="$(realpath -m "${2:?--build-dir needs a folder}")"; shift 2 ;;
    --out) OUT_DIR="$(realpath -m "${2:?--out needs a folder}")"; shift 2 ;;
    --release) RELEASE="${2:?--release needs a number}"; shift 2 ;;
    --jobs) JOBS="${2:?--jobs needs a number}"; shift 2 ;;
    --cmake-arg) CMAKE_ARGS+=("${2:?--cmake-arg needs an argument}"); shift 2 ;;
    --skip-setup) SETUP=0; shift ;;
    -h|--help) usage; exit 0 ;;
    *) echo "package.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ -n "$OUT_DIR" ] || OUT_DIR="$BUILD_DIR/packages"
case "$RELEASE" in ''|*[!0-9a-z.+~]*) echo "package.sh: --release: bad revision '$RELEASE'" >&2; exit 2 ;; esac

log() { echo "package.sh: $*"; }

if [ "$SETUP" = 1 ]; then
  scripts/setup.sh
fi
for tool in cmake ninja cpack dpkg-deb dpkg-shlibdeps; do
  command -v "$tool" >/dev/null || { echo "package.sh: '$tool' not found (apt-get install cmake ninja-build dpkg-dev)" >&2; exit 1; }
done

log "configuring $BUILD_DIR (Release, no tests, prefix /usr)"
cmake -S "$ROOT" -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DVP_BUILD_TESTS=OFF \
  -DCMAKE_INSTALL_PREFIX=/usr -DCMAKE_SKIP_INSTALL_ALL_DEPENDENCY=ON \
  -DVP_PACKAGE_RELEASE="$RELEASE" ${CMAKE_ARGS[@]+"${CMAKE_ARGS[@]}"} >/dev/null

# Only what the packages hold: the programs and their man pages.
targets=()
available="$(ninja -C "$BUILD_DIR" -t targets all 2>/dev/null | sed -n 's/^\([A-Za-z0-9_.-]*\): .*/\1/p')"
for t in vp_firmware_app vp_firmware_app_man vp_rsu_subscriber vp_rsu_subscriber_man; do
  if grep -qx "$t" <<<"$available"; then targets+=("$t"); fi
done
if ! grep -qx vp_firmware_app <<<"$available"; then
  log "WARNING: no target vp_firmware_app: vehicle-perception is built without the app and unit"
fi
log "building ${targets[*]} (-j$JOBS, nice -n 10)"
nice -n 10 cmake --build "$BUILD_DIR" -j "$JOBS" --target "${targets[@]}"

log "running CPack into $OUT_DIR"
mkdir -p "$OUT_DIR"
rm -f "$OUT_DIR"/*.deb
(cd "$BUILD_DIR" && cpack -G DEB -B "$OUT_DIR" >/dev/null) || {
  echo "package.sh: cpack failed; run 'cd $BUILD_DIR && cpack -G DEB --verbose' for details" >&2
  exit 1
}
rm -rf "$OUT_DIR/_CPack_Packages"

for deb in "$OUT_DIR"/*.deb; do
  echo
  log "$deb"
  echo "  size:      $(stat -c %s "$deb") bytes ($(du -h "$deb" | cut -f1)), installed $(dpkg-deb -f "$deb" Installed-Size) KiB"
  echo "  package:   $(dpkg-deb -f "$deb" Package) $(dpkg-deb -f "$deb" Version) $(dpkg-deb -f "$deb" Architecture)"
  echo "  depends:   $(dpkg-deb -f "$deb" Depends)"
  echo "  conffiles: $(dpkg-deb --ctrl-tarfile "$deb" | tar -xO ./conffiles 2>/dev/null | tr '\n' ' ')"
  echo "  files:"
  dpkg-deb -c "$deb" | awk '$1 !~ /^d/ {print "    " $6 ($7 != "" ? " " $7 " " $8 : "")}'
done
