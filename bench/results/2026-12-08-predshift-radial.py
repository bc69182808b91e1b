#!/usr/bin/env python3
"""predshift: mean radial corner error (px, + outward from the marker's centroid) of MCMT_IMAGING_DUMP
CSVs (bench_imaging_maps), per view-angle band, over markers with all four corners in every dump.
Usage: 2026-12-08-predshift-radial.py A.csv B.csv ..."""
import csv, math, sys


def load(path):
    m = {}
    for r in csv.DictReader(open(path)):
        key = (r['radius'], r['condition'], r['camera'], r['seq'], r['id'])
        m.setdefault(key, {})[int(r['corner'])] = r
    return {k: v for k, v in m.items() if len(v) == 4}


dumps = [load(p) for p in sys.argv[1:]]
common = set(dumps[0])
for d in dumps[1:]:
    common &= set(d)
bands = [(0, 40), (40, 60), (60, 90), (0, 90)]
for path, d in zip(sys.argv[1:], dumps):
    out = []
    for lo, hi in bands:
        radial = []
        for k in common:
            c = d[k]
            view = float(c[0]['view_deg'])
            if not (lo <= view < hi):
                continue
            # x, y: the true corners (the detected = true + (dx, dy)).
            cx = sum(float(c[i]['x']) for i in range(4)) / 4
            cy = sum(float(c[i]['y']) for i in range(4)) / 4
            for i in range(4):
                ux, uy = float(c[i]['x']) - cx, float(c[i]['y']) - cy
                n = math.hypot(ux, uy)
                radial.append((float(c[i]['dx']) * ux + float(c[i]['dy']) * uy) / n)
        out.append("%d-%d deg %+.4f (%d)" % (lo, hi, sum(radial) / max(1, len(radial)), len(radial) // 4))
    print(path, " | ".join(out))

# The relative error (%) of each marker's shorter and longer width (the mean length of its two
# opposite sides, detected vs true: x, y are the true corners, detected = true + (dx, dy)).
print("relative width error %, shorter (foreshortened) / longer pair of opposite sides:")
for path, d in zip(sys.argv[1:], dumps):
    out = []
    for lo, hi in bands:
        short, long_ = [], []
        for k in common:
            c = d[k]
            if not (lo <= float(c[0]['view_deg']) < hi):
                continue
            t = [(float(c[i]['x']), float(c[i]['y'])) for i in range(4)]
            e = [(t[i][0] + float(c[i]['dx']), t[i][1] + float(c[i]['dy'])) for i in range(4)]
            side = lambda p, i: math.hypot(p[(i + 1) % 4][0] - p[i][0], p[(i + 1) % 4][1] - p[i][1])
            w = [(side(t, 0) + side(t, 2)) / 2, (side(t, 1) + side(t, 3)) / 2]
            we = [(side(e, 0) + side(e, 2)) / 2, (side(e, 1) + side(e, 3)) / 2]
            rel = [100 * (we[j] / w[j] - 1) for j in range(2)]
            s = 0 if w[0] < w[1] else 1
            short.append(rel[s]), long_.append(rel[1 - s])
        out.append("%d-%d deg %+.3f / %+.3f" % (lo, hi, sum(short) / max(1, len(short)), sum(long_) / max(1, len(long_))))
    print(path, " | ".join(out))
