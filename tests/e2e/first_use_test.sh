#!/usr/bin/env bash
# First-use traps (issue 20), each checked on the real programs and scripts:
#   --version on every program and script; script --help prints only its comment block; mcmt-launch's camera
#   list on one line; mcmt-mapper refuses another session's --out without --force and records its version
#   in map.yaml and report.json; mcmt-replay shows progress (plain lines in a pipe, a bar on a terminal);
#   mcmt-spy without a display says so in one line. Replay on udpm port 7778 (logger range;
#   tests/e2e/udpm_port.sh).
#   first_use_test.sh SOURCE_DIR BUILD_DIR
set -uo pipefail
SRC="$1"
BUILD="$2"
BIN="$BUILD/bin"
export MCMT_BIN="$BIN"  # mcmt-replay's mcmt-progress: this build's, not ../build's
WORK="$BUILD/tests/e2e_first_use"
rm -rf "$WORK" && mkdir -p "$WORK"
FAILS=0
fail() { echo "first_use_test: FAIL: $*"; FAILS=$((FAILS + 1)); }
ok() { echo "ok   $*"; }
VERSION=$(sed -n 's/^project(mcmt VERSION \([0-9.]*\).*/\1/p' "$SRC/CMakeLists.txt")

# --version everywhere.
for p in "$BIN"/mcmt-*; do
  name=$(basename "$p")
  out=$("$p" --version 2>&1) || { fail "$name --version exits non-zero: $out"; continue; }
  [[ "$out" == "$name $VERSION"* && $(wc -l <<<"$out") == 1 ]] || fail "$name --version printed '$out'"
done
for s in mcmt-launch mcmt-replay mcmt-spy caliscope-to-mcmt; do
  out=$("$SRC/scripts/$s" --version 2>&1) || fail "$s --version exits non-zero"
  [[ "$out" == "$s $VERSION"* ]] || fail "scripts/$s --version printed '$out'"
  help=$("$SRC/scripts/$s" --help 2>&1) || fail "$s --help exits non-zero"
  if grep -qE '^(set -|prog=|PROG=|ROOT=|HERE=|source )' <<<"$help"; then fail "$s --help prints script source"; fi
done
ok "--version and --help"

# mcmt-launch: the camera list on one line (detectors replaced by a stub that ends at once).
mkdir -p "$WORK/stubbin"
printf '#!/bin/sh\nexit 0\n' >"$WORK/stubbin/mcmt-detector" && chmod +x "$WORK/stubbin/mcmt-detector"
"$BIN/mcmt-sim" --out "$WORK/sim" --detections-only --frames 100 --cameras 3 --quiet >/dev/null ||
  fail "mcmt-sim --detections-only"
launch=$(MCMT_BIN="$WORK/stubbin" "$SRC/scripts/mcmt-launch" "$WORK/sim/rig.yaml" detect 2>&1)
grep -q "^mcmt-launch: detect: 3 processes (cameras: cam0 cam1 cam2)$" <<<"$launch" ||
  fail "mcmt-launch camera list: $launch"
ok "mcmt-launch camera list"

# mcmt-mapper: another session's --out is refused unless --force; the version is recorded.
M="$BIN/mcmt-mapper"
"$M" --config "$WORK/sim/rig.yaml" --log "$WORK/sim/detections.lcmlog" --out "$WORK/calib/" >"$WORK/map1.txt" 2>&1 ||
  fail "first mapping"
grep -q "wrote $WORK/calib/map.yaml," "$WORK/map1.txt" || fail "path joining: $(grep wrote "$WORK/map1.txt")"
grep -q "^written_by: \"mcmt $VERSION" "$WORK/calib/map.yaml" || fail "map.yaml has no written_by"
grep -q "\"mcmt_version\": \"$VERSION" "$WORK/calib/report.json" || fail "report.json has no mcmt_version"
"$M" --config "$WORK/sim/rig.yaml" --log "$WORK/sim/detections.lcmlog" --out "$WORK/calib" >/dev/null 2>&1 ||
  fail "re-mapping the same log into its own folder is refused"
cp "$WORK/sim/detections.lcmlog" "$WORK/other.lcmlog"
before=$(md5sum <"$WORK/calib/map.yaml")
if err=$("$M" --config "$WORK/sim/rig.yaml" --log "$WORK/other.lcmlog" --out "$WORK/calib" 2>&1); then
  fail "another session's --out was overwritten"
fi
[[ $(wc -l <<<"$err") == 1 && "$err" == *"holds the results of another session"*"--force"* ]] ||
  fail "refusal message: $err"
[[ $(md5sum <"$WORK/calib/map.yaml") == "$before" ]] || fail "the refused run changed map.yaml"
"$M" --config "$WORK/sim/rig.yaml" --log "$WORK/other.lcmlog" --out "$WORK/calib" --force >/dev/null 2>&1 ||
  fail "--force does not overwrite"
ok "mcmt-mapper --out / --force / versions"

# mcmt-replay: progress, plain in a pipe, a bar with ETA on a terminal (script gives it a pty).
source "$SRC/tests/e2e/udpm_port.sh"
udpm_port 7778 || exit 1
URL="udpm://239.255.76.67:$PORT?ttl=0"
"$SRC/scripts/mcmt-replay" "$WORK/sim/detections.lcmlog" --lcm-url "$URL" 2>"$WORK/replay.txt" || fail "mcmt-replay"
grep -q "^mcmt-replay detections.lcmlog: 100 % .* kB, .* kB/s, done in 0:0" "$WORK/replay.txt" ||
  fail "mcmt-replay plain progress: $(cat "$WORK/replay.txt")"
if ! grep -q $'\r' "$WORK/replay.txt"; then :; else fail "escape codes in a pipe"; fi
if command -v script >/dev/null; then
  script -qec "'$SRC/scripts/mcmt-replay' '$WORK/sim/detections.lcmlog' --lcm-url '$URL'" /dev/null >"$WORK/replay_tty.txt" 2>&1
  grep -q $'\r\e\\[Kmcmt-replay detections.lcmlog \\[#*\\.*\\] .* kB/s  ETA' "$WORK/replay_tty.txt" ||
    fail "mcmt-replay terminal progress: $(cat -A "$WORK/replay_tty.txt" | head -c 600)"
fi
ok "mcmt-replay progress"

# mcmt-spy without a display: one line, exit 1.
if [[ -f "$BUILD/lcmtypes/mcmt_lcmtypes.jar" ]] && command -v java >/dev/null; then
  spy=$(env -u DISPLAY -u WAYLAND_DISPLAY MCMT_BUILD_DIR="$BUILD" "$SRC/scripts/mcmt-spy" 2>&1)
  rc=$?
  [[ $rc == 1 && $(wc -l <<<"$spy") == 1 && "$spy" == "mcmt-spy: error: no display"* ]] || fail "mcmt-spy: rc $rc: $spy"
  ok "mcmt-spy without a display"
fi

((FAILS == 0)) || { echo "first_use_test: $FAILS failures"; exit 1; }
echo "first_use_test: PASS"
