#!/bin/bash
# The one-side fit (diag_side_exact, line at the truth, one cold fit) on diag_side_bias's print at 9 px
# markers (1.125 px cells), sharp, pixel area (BOX=4), averaged over ids 0-15 x sides 0-3 at one pixel phase
# (OFFX, OFFY), then over 16 fixed quasi-random phases, per roll. smallcell's -0.014 px was the phase
# (0.3, 0.7) alone. EXE: a diag_side_exact built at 55fcdd5 (its ALONG default is the optical blur, so the
# pixel's spread is given: sqrt(0.01^2 + 1/6 + (1 - 1/16)/12) = 0.495 px).
# usage: bash 2026-12-07-sharpstep-phases.sh [ROLLS...]   (default 13 37 58 77)
EXE=${EXE:-build/bench/diag_side_exact}
one_phase() {  # ROLL OFFX OFFY -> the mean e over the 64 sides
  for id in $(seq 0 15); do for side in 0 1 2 3; do
    PIX=1 BOX=4 ALONG=0.495 ROLL=$1 OFFX=$2 OFFY=$3 "$EXE" "$id" "$side" 0.01 9 | grep -o "e [-+][0-9.]*" |
      head -1 | cut -d' ' -f2
  done; done | awk '{s += $1; n++} END {printf "%+.4f\n", s / n}'
}
for roll in ${@:-13 37 58 77}; do
  python3 -c "
import random
random.seed(7)
for i in range(16): print('%.3f %.3f' % (random.random(), random.random()))" | while read -r ox oy; do
    one_phase "$roll" "$ox" "$oy"
  done | awk -v r="$roll" '{s += $1; ss += $1 * $1; n++; v = v " " $1}
    END {m = s / n; printf "roll %s: phase mean %+.4f (se over phases %.4f; phases:%s)\n", r, m, sqrt((ss / n - m * m) / (n - 1)), v}'
done
