# Sourced by the evaluation scripts (not run): the build folder to take binaries from when the
# caller gives none.
#   vp_find_build BINARY   prints the first of ROOT/build/release and ROOT/build/ci that holds
#                          the executable BINARY (a path inside the build folder), or nothing
vp_find_build() {
  local root b
  root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
  for b in release ci; do
    if [[ -x "$root/build/$b/$1" ]]; then
      echo "$root/build/$b"
      return 0
    fi
  done
}
