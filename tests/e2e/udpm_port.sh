# Sourced by the shell tests: udpm_port BASE sets PORT to the first of BASE, BASE + 400, ... (up to 31999)
# whose lock file this shell can lock, and keeps it locked on file descriptor 9 until the shell exits (the
# programs it starts inherit it): the shell form of tests/support/udpm.h, with the same lock files, so two
# runs of the suite on one machine never share a port. One port per script.
udpm_port() {
  local base="$1" slot
  for ((slot = 0; slot < 61; slot++)); do
    PORT=$((base + slot * 400))
    exec 9>>"${TMPDIR:-/tmp}/mcmt_udpm_$PORT.lock" || continue
    if flock -n 9; then return 0; fi
    exec 9>&-
  done
  echo "udpm port $base: every slot up to $((base + 60 * 400)) is held by another test run" >&2
  return 1
}
