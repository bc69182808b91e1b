# Sourced by the mcmt shell scripts (not run): their --help and --version.
#   mcmt_usage FILE     prints FILE's leading comment block (after the #! line), without the "# "
#   mcmt_version NAME   prints "NAME VERSION": the project version of CMakeLists.txt plus git describe of the
#                       checkout when there is one, as the programs' --version does
mcmt_usage() { awk 'NR == 1 { next } /^#/ { sub(/^# ?/, ""); print; next } { exit }' "$1"; }
mcmt_version() {
  local root v g
  root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
  v=$(sed -n 's/^project(mcmt VERSION \([0-9.]*\).*/\1/p' "$root/CMakeLists.txt")
  g=$(git -C "$root" describe --always --tags --dirty 2>/dev/null || true)
  echo "$1 ${v:-unknown}${g:+ (git $g)}"
}
