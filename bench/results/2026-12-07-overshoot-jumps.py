#!/usr/bin/env python3
"""Classifies the jumps of one side's pass function (MCMT_X_PASSMAP, overshoot; per point
d_in:d_out:crossing end 0:crossing end 1:choice:rays:margin width): a step between grid neighbours that
differs from the median neighbour slope's by > 0.01 px, by what else changed across it: the crossing line
(> 0.05 px at an end), the surround choice or cut, the number of rays, the margin width (> 0.5 px), none.
Usage: 2026-12-07-overshoot-jumps.py FILE"""
import collections
import statistics as st
import sys

for mode_want in sys.argv[2:] or ['-']:
    kinds = collections.Counter()
    rows = jumps_total = 0
    sizes = []
    for line in open(sys.argv[1]):
        parts = line.rstrip('\n').split(' | ')
        for part in parts[1:]:
            toks = part.split()
            if toks[0] != mode_want: continue
            pts = [t.split(':') for t in toks[1:]]
            pts = [(float(p[0]), float(p[1]), float(p[2]), float(p[3]), p[4], int(p[5]), float(p[6])) for p in pts]
            pts = [p for p in pts if p[1] == p[1]]
            if len(pts) < 4: continue
            rows += 1
            ns = [(b[1] - a[1]) / (b[0] - a[0]) for a, b in zip(pts, pts[1:])]
            med = st.median(ns)
            for a, b in zip(pts, pts[1:]):
                dev = (b[1] - a[1]) - med * (b[0] - a[0])
                if abs(dev) <= 0.01: continue
                jumps_total += 1
                sizes.append(abs(dev))
                k = []
                if a[2] == a[2] and b[2] == b[2] and max(abs(b[2] - a[2]), abs(b[3] - a[3])) > 0.05: k.append('crossing')
                if a[2] != a[2] or b[2] != b[2]: k.append('no-crossing')
                if a[4] != b[4]: k.append('choice')
                if a[5] != b[5]: k.append('rays')
                if abs(a[6] - b[6]) > 0.5: k.append('margin')
                kinds['+'.join(k) or 'none'] += 1
    print(f"mode {mode_want}: sides {rows}, jumps {jumps_total}, size median {st.median(sizes):.3f} px")
    for k, v in kinds.most_common(12): print(f"  {k}: {v} ({v/jumps_total:.0%})")
