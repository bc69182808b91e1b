#!/usr/bin/env python3
"""Perturbation probe: count markers whose corners moved between two corner dumps.

Usage: 2026-12-07-fullsettle-cmp.py A B. Lines: [frame] id x0 y0 .. x3 y3 (test_detector_realdata's
MCMT_PROBE_DUMP has the frame, bench_accuracy's MCMT_CORNER_DUMP not). Markers are matched by (frame, id)
and the nearest corners (within 3 px); prints matched, unmatched, moved > 1e-6 px, > 0.01 px, and the largest move."""
import sys
from collections import defaultdict


def load(path):
    out = defaultdict(list)
    for line in open(path):
        v = line.split()
        if len(v) == 9:
            key, c = (0, int(v[0])), v[1:]
        else:
            key, c = (int(v[0]), int(v[1])), v[2:]
        out[key].append([float(x) for x in c])
    return out


a, b = load(sys.argv[1]), load(sys.argv[2])
moves, unmatched = [], 0
for key, la in a.items():
    lb = list(b.get(key, []))
    for ca in la:
        best = None
        for i, cb in enumerate(lb):
            d = max(((ca[2 * k] - cb[2 * k]) ** 2 + (ca[2 * k + 1] - cb[2 * k + 1]) ** 2) ** 0.5 for k in range(4))
            if best is None or d < best[0]:
                best = (d, i)
        if best is None or best[0] > 3.0:
            unmatched += 1
            continue
        moves.append(best[0])
        lb.pop(best[1])
    unmatched += len(lb)
n6 = sum(m > 1e-6 for m in moves)
n2 = sum(m > 1e-2 for m in moves)
print(f"matched {len(moves)} unmatched {unmatched} moved>1e-6 {n6} moved>0.01 {n2} max {max(moves + [0]):.3g} px")
