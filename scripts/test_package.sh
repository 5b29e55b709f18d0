#!/usr/bin/env bash
# Tests the Debian packages on a fresh Debian 12 (debootstrap --variant=minbase bookworm):
# install with apt (dependencies from the Debian mirror), check the files, run the unit's
# ExecStart the way systemd would (notify socket, watchdog, SIGTERM) on a recorded
# sequence, then remove and purge and check that nothing is left behind.
set -euo pipefail

usage() {
  cat <<'EOF'
Usage: scripts/test_package.sh [options]        (as root: debootstrap, chroot, mounts)

Steps (each prints what it does; the first failure stops the script with exit status 1):
  1. packages: build them with scripts/package.sh unless --deb-dir already holds them
  2. root: a fresh copy of a cached Debian 12 minbase root (debootstrap on first use)
  3. install: apt-get install ./vehicle-perception_*.deb ./vehicle-perception-rsu_*.deb;
     lists the packages apt added and their size; checks files, conffiles, the installed
     config's paths, ldd, --help, man pages; systemd-analyze verify / security (offline)
  4. service: ExecStart and EnvironmentFile of the installed unit, run as an unprivileged
     user (DynamicUser stand-in) with NOTIFY_SOCKET / WATCHDOG_USEC / WATCHDOG_PID /
     STATE_DIRECTORY set like systemd does; VP_ARGS replays a recorded sequence in a loop.
     packaging/tests/sd_notify_harness.py checks READY=1, >= 2 WATCHDOG=1 in time,
     STOPPING=1 and exit status 0 after SIGTERM.
  5. remove: dpkg -r leaves only the conffiles; dpkg -P leaves nothing of the packages,
     and no file that was not there before installation (dependencies stay installed)

Options:
  --deb-dir DIR     folder with the .deb files (default: build-pkg/packages; built if empty)
  --cache DIR       where the minbase root tarball is kept (default /work/pkgwork)
  --work DIR        the test root is unpacked here (default <cache>/test-root; replaced)
  --mirror URL      Debian mirror for debootstrap (default http://deb.debian.org/debian)
  --sequence DIR    recorded sequence to replay (default tests/fixtures/sequence_min with
                    its DTM; any docs/recorded_sequence.md folder, e.g. from vp_simulate)
  --watchdog-sec S  WatchdogSec for the run (default: the unit's value)
  --keep            leave the test root and its mounts' folders for inspection
  -h, --help        this text
EOF
}

cd "$(dirname "$0")/.."
REPO="$PWD"
DEB_DIR="$REPO/build-pkg/packages"
CACHE=/work/pkgwork
WORK=""
MIRROR=http://deb.debian.org/debian
SEQUENCE="$REPO/tests/fixtures/sequence_min"
WATCHDOG_SEC=""
KEEP=0
while [ $# -gt 0 ]; do
  case "$1" in
    --deb-dir) DEB_DIR="$(realpath -m "${2:?--deb-dir needs a folder}")"; shift 2 ;;
    --cache) CACHE="$(realpath -m "${2:?--cache needs a folder}")"; shift 2 ;;
    --work) WORK="$(realpath -m "${2:?--work needs a folder}")"; shift 2 ;;
    --mirror) MIRROR="${2:?--mirror needs a URL}"; shift 2 ;;
    --sequence) SEQUENCE="$(realpath -m "${2:?--sequence needs a folder}")"; shift 2 ;;
    --watchdog-sec) WATCHDOG_SEC="${2:?--watchdog-sec needs seconds}"; shift 2 ;;
    --keep) KEEP=1; shift ;;
    -h|--help) usage; exit 0 ;;
    *) echo "test_package.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ -n "$WORK" ] || WORK="$CACHE/test-root"
ROOTFS="$WORK"
TARBALL="$CACHE/bookworm-minbase.tar"
UNIT_NAME=vehicle-perception.service
ARTIFACTS="$CACHE/test-package-logs"

log() { echo "test_package.sh: $*"; }
fail() { echo "test_package.sh: FAIL: $*" >&2; exit 1; }
[ "$(id -u)" -eq 0 ] || fail "must run as root (debootstrap, chroot, mount)"
[ -f "$SEQUENCE/sequence.yaml" ] || fail "--sequence $SEQUENCE: no sequence.yaml there"
for tool in debootstrap chroot mount python3 dpkg-deb; do
  command -v "$tool" >/dev/null || fail "'$tool' not found (apt-get install debootstrap python3)"
done
case "$ROOTFS" in "$REPO"/*) fail "--work must be outside the repository ($ROOTFS)" ;; esac

# --- 1. packages ------------------------------------------------------------------------------
shopt -s nullglob
debs=("$DEB_DIR"/vehicle-perception_*.deb "$DEB_DIR"/vehicle-perception-rsu_*.deb)
if [ ${#debs[@]} -eq 0 ]; then
  log "no packages in $DEB_DIR: building them (scripts/package.sh)"
  scripts/package.sh --out "$DEB_DIR"
  debs=("$DEB_DIR"/vehicle-perception_*.deb "$DEB_DIR"/vehicle-perception-rsu_*.deb)
fi
[ ${#debs[@]} -eq 2 ] || fail "expected the two packages in $DEB_DIR, found: ${debs[*]:-none}"
for d in "${debs[@]}"; do log "package $(basename "$d"): $(stat -c %s "$d") bytes"; done

# --- 2. fresh root ---------------------------------------------------------------------------
mkdir -p "$CACHE" "$ARTIFACTS"
if [ ! -f "$TARBALL" ]; then
  log "no cached root: debootstrap --variant=minbase bookworm (once; cached as $TARBALL)"
  rm -rf "$CACHE/bootstrap.tmp"
  debootstrap --variant=minbase bookworm "$CACHE/bootstrap.tmp" "$MIRROR"
  tar -C "$CACHE/bootstrap.tmp" -cf "$TARBALL.tmp" . && mv "$TARBALL.tmp" "$TARBALL"
  rm -rf "$CACHE/bootstrap.tmp"
fi

MOUNTS=()
cleanup() {
  local m
  for ((i = ${#MOUNTS[@]} - 1; i >= 0; i--)); do
    m="${MOUNTS[$i]}"
    umount -l "$m" 2>/dev/null || true
  done
  if [ "$KEEP" = 0 ] && [ -d "$ROOTFS" ]; then
    rm -rf --one-file-system "$ROOTFS"
  fi
}
trap cleanup EXIT

log "fresh root: unpacking $TARBALL into $ROOTFS"
if [ -d "$ROOTFS" ]; then
  while read -r m; do umount -l "$m" 2>/dev/null || true; done < <(awk -v r="$ROOTFS" '$2 ~ "^"r {print $2}' /proc/mounts | sort -r)
  rm -rf --one-file-system "$ROOTFS"
fi
mkdir -p "$ROOTFS"
tar -C "$ROOTFS" -xf "$TARBALL"
mount -t proc proc "$ROOTFS/proc"; MOUNTS+=("$ROOTFS/proc")
mount --bind /dev "$ROOTFS/dev"; MOUNTS+=("$ROOTFS/dev")
mount -t sysfs sysfs "$ROOTFS/sys"; MOUNTS+=("$ROOTFS/sys")
cp -L /etc/resolv.conf "$ROOTFS/etc/resolv.conf"
in_root() { chroot "$ROOTFS" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin \
  DEBIAN_FRONTEND=noninteractive LANG=C.UTF-8 "$@"; }

# File list of the root (files and symlinks; not /proc /dev /sys /tmp /run or apt's caches).
snapshot() {
  (cd "$ROOTFS" && find . -xdev \( -path ./proc -o -path ./dev -o -path ./sys -o -path ./tmp \
      -o -path ./run -o -path ./var/cache -o -path ./var/lib/apt/lists -o -path ./var/log \
      -o -path ./var/lib/dpkg \) -prune -o \( -type f -o -type l \) -printf '/%P\n' | LC_ALL=C sort)
}

# --- 3. install --------------------------------------------------------------------------------
mkdir -p "$ROOTFS/tmp/debs"
cp "${debs[@]}" "$ROOTFS/tmp/debs/"
in_root dpkg-query -W -f '${Package}\n' | LC_ALL=C sort > "$ARTIFACTS/packages.before"
snapshot > "$ARTIFACTS/files.before-install"
log "apt-get update + install of the two packages (dependencies from $MIRROR)"
in_root apt-get update -qq
in_debs=()
for d in "${debs[@]}"; do in_debs+=("/tmp/debs/$(basename "$d")"); done
in_root apt-get install -y --no-install-recommends "${in_debs[@]}" > "$ARTIFACTS/apt-install.log" 2>&1 \
  || { tail -30 "$ARTIFACTS/apt-install.log"; fail "apt-get install of the packages failed"; }
in_root dpkg-query -W -f '${Package}\t${Installed-Size}\n' | LC_ALL=C sort > "$ARTIFACTS/packages.after"
added="$(cut -f1 "$ARTIFACTS/packages.after" | LC_ALL=C comm -13 "$ARTIFACTS/packages.before" -)"
n_added=$(wc -w <<<"$added")
size_added=$(awk 'NR == FNR {want[$1] = 1; next} ($1 in want) {s += $2} END {print s + 0}' \
             <(tr ' ' '\n' <<<"$added") "$ARTIFACTS/packages.after")
log "apt installed $n_added packages, $((size_added / 1024)) MiB in all (list: $ARTIFACTS/packages.after)"
for p in vehicle-perception vehicle-perception-rsu; do
  st="$(in_root dpkg-query -W -f '${Status} ${Version} ${Installed-Size}' "$p")"
  log "  $p: $st KiB"
  [[ "$st" == "install ok installed"* ]] || fail "$p is not installed"
done
in_root dpkg -L vehicle-perception vehicle-perception-rsu | LC_ALL=C sort -u > "$ARTIFACTS/package-files"
# The same paths as the merged-/usr root shows them (/lib/systemd/... is /usr/lib/systemd/...).
sed -E 's#^/(lib|bin|sbin)/#/usr/\1/#' "$ARTIFACTS/package-files" | LC_ALL=C sort -u > "$ARTIFACTS/package-files.usr"

log "checking the installed files"
for f in /usr/bin/vp_firmware_app /usr/bin/vp_rsu_subscriber /etc/vp/vp.yaml \
         /etc/default/vehicle-perception /lib/systemd/system/$UNIT_NAME \
         /usr/share/man/man1/vp_firmware_app.1.gz /usr/share/man/man1/vp_rsu_subscriber.1.gz \
         /usr/share/doc/vehicle-perception/copyright /usr/share/doc/vehicle-perception/deployment.md; do
  [ -e "$ROOTFS$f" ] || fail "$f is not installed"
done
conffiles="$(in_root dpkg-query -W -f '${Conffiles}\n' vehicle-perception | awk 'NF {print $1}')"
log "  conffiles: $(echo $conffiles)"
grep -qx /etc/vp/vp.yaml <<<"$conffiles" || fail "/etc/vp/vp.yaml is not a conffile"
# Every absolute path the installed config names under /usr/share/vp must exist; no relative ones.
grep -v '^\s*#' "$ROOTFS/etc/vp/vp.yaml" | grep -oE ':\s+"?\.\.?/[^ "#]*' \
  && fail "/etc/vp/vp.yaml still has relative paths (above)"
for p in $(grep -v '^\s*#' "$ROOTFS/etc/vp/vp.yaml" | grep -oE '/usr/share/vp/[^ "#]*'); do
  [ -e "$ROOTFS$p" ] || fail "/etc/vp/vp.yaml names $p, which is not installed"
  log "  config -> $p (installed)"
done
for exe in vp_firmware_app vp_rsu_subscriber; do
  missing="$(in_root ldd /usr/bin/$exe | grep 'not found' || true)"
  [ -z "$missing" ] || fail "$exe: libraries not found: $missing"
  in_root /usr/bin/$exe --help > "$ARTIFACTS/$exe.help" || fail "$exe --help failed"
  log "  $exe: all libraries resolve, --help prints $(wc -l < "$ARTIFACTS/$exe.help") lines"
done

UNIT="$ROOTFS/lib/systemd/system/$UNIT_NAME"
if command -v systemd-analyze >/dev/null; then
  log "systemd-analyze verify (this machine's systemd $(systemd-analyze --version | head -1 | awk '{print $2}'))"
  # verify needs ExecStart's binary at its path: check a copy with the root's binary path.
  mkdir -p "$ARTIFACTS/unit"
  sed "s#ExecStart=/usr/bin/#ExecStart=$ROOTFS/usr/bin/#" "$UNIT" > "$ARTIFACTS/unit/$UNIT_NAME"
  if systemd-analyze verify --man=no "$ARTIFACTS/unit/$UNIT_NAME" > "$ARTIFACTS/verify.log" 2>&1; then
    log "  verify: no problems"
  else
    cat "$ARTIFACTS/verify.log"
    fail "systemd-analyze verify reported problems"
  fi
  if systemd-analyze security --offline=yes "$ARTIFACTS/unit/$UNIT_NAME" > "$ARTIFACTS/security.log" 2>&1; then
    log "  security (offline): $(grep -i 'overall exposure' "$ARTIFACTS/security.log" | sed 's/^[^A-Za-z]*//')"
  else
    log "  security (offline) not available here: $(tail -1 "$ARTIFACTS/security.log")"
  fi
else
  log "systemd-analyze not installed: unit not verified (apt-get install systemd)"
fi

# --- 4. the service, as systemd would start it -------------------------------------------------
execstart="$(sed -n 's/^ExecStart=//p' "$UNIT")"
envfile="$(sed -n 's/^EnvironmentFile=-\{0,1\}//p' "$UNIT")"
wd_sec="${WATCHDOG_SEC:-$(sed -n 's/^WatchdogSec=\([0-9.]*\)s\{0,1\}$/\1/p' "$UNIT")}"
[ -n "$execstart" ] && [ -n "$wd_sec" ] || fail "no ExecStart= or WatchdogSec= in $UNIT"
wd_usec=$(python3 -c "print(int(float('$wd_sec') * 1000000))")

# The sequence goes into the service's state folder; DynamicUser stand-in: nobody (65534).
state=/var/lib/vp
mkdir -p "$ROOTFS$state/sequences" "$ROOTFS/var/log/vp" "$ROOTFS/run/vp-test"
cp -a "$SEQUENCE" "$ROOTFS$state/sequences/test"
dtm_rel="$(sed -n 's/^\s*dtm_path:\s*\([^ #]*\).*/\1/p' "$SEQUENCE/rig.yaml")"
if [ -n "$dtm_rel" ] && [ "${dtm_rel#/}" = "$dtm_rel" ] && [ ! -e "$ROOTFS$state/sequences/test/$dtm_rel" ]; then
  src="$(realpath -m "$SEQUENCE/$dtm_rel")"
  dst="$(realpath -m "$ROOTFS$state/sequences/test/$dtm_rel")"
  [ -f "$src" ] || fail "the sequence's DTM $src does not exist"
  mkdir -p "$(dirname "$dst")" && cp "$src" "$dst"
fi
chown -R 65534:65534 "$ROOTFS$state" "$ROOTFS/var/log/vp"
chmod 0755 "$ROOTFS/run/vp-test"

# Environment: the EnvironmentFile (KEY=value lines, as systemd reads them), then the test's
# VP_ARGS (as a drop-in's second EnvironmentFile would).
declare -A env=()
if [ -n "$envfile" ] && [ -f "$ROOTFS$envfile" ]; then
  while IFS= read -r line; do
    [[ "$line" =~ ^[[:space:]]*(#|$) ]] && continue
    [[ "$line" =~ ^([A-Za-z_][A-Za-z0-9_]*)=(.*)$ ]] || fail "$envfile: bad line '$line'"
    env[${BASH_REMATCH[1]}]="${BASH_REMATCH[2]}"
  done < "$ROOTFS$envfile"
fi
env[VP_ARGS]="--sequence $state/sequences/test --loop --no-dds"
# ExecStart: $VAR expands to its words, ${VAR} to one word (systemd.service(5)).
argv=()
read -ra words <<<"$execstart"
for w in "${words[@]}"; do
  if [[ "$w" =~ ^\$([A-Za-z_][A-Za-z0-9_]*)$ ]]; then
    read -ra split <<<"${env[${BASH_REMATCH[1]}]:-}"
    argv+=(${split[@]+"${split[@]}"})
  elif [[ "$w" =~ ^\$\{([A-Za-z_][A-Za-z0-9_]*)\}$ ]]; then
    argv+=("${env[${BASH_REMATCH[1]}]:-}")
  else
    argv+=("$w")
  fi
done
envargs=()
for k in "${!env[@]}"; do envargs+=("$k=${env[$k]}"); done
log "service: ${argv[*]}"
log "  as uid 65534, NOTIFY_SOCKET=/run/vp-test/notify WATCHDOG_USEC=$wd_usec STATE_DIRECTORY=$state"
set +e
python3 "$REPO/packaging/tests/sd_notify_harness.py" --socket "$ROOTFS/run/vp-test/notify" \
  --watchdog-usec "$wd_usec" --watchdogs 2 --log "$ARTIFACTS/service.log" -- \
  chroot --userspec=65534:65534 "$ROOTFS" /usr/bin/env -i PATH=/usr/bin:/bin HOME=/ LANG=C.UTF-8 \
    NOTIFY_SOCKET=/run/vp-test/notify WATCHDOG_USEC="$wd_usec" STATE_DIRECTORY="$state" \
    LOGS_DIRECTORY=/var/log/vp INVOCATION_ID=test-package "${envargs[@]}" \
    /bin/sh -c 'cd / && WATCHDOG_PID=$$ && export WATCHDOG_PID && exec "$@"' sh "${argv[@]}"
harness_rc=$?
set -e
log "service output (last lines of $ARTIFACTS/service.log):"
tail -n 8 "$ARTIFACTS/service.log" | sed 's/^/    /'
[ $harness_rc -eq 0 ] || fail "the service run failed the notify/watchdog/stop checks (above)"

# --- 5. remove, purge ---------------------------------------------------------------------------
snapshot > "$ARTIFACTS/files.installed"
log "dpkg -r vehicle-perception vehicle-perception-rsu"
in_root dpkg -r vehicle-perception vehicle-perception-rsu > "$ARTIFACTS/dpkg-r.log" 2>&1 \
  || { cat "$ARTIFACTS/dpkg-r.log"; fail "dpkg -r failed"; }
left=""
while IFS= read -r f; do
  if [ -e "$ROOTFS$f" ] && [ ! -d "$ROOTFS$f" ] && ! grep -qx "$f" <<<"$conffiles"; then
    left+=" $f"
  fi
done < "$ARTIFACTS/package-files"
[ -z "$left" ] || fail "dpkg -r left files that are not conffiles:$left"
for c in $conffiles; do [ -e "$ROOTFS$c" ] || fail "dpkg -r removed conffile $c"; done
st="$(in_root dpkg-query -W -f '${db:Status-Abbrev}' vehicle-perception)"
log "  removed: only the conffiles remain (dpkg status '${st% }')"

log "dpkg -P vehicle-perception vehicle-perception-rsu"
in_root dpkg -P vehicle-perception vehicle-perception-rsu > "$ARTIFACTS/dpkg-P.log" 2>&1 \
  || { cat "$ARTIFACTS/dpkg-P.log"; fail "dpkg -P failed"; }
for c in $conffiles /etc/vp "$state"; do
  [ ! -e "$ROOTFS$c" ] || fail "dpkg -P left $c"
done
snapshot > "$ARTIFACTS/files.purged"
new_files="$(LC_ALL=C comm -13 "$ARTIFACTS/files.installed" "$ARTIFACTS/files.purged")"
[ -z "$new_files" ] || fail "remove/purge created files: $new_files"
# Everything gone must have been ours: package files, the service's state, and the
# deb-systemd-helper state that postinst recorded (and purge forgets).
gone="$(LC_ALL=C comm -23 "$ARTIFACTS/files.installed" "$ARTIFACTS/files.purged" \
        | grep -vxFf "$ARTIFACTS/package-files.usr" | grep -v "^$state/" \
        | grep -vE "^/var/lib/systemd/deb-systemd-helper-[a-z]+/$UNIT_NAME" || true)"
[ -z "$gone" ] || fail "remove/purge deleted files that were not the packages': $gone"
# Against the root before installation only the dependencies' files may differ.
ours_left="$(LC_ALL=C comm -12 "$ARTIFACTS/files.purged" "$ARTIFACTS/package-files.usr" \
             | grep -vxFf "$ARTIFACTS/files.before-install" || true)"
[ -z "$ours_left" ] || fail "files of the packages survived the purge: $ours_left"
log "  purged: no file of the packages, no conffile, no state left; dependencies stay installed"

log "PASS (logs in $ARTIFACTS)"
