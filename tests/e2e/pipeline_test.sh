#!/usr/bin/env bash
# The demo's pipeline on a shorter rendered session, every process real (detectors and logger over udpm on
# loopback, mapper from the log, tracker fed by lcm-logplayer, eval, viewer), on its own multicast port.
# Detectors paced in real time from a shared start, as synchronised cameras. Asserts the accuracy against ground truth is at least as good as the paper's figures at 0.9 m (the
# demo's rig is at 1.0 m), that nearly every frame has a pose, and that every output exists.
#   pipeline_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
SRC="$1"
BUILD="$2"
OUT="$BUILD/tests/e2e_pipeline"
# 10 fps: CPU time to spare beside the test ctest runs in parallel. (The failures once seen here, 4 of 5
# cameras' views all dropped as late, were detectors ready after --start-wall-utime pacing from their own
# late start: fixed in detector/node.cc.)
source "$SRC/tests/e2e/udpm_port.sh"
udpm_port 7832 || exit 1
export MCMT_BUILD_DIR="$BUILD" MCMT_DEMO_OUT="$OUT" MCMT_DEMO_FRAMES=120 MCMT_DEMO_PORT=$PORT MCMT_DEMO_RATE=realtime
export MCMT_DEMO_FPS=10
"$SRC/scripts/run-pipeline" >"$BUILD/tests/e2e_pipeline.log" 2>&1 || {
  tail -n 40 "$BUILD/tests/e2e_pipeline.log"; echo "pipeline_test: FAIL: run-pipeline failed"; exit 1; }
for f in session.lcmlog map/map.yaml map/trajectory.csv map/report.json poses.csv eval.txt eval.json rig.png; do
  [[ -s "$OUT/$f" ]] || { echo "pipeline_test: FAIL: $OUT/$f missing or empty"; exit 1; }
done
cat "$OUT/eval.txt"
python3 - "$OUT/eval.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
checks = [
    ("object rotation error (deg, mean)", r["object"]["rotation_deg"]["mean"], 1.05),
    ("object translation error (mm, mean)", r["object"]["translation_mm"]["mean"], 0.85),
    ("camera position error (mm, mean)", r["cameras"]["position_mm"]["mean"], 2.38),
    ("object configuration error (mm, mean)", r["markers"]["configuration_mm"]["mean"], 0.30),
]
ok = True
for name, value, bound in checks:
    good = value <= bound
    ok &= good
    print(f"{'ok  ' if good else 'FAIL'} {name}: {value:.3f} (paper at 0.9 m: {bound})")
frac = r["object"]["fraction_with_pose"]
print(f"{'ok  ' if frac >= 0.95 else 'FAIL'} fraction of frames with a pose: {frac:.3f} (>= 0.95)")
ok &= frac >= 0.95
if r["cameras"]["missing"]:
    print("FAIL cameras not mapped:", r["cameras"]["missing"]); ok = False
sys.exit(0 if ok else 1)
PY
echo "pipeline_test: PASS"
