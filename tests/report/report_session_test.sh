#!/usr/bin/env bash
# Maps a session with the real programs and checks mcmt-report's page in headless Chromium
# (report_page_test.sh). Detectors write LCM logs through LCM's file provider: no network.
#   report_session_test.sh demo|caliscope BIN_DIR SOURCE_DIR WORK_DIR
#     demo:      mcmt-sim renders 3 cameras x 40 frames (the demo's object) -> mcmt-detector per camera
#     caliscope: the real caliscope charuco recording (../shared/data/caliscope; skipped when absent)
#   then mcmt-mapper -> mcmt-report -> Chromium.  Exit 77: skipped.
set -euo pipefail
MODE="$1"; BIN="$2"; SRC="$3"; WORK="$4"
rm -rf "$WORK"; mkdir -p "$WORK"
if [[ $MODE == demo ]]; then
  "$BIN/mcmt-sim" --out "$WORK/sim" --cameras 3 --frames 40 --seed 7 --quiet
  RIG="$WORK/sim/rig.yaml"
else
  [[ -d "$SRC/../shared/data/caliscope/charuco_calibration" ]] || {
    echo "report_session_test: SKIP: ../shared/data/caliscope absent"; exit 77; }
  RIG="$SRC/configs/caliscope_charuco.yaml"
fi
for cam in $(sed -n 's/^ *- *name: *\([^ ]*\).*/\1/p' "$RIG"); do
  "$BIN/mcmt-detector" --config "$RIG" --camera "$cam" --quiet --lcm-url "file://$WORK/$cam.lcmlog?mode=w"
done
cat "$WORK"/cam*.lcmlog > "$WORK/session.lcmlog"
"$BIN/mcmt-mapper" --config "$RIG" --log "$WORK/session.lcmlog" --out "$WORK/map" > "$WORK/mapper.txt" 2>&1 || {
  tail -5 "$WORK/mapper.txt"; echo "report_session_test: FAIL: mcmt-mapper"; exit 1; }
# The verdicts are the mapper's last lines, one per camera, and the same as report.json's.
python3 - "$WORK/mapper.txt" "$WORK/map/report.json" <<'PY'
import json, re, sys
lines = [re.match(r"^camera (\S+): (good|fair|poor) \(", l) for l in open(sys.argv[1]).read().splitlines()]
cams = json.load(open(sys.argv[2]))["diagnostics"]["cameras"]
printed = {m.group(1): m.group(2) for m in lines if m}
want = {c["name"]: c["verdict"] for c in cams}
print("verdicts:", want)
if printed != want or not want:
    print("report_session_test: FAIL: mapper lines", printed, "!= report.json", want); sys.exit(1)
PY
exec "$(dirname "$0")/report_page_test.sh" "$BIN" "$WORK/map" "$WORK/page"
