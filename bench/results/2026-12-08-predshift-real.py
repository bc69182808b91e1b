#!/usr/bin/env python3
"""predshift: per camera (I lines) of a DetectorRealData MCMT_X_PRED_DUMP (MCMT_X_CLEAN_ALL=6/7), in the
passes with a warm model: each ray's measured crossing and its crossing less the model's predicted shift
(px outward from the ray's origin, the previous model pass's edge), clean vs unclean, by place along the
side (fifths of the rays). Usage: 2026-12-08-predshift-real.py DUMP"""
import math, statistics, sys

cams = {}
cam, warm = None, False
for line in open(sys.argv[1]):
    f = line.split()
    if f[0] == 'I':
        cam = f[1]
    elif f[0] == 'S':
        warm = f[3] == '1'
    elif f[0] == 'R' and warm and cam:
        clean = int(f[1])
        best, shift = float(f[6]), float(f[7])
        i, n = int(f[8]), int(f[9])
        if not (math.isfinite(best) and math.isfinite(shift)):
            continue
        d = cams.setdefault(cam, {})
        fifth = min(4, int(5 * (i + 0.5) / n))
        for key in ((clean, 'all'), (clean, fifth)):
            d.setdefault(key, ([], [])),
            d[key][0].append(best)
            d[key][1].append(best - shift)


def med(v):
    return statistics.median(v) if v else float('nan')


for cam, d in sorted(cams.items()):
    print(cam)
    for clean in (1, 0):
        m, c = d.get((clean, 'all'), ([], []))
        print("  %-7s n %6d measured mean %+.4f median %+.4f | corrected mean %+.4f median %+.4f" %
              ('clean' if clean else 'unclean', len(m), sum(m) / max(1, len(m)), med(m), sum(c) / max(1, len(c)),
               med(c)))
    for clean in (1, 0):
        row = []
        for q in range(5):
            m, c = d.get((clean, q), ([], []))
            row.append("%+.3f/%+.3f (%d)" % (med(m), med(c), len(m)))
        print("  %-7s by fifth, median measured/corrected: %s" % ('clean' if clean else 'unclean', "  ".join(row)))
