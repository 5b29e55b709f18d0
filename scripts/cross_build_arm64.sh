#!/usr/bin/env bash
# Cross-builds the project for aarch64 (Debian arm64) on an amd64 Debian 12 machine with
# Debian's cross compiler, against an arm64 sysroot, and runs the tests under QEMU user
# emulation. docs/deployment.md ("Cross-building for aarch64") explains the choices.
set -euo pipefail

usage() {
  cat <<'EOF'
Usage: scripts/cross_build_arm64.sh [options]          (as root, or with sudo for apt-get)

  1. installs the cross tools: g++-aarch64-linux-gnu, qemu-user-static (+ scripts/setup.sh
     for the build machine's own tools, e.g. idlc)
  2. makes the arm64 sysroot once: the arm64 -dev packages of scripts/setup.sh and their
     dependencies, downloaded with a private apt state (this machine's dpkg database and
     packages are not touched) and unpacked; absolute symlinks made relative
  3. configures --build-dir with cmake/toolchain-aarch64-linux-gnu.cmake, builds (nice -n 10)
  4. runs the tests with ctest; each test binary runs under qemu-aarch64-static -L <sysroot>
  5. with --package: also builds the arm64 .deb files (scripts/package.sh)

Options:
  --sysroot DIR     the arm64 sysroot (default /work/pkgwork/sysroot-arm64; made if missing)
  --build-dir DIR   build folder (default build-arm64 in the repository)
  --jobs N          parallel compile jobs (default 2)
  --target T        build only target T (repeatable; default: everything)
  --no-tests        build only, run no tests
  --test-regex RE   run only the tests matching RE (ctest -R)
  --sysroot-only    stop after step 2
  --refresh-sysroot download and unpack the sysroot again (e.g. after a Debian point release)
  --package         step 5: arm64 packages into <build-dir>-pkg/packages. Their Depends are
                    copied from the amd64 packages in build-pkg/packages (same Debian release,
                    same package names and versions; run scripts/package.sh first), because
                    dpkg-shlibdeps cannot see a sysroot's libraries
  -h, --help        this text

Why a sysroot and not multiarch: on Debian 12 libopencv-dev, libyaml-cpp-dev,
libgeographiclib-dev, libxnnpack-dev and libpthreadpool-dev (and the libxnnpack0,
libopencv-imgcodecs406 runtimes) are not "Multi-Arch: same", so installing their arm64
versions removes the amd64 ones this machine builds with.
EOF
}

cd "$(dirname "$0")/.."
REPO="$PWD"
SYSROOT=/work/pkgwork/sysroot-arm64
BUILD_DIR="$REPO/build-arm64"
JOBS=2
TARGETS=()
RUN_TESTS=1
TEST_REGEX=""
SYSROOT_ONLY=0
REFRESH=0
PACKAGE=0
while [ $# -gt 0 ]; do
  case "$1" in
    --sysroot) SYSROOT="$(realpath -m "${2:?--sysroot needs a folder}")"; shift 2 ;;
    --build-dir) BUILD_DIR="$(realpath -m "${2:?--build-dir needs a folder}")"; shift 2 ;;
    --jobs) JOBS="${2:?--jobs needs a number}"; shift 2 ;;
    --target) TARGETS+=("${2:?--target needs a name}"); shift 2 ;;
    --no-tests) RUN_TESTS=0; shift ;;
    --test-regex) TEST_REGEX="${2:?--test-regex needs a regular expression}"; shift 2 ;;
    --sysroot-only) SYSROOT_ONLY=1; shift ;;
    --refresh-sysroot) REFRESH=1; shift ;;
    --package) PACKAGE=1; shift ;;
    -h|--help) usage; exit 0 ;;
    *) echo "cross_build_arm64.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done

log() { echo "cross_build_arm64.sh: $*"; }
fail() { echo "cross_build_arm64.sh: error: $*" >&2; exit 1; }
case "$SYSROOT" in "$REPO"/*) fail "--sysroot must be outside the repository ($SYSROOT)" ;; esac
SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"

# arm64 packages of the sysroot: the -dev packages of scripts/setup.sh (not the build tools,
# which run on this machine) plus the C/C++ runtime.
SYSROOT_PACKAGES=(
  libc6-dev libstdc++-12-dev
  libeigen3-dev libopencv-dev libyaml-cpp-dev libgeographiclib-dev
  libtiff-dev libgeotiff-dev
  libxnnpack-dev libpthreadpool-dev libonnx-dev libprotobuf-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  cyclonedds-dev libcycloneddsidl0
)

# --- 1. cross tools ----------------------------------------------------------------------------
scripts/setup.sh
missing=()
for p in g++-aarch64-linux-gnu qemu-user-static; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  log "installing ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# --- 2. sysroot ----------------------------------------------------------------------------------
STAMP="$SYSROOT/.vp-sysroot"
want_stamp="bookworm arm64: ${SYSROOT_PACKAGES[*]}"
if [ "$REFRESH" = 1 ] || [ ! -f "$STAMP" ] || [ "$(cat "$STAMP")" != "$want_stamp" ]; then
  APT_DIR="$SYSROOT.apt"
  log "making the arm64 sysroot $SYSROOT (apt state in $APT_DIR)"
  mkdir -p "$APT_DIR"/etc/apt/sources.list.d "$APT_DIR"/etc/apt/preferences.d \
           "$APT_DIR"/etc/apt/apt.conf.d "$APT_DIR"/var/lib/apt/lists/partial \
           "$APT_DIR"/var/cache/apt/archives/partial "$APT_DIR"/var/lib/dpkg
  : > "$APT_DIR/var/lib/dpkg/status"  # empty: apt fetches the whole dependency closure
  cat > "$APT_DIR/etc/apt/sources.list.d/debian.sources" <<'EOF'
Types: deb
URIs: http://deb.debian.org/debian
Suites: bookworm bookworm-updates
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg

Types: deb
URIs: http://deb.debian.org/debian-security
Suites: bookworm-security
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
EOF
  APT=(apt-get -o Dir="$APT_DIR" -o Dir::State::status="$APT_DIR/var/lib/dpkg/status"
       -o APT::Architecture=arm64 -o APT::Architectures::=arm64 -o Debug::NoLocking=1
       -o Dir::Etc::trusted=/etc/apt/trusted.gpg -o Dir::Etc::trustedparts=/etc/apt/trusted.gpg.d)
  "${APT[@]}" update -qq
  log "downloading ${SYSROOT_PACKAGES[*]} and their dependencies (arm64)"
  "${APT[@]}" install -y -qq --download-only --no-install-recommends "${SYSROOT_PACKAGES[@]}"
  debs=("$APT_DIR"/var/cache/apt/archives/*.deb)
  log "unpacking ${#debs[@]} packages"
  rm -rf "$SYSROOT"
  mkdir -p "$SYSROOT"/usr/lib "$SYSROOT"/usr/bin "$SYSROOT"/usr/sbin
  ln -s usr/lib "$SYSROOT/lib"; ln -s usr/bin "$SYSROOT/bin"; ln -s usr/sbin "$SYSROOT/sbin"
  for d in "${debs[@]}"; do
    dpkg-deb --fsys-tarfile "$d" | tar -x --keep-directory-symlink -C "$SYSROOT"
  done
  # Absolute symlinks (libz.so -> /lib/...) would point into this machine: make them relative.
  n=0
  while IFS= read -r -d '' l; do
    t="$(readlink "$l")"
    ln -sfn "$(realpath -m --relative-to="$(dirname "$l")" "$SYSROOT$t")" "$l"
    n=$((n + 1))
  done < <(find "$SYSROOT" -type l -lname '/*' -print0)
  log "made $n absolute symlinks relative"
  # update-alternatives links that the (not run) maintainer scripts would have made.
  for alt in blas lapack; do
    for f in "$SYSROOT"/usr/lib/aarch64-linux-gnu/$alt/lib$alt.so*; do
      [ -e "$f" ] || continue
      b="$(basename "$f")"
      [ -e "$SYSROOT/usr/lib/aarch64-linux-gnu/$b" ] || ln -s "$alt/$b" "$SYSROOT/usr/lib/aarch64-linux-gnu/$b"
    done
  done
  echo "$want_stamp" > "$STAMP"
  log "sysroot ready: $(du -sh "$SYSROOT" | cut -f1)"
else
  log "sysroot $SYSROOT is up to date"
fi
[ "$SYSROOT_ONLY" = 1 ] && exit 0

# --- 3. configure + build ------------------------------------------------------------------------
TOOLCHAIN="$REPO/cmake/toolchain-aarch64-linux-gnu.cmake"
log "configuring $BUILD_DIR (Release, $TOOLCHAIN)"
cmake -S "$REPO" -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_TOOLCHAIN_FILE="$TOOLCHAIN" -DVP_ARM64_SYSROOT="$SYSROOT" >/dev/null
log "building ${TARGETS[*]:-everything} (-j$JOBS, nice -n 10)"
nice -n 10 cmake --build "$BUILD_DIR" -j "$JOBS" ${TARGETS[@]+--target "${TARGETS[@]}"}
for exe in firmware_app/vp_firmware_app tools/rsu_subscriber/vp_rsu_subscriber; do
  [ -f "$BUILD_DIR/$exe" ] && log "built $exe: $(file -b "$BUILD_DIR/$exe" | cut -d, -f1-2)"
done

# --- 4. tests under QEMU ------------------------------------------------------------------------
if [ "$RUN_TESTS" = 1 ]; then
  log "running the tests under qemu-aarch64-static -L $SYSROOT (ctest)"
  set +e
  (cd "$BUILD_DIR" && nice -n 10 ctest -j "$JOBS" --output-on-failure --timeout 600 \
     ${TEST_REGEX:+-R "$TEST_REGEX"} > "$BUILD_DIR/ctest-arm64.log" 2>&1)
  rc=$?
  set -e
  grep -E "tests passed|tests failed|^\s+[0-9]+ - " "$BUILD_DIR/ctest-arm64.log" || true
  log "full log: $BUILD_DIR/ctest-arm64.log"
  [ $rc -eq 0 ] || log "some tests failed under emulation (list above)"
fi

# --- 5. packages -----------------------------------------------------------------------------------
if [ "$PACKAGE" = 1 ]; then
  shopt -s nullglob
  amd64_vp=("$REPO"/build-pkg/packages/vehicle-perception_*_amd64.deb)
  amd64_rsu=("$REPO"/build-pkg/packages/vehicle-perception-rsu_*_amd64.deb)
  [ ${#amd64_vp[@]} -eq 1 ] && [ ${#amd64_rsu[@]} -eq 1 ] \
    || fail "--package needs the amd64 packages in build-pkg/packages (run scripts/package.sh)"
  scripts/package.sh --skip-setup --build-dir "$BUILD_DIR-pkg" --jobs "$JOBS" \
    --cmake-arg "-DCMAKE_TOOLCHAIN_FILE=$TOOLCHAIN" --cmake-arg "-DVP_ARM64_SYSROOT=$SYSROOT" \
    --cmake-arg "-DVP_DEB_SHLIBDEPS=OFF" \
    --cmake-arg "-DVP_DEB_DEPENDS_VP=$(dpkg-deb -f "${amd64_vp[0]}" Depends)" \
    --cmake-arg "-DVP_DEB_DEPENDS_RSU=$(dpkg-deb -f "${amd64_rsu[0]}" Depends)"
fi
exit ${rc:-0}
