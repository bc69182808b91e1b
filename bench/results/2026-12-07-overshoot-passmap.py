#!/usr/bin/env python3
"""Summarises MCMT_X_PASSMAP's file (overshoot): per freeze mode the slope dd_out/dd_in of one side's pass
function (least squares over the grid, and over |d_in| <= 0.1 px), and its jumps (a step between grid
neighbours that differs from the slope's by > 0.01 px), and the crossing line's jumps (> 0.05 px at an end).
Usage: 2026-12-07-overshoot-passmap.py FILE"""
import statistics as st
import sys

rows = [l.rstrip('\n').split(' | ') for l in open(sys.argv[1])]
modes = {}
for r in rows:
    head = r[0].split()
    for part in r[1:]:
        toks = part.split()
        mode, pts = toks[0], []
        for t in toks[1:]:
            v = [float(x) for x in t.split(':')]
            pts.append(v)
        modes.setdefault(mode, []).append((head, pts))


def ls(p):
    p = [q for q in p if q[1] == q[1]]
    if len(p) < 3: return float('nan')
    mx = sum(q[0] for q in p) / len(p); my = sum(q[1] for q in p) / len(p)
    sxx = sum((q[0] - mx) ** 2 for q in p)
    return sum((q[0] - mx) * (q[1] - my) for q in p) / sxx


for mode, items in modes.items():
    slopes, inner, jumpy, xjumpy, robust = [], [], 0, 0, []
    for head, pts in items:
        s = ls(pts); si = ls([q for q in pts if abs(q[0]) <= 0.1001])
        if s != s: continue
        slopes.append(s)
        if si == si: inner.append(si)
        # robust: the median of neighbour slopes
        ns = [(b[1] - a[1]) / (b[0] - a[0]) for a, b in zip(pts, pts[1:]) if a[1] == a[1] and b[1] == b[1]]
        med = st.median(ns) if ns else float('nan')
        robust.append(med)
        if any(abs((b[1] - a[1]) - med * (b[0] - a[0])) > 0.01 for a, b in zip(pts, pts[1:])): jumpy += 1
        if len(pts[0]) > 2 and any(max(abs(b[2] - a[2]), abs(b[3] - a[3])) > 0.05 for a, b in zip(pts, pts[1:])):
            xjumpy += 1
    n = len(slopes)
    q = lambda v, f: sorted(v)[int(f * (len(v) - 1))]
    print(f"{mode:4s} n {n}  LS slope median {st.median(slopes):+.3f} (q10 {q(slopes,.1):+.3f} q90 {q(slopes,.9):+.3f})"
          f"  |d_in|<=0.1 {st.median(inner):+.3f}  neighbour-slope median {st.median(robust):+.3f}"
          f" (<-0.5: {sum(1 for v in robust if v < -0.5)/n:.0%})  jumps {jumpy/n:.0%}  crossing jumps {xjumpy/n:.0%}")
