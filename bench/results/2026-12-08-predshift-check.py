#!/usr/bin/env python3
"""predshift: per-ray residuals (px, + outward) of the measured and the corrected (measured less the side
model's predicted shift) mid-level crossings against the true side line, clean vs unclean rays
(MCMT_X_PRED_DUMP of bench_accuracy with MCMT_X_CLEAN_ALL=6; only passes with a warm model).
Usage: 2026-12-08-predshift-check.py DUMP [DUMP...]"""
import math, statistics, sys


def stats(v):
    if not v:
        return "n 0"
    med = statistics.median(v)
    mad = 1.4826 * statistics.median([abs(x - med) for x in v])
    return "n %6d mean %+.4f median %+.4f robust sd %.4f" % (len(v), sum(v) / len(v), med, mad)


for path in sys.argv[1:]:
    truth, warm, res = [], False, {}
    for line in open(path):
        f = line.split()
        if f[0] == 'I':
            truth = []
        elif f[0] == 'T':
            x = [float(v) for v in f[2:10]]
            truth.append([(x[2 * k], x[2 * k + 1]) for k in range(4)])
        elif f[0] == 'S':
            warm = f[3] == '1'
            off_x, off_y = float(f[5]), float(f[6])  # the refinement's crop in the image
        elif f[0] == 'R' and warm:
            clean = int(f[1])
            ox, oy, nx, ny, best, shift = (float(v) for v in f[2:8])
            if not math.isfinite(best):
                continue
            px, py = off_x + ox + best * nx, off_y + oy + best * ny
            found = None
            for c in truth:
                cx, cy = sum(p[0] for p in c) / 4, sum(p[1] for p in c) / 4
                for k in range(4):
                    (ax, ay), (bx, by) = c[k], c[(k + 1) % 4]
                    length = math.hypot(bx - ax, by - ay)
                    dx, dy = (bx - ax) / length, (by - ay) / length
                    tx, ty = dy, -dx
                    if tx * (ax - cx) + ty * (ay - cy) < 0:
                        tx, ty = -tx, -ty
                    cosine = tx * nx + ty * ny
                    if cosine < 0.9:
                        continue
                    t = ((px - ax) * dx + (py - ay) * dy) / length
                    if t < -0.05 or t > 1.05:
                        continue
                    dist = tx * (px - ax) + ty * (py - ay)
                    if abs(dist) < 2.0 and (found is None or abs(dist) < abs(found[0])):
                        found = (dist, cosine)
            if found is None:
                continue
            dist, cosine = found
            fifth = min(4, int(5 * (int(f[8]) + 0.5) / int(f[9]))) if len(f) > 9 else 0
            res.setdefault((clean, 'measured, all'), []).append(dist)
            if math.isfinite(shift):
                res.setdefault((clean, fifth, 'measured'), []).append(dist)
                res.setdefault((clean, fifth, 'corrected'), []).append(dist - shift * cosine)
            if math.isfinite(shift):
                res.setdefault((clean, 'measured'), []).append(dist)
                res.setdefault((clean, 'predicted shift'), []).append(shift)
                res.setdefault((clean, 'corrected'), []).append(dist - shift * cosine)
    print(path)
    for clean in (1, 0):
        for kind in ('measured, all', 'measured', 'predicted shift', 'corrected'):
            print("  %-7s %-16s %s" % ('clean' if clean else 'unclean', kind, stats(res.get((clean, kind), []))))
    for clean in (1, 0):
        row = []
        for q in range(5):
            m, c = res.get((clean, q, 'measured'), []), res.get((clean, q, 'corrected'), [])
            row.append("%+.3f/%+.3f (%d)" % (statistics.median(m) if m else math.nan,
                                             statistics.median(c) if c else math.nan, len(m)))
        print("  %-7s by fifth of the side, median measured/corrected: %s" % ('clean' if clean else 'unclean',
                                                                              "  ".join(row)))
