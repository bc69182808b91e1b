#!/usr/bin/env bash
# Across hosts: the detectors run in one network namespace ("camera host"), the mapper, tracker and a
# logger in another ("compute host"), joined by a veth pair with a multicast route on each side. Nothing
# but LCM's UDP multicast crosses between them. The mapper (live) solves after N frames and publishes
# MCMT_MAP; the tracker, started with no map, picks it up from LCM; the detectors then run again and the
# tracker's poses are recorded on the compute host and checked.
# Exit 77 (ctest: skipped) where namespaces cannot be made (not root, no iproute2, no netns support).
#   netns_test.sh BIN_DIR WORK_DIR
set -uo pipefail
BIN="$1"
WORK="$2"
SKIP=77
ID="$$"
NA="mcmt_cam_$ID"
NB="mcmt_cpu_$ID"
VA="vmc$ID"
VB="vmp$ID"
source "$(dirname "$0")/udpm_port.sh"
udpm_port 7830 || exit 1
URL="udpm://239.255.76.67:$PORT?ttl=1"

fail() { echo "netns_test: FAIL: $*" >&2; exit 1; }
cleanup() {
  ip netns pids "$NA" 2>/dev/null | xargs -r kill -9 2>/dev/null
  ip netns pids "$NB" 2>/dev/null | xargs -r kill -9 2>/dev/null
  ip netns del "$NA" 2>/dev/null
  ip netns del "$NB" 2>/dev/null
}
trap cleanup EXIT

if [[ $(id -u) -ne 0 ]] || ! command -v ip >/dev/null; then
  echo "netns_test: SKIPPED: needs root and iproute2 to create network namespaces" >&2; exit $SKIP
fi
if ! ip netns add "$NA" 2>/dev/null || ! ip netns add "$NB" 2>/dev/null; then
  echo "netns_test: SKIPPED: cannot create network namespaces here (ip netns add failed)" >&2; exit $SKIP
fi
ip link add "$VA" type veth peer name "$VB" || { echo "netns_test: SKIPPED: cannot create a veth pair" >&2; exit $SKIP; }
ip link set "$VA" netns "$NA" && ip link set "$VB" netns "$NB" || fail "moving veth ends into namespaces"
ip -n "$NA" addr add 10.231.0.1/24 dev "$VA" && ip -n "$NB" addr add 10.231.0.2/24 dev "$VB" || fail "addresses"
for ns in "$NA" "$NB"; do ip -n "$ns" link set lo up; done
ip -n "$NA" link set "$VA" up && ip -n "$NB" link set "$VB" up || fail "link up"
ip -n "$NA" route add 224.0.0.0/4 dev "$VA" && ip -n "$NB" route add 224.0.0.0/4 dev "$VB" || fail "multicast routes"

rm -rf "$WORK" && mkdir -p "$WORK"
FRAMES=40
"$BIN/mcmt-sim" --out "$WORK/sim" --cameras 3 --frames $FRAMES --seed 3 >/dev/null || fail "mcmt-sim"
RIG="$WORK/sim/rig.yaml"
CAMS="cam0 cam1 cam2"

# Compute host: logger (poses and map), mapper (live, solves after all frames), tracker (waits for MCMT_MAP).
ip netns exec "$NB" "$BIN/mcmt-logger" --out "$WORK/compute.lcmlog" --lcm-url "$URL" --channels 'MCMT_(POSE|MAP)' \
  >"$WORK/logger.out" 2>&1 &
LOGGER=$!
ip netns exec "$NB" "$BIN/mcmt-mapper" --config "$RIG" --out "$WORK/map" --lcm-url "$URL" --frames $FRAMES --publish \
  >"$WORK/mapper.out" 2>&1 &
MAPPER=$!
ip netns exec "$NB" "$BIN/mcmt-tracker" --config "$RIG" --lcm-url "$URL" --out "$WORK/poses.csv" \
  >"$WORK/tracker.out" 2>&1 &
TRACKER=$!
sleep 1

# Each pass stamps its frames with the wall clock at which they are published, as live cameras do (the
# tracker drops views older than the frames it has already published, so a second pass of the same video
# with the same stamps would be late).
run_detectors() {
  local pids=()
  local start=$(( $(date +%s%N) / 1000 + 1000000 ))
  for cam in $CAMS; do
    ip netns exec "$NA" "$BIN/mcmt-detector" --config "$RIG" --camera "$cam" --lcm-url "$URL" --rate realtime \
      --start-utime "$start" --start-wall-utime "$start" \
      >>"$WORK/detector_$cam.out" 2>&1 &
    pids+=("$!")
  done
  for p in "${pids[@]}"; do wait "$p" || fail "a detector failed: $(tail -n 3 "$WORK"/detector_*.out)"; done
}

# Camera host, first pass: the mapper collects and solves.
run_detectors
for _ in $(seq 1 120); do kill -0 $MAPPER 2>/dev/null || break; sleep 0.5; done
if kill -0 $MAPPER 2>/dev/null; then fail "mapper did not finish: $(tail -n 5 "$WORK/mapper.out")"; fi
wait $MAPPER || fail "mapper failed: $(tail -n 5 "$WORK/mapper.out")"
[[ -s "$WORK/map/map.yaml" ]] || fail "no map.yaml on the compute host"
sleep 2  # the tracker receives MCMT_MAP
# Second pass: the tracker tracks.
run_detectors
sleep 1
kill -INT $TRACKER; wait $TRACKER || fail "tracker failed: $(tail -n 5 "$WORK/tracker.out")"
kill -INT $LOGGER; wait $LOGGER || fail "logger failed: $(tail -n 5 "$WORK/logger.out")"

rows=$(($(wc -l <"$WORK/poses.csv") - 1))
echo "netns_test: map from the other host, $rows poses tracked of $FRAMES frames"
((rows >= FRAMES * 9 / 10)) || fail "only $rows poses for $FRAMES frames (tracker: $(tail -n 3 "$WORK/tracker.out"))"
"$BIN/mcmt-export" --log "$WORK/compute.lcmlog" --summary >"$WORK/summary.txt" 2>&1 || fail "mcmt-export --summary"
grep -q "MCMT_POSE" "$WORK/summary.txt" || fail "no MCMT_POSE recorded on the compute host"
grep -q "MCMT_MAP" "$WORK/summary.txt" || fail "no MCMT_MAP recorded on the compute host"
echo "netns_test: PASS"
