#!/usr/bin/env python3
"""Gross corners of a bench_accuracy MCMT_CORNER_DUMP (issue 15, id123).

  2026-12-07-id123-gross.py TRUTH DUMP [bound px (0.5)]

TRUTH: `build/bench/diag_id123 --truth IMAGES` (condition, side band, angle band, image, id, side px, view
deg, true corners). Each dumped marker (id x0 y0 .. x3 y3, the matrix's markers in bench_accuracy's order) is
matched to the truth of its id whose centre is nearest (within 8 px); its corner errors are the distances
to the true corners. Prints the corners beyond the bound, their count per condition and in all.
"""
import math
import sys
from collections import defaultdict

truth_path, dump_path = sys.argv[1], sys.argv[2]
bound = float(sys.argv[3]) if len(sys.argv) > 3 else 0.5
truths = defaultdict(list)
for line in open(truth_path):
    f = line.split()
    c, s, g, i, mid = map(int, f[:5])
    side, view = float(f[5]), float(f[6])
    pts = [(float(f[7 + 2 * k]), float(f[8 + 2 * k])) for k in range(4)]
    truths[mid].append((c, s, g, i, side, view, pts))
per_cond = defaultdict(int)
markers = defaultdict(int)
gross_markers = 0
unmatched = 0
total = 0
for line in open(dump_path):
    f = line.split()
    mid = int(f[0])
    pts = [(float(f[1 + 2 * k]), float(f[2 + 2 * k])) for k in range(4)]
    cx, cy = sum(p[0] for p in pts) / 4, sum(p[1] for p in pts) / 4
    best, bd = None, 8.0
    for t in truths[mid]:
        tx, ty = sum(p[0] for p in t[6]) / 4, sum(p[1] for p in t[6]) / 4
        d = math.hypot(tx - cx, ty - cy)
        if d < bd:
            best, bd = t, d
    if best is None:
        unmatched += 1
        continue
    total += 1
    markers[best[0]] += 1
    errs = [math.hypot(pts[k][0] - best[6][k][0], pts[k][1] - best[6][k][1]) for k in range(4)]
    n = sum(e > bound for e in errs)
    if n:
        gross_markers += 1
        per_cond[best[0]] += n
        print("cond %2d band %d/%d image %d id %3d %.1f px %.1f deg: errors %s" %
              (best[0], best[1], best[2], best[3], mid, best[4], best[5], " ".join("%.2f" % e for e in errs)))
print("corners > %.2f px per condition: %s" % (bound, dict(sorted(per_cond.items()))))
print("all: %d corners on %d markers of %d matched (%d unmatched)" %
      (sum(per_cond.values()), gross_markers, total, unmatched))
