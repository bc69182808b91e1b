"""Split a bench_imaging_maps corner dump (MCMT_IMAGING_RENDERER=reference, MCMT_IMAGING_DUMP) by each side's
angle to its image's motion line, by marker size, view angle and the motion's length across the side over the
cells' depth across it: mean offset along the true side's outward normal (+ outward), px (2026-12-07-motionmap.md).
  g++ -O2 -o /tmp/motion_angle 2026-12-07-motionmap-angle.cc
  [MOTION=px (motion_px, 2.5)] [ANGLE_BIN=/tmp/motion_angle] python3 2026-12-07-motionmap-split.py DUMP [ROW (8)]
A side's end offsets are its corners' errors projected on its outward normal (a corner lies on both its
sides' lines, so that projection is exactly the line's offset there); the side's offset is their mean."""
import math, subprocess, sys, os
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from corner_dump import marker_rows, truth_and_error

path = sys.argv[1]
ci = int(sys.argv[2]) if len(sys.argv) > 2 else 8
rows = marker_rows(path)
seeds = sorted({1000003 * ci + 1009 * int(cam) + int(seq) for (cam, seq, _id) in rows})
out = subprocess.run([os.environ.get('ANGLE_BIN', '/tmp/motion_angle')], input='\n'.join(map(str, seeds)) + '\n', capture_output=True,
                     text=True).stdout.split('\n')
angle = {int(l.split()[0]): float(l.split()[1]) for l in out if l.strip()}

sides = []  # (phi deg: side direction vs motion line 0..90, side length px, size_px, view_deg, offset, end offsets)
for (cam, seq, mid), c in rows.items():
    t, e = truth_and_error(c)
    a = angle[1000003 * ci + 1009 * int(cam) + int(seq)]
    m = (math.cos(a), math.sin(a))
    cx = sum(p[0] for p in t) / 4
    cy = sum(p[1] for p in t) / 4
    for s in range(4):
        p, q = t[s], t[(s + 1) % 4]
        d = (q[0] - p[0], q[1] - p[1])
        L = math.hypot(*d)
        n = (d[1] / L, -d[0] / L)
        mx, my = 0.5 * (p[0] + q[0]) - cx, 0.5 * (p[1] + q[1]) - cy
        if n[0] * mx + n[1] * my < 0:
            n = (-n[0], -n[1])
        o0 = n[0] * e[s][0] + n[1] * e[s][1]
        o1 = n[0] * e[(s + 1) % 4][0] + n[1] * e[(s + 1) % 4][1]
        phi = math.degrees(math.acos(min(1, abs(d[0] * m[0] + d[1] * m[1]) / L)))
        r_, q_ = t[(s + 2) % 4], t[(s + 3) % 4]
        depth = n[0] * (p[0] - 0.5 * (r_[0] + q_[0])) + n[1] * (p[1] - 0.5 * (r_[1] + q_[1]))
        across = abs(n[0] * m[0] + n[1] * m[1])
        sides.append((phi, L, float(c[0]['size_px']), float(c[0]['view_deg']), 0.5 * (o0 + o1), o0, o1, s,
                      depth / 8.0, across))


def table(title, key, edges, fmt='%g-%g'):
    print('\n| %s | sides | mean offset px | median px |\n|---|---|---|---|' % title)
    for lo, hi in zip(edges[:-1], edges[1:]):
        v = sorted(x[4] for x in sides if lo <= key(x) < hi)
        if v:
            print('| %s | %d | %+.4f | %+.4f |' % (fmt % (lo, hi), len(v), sum(v) / len(v), v[len(v) // 2]))


allv = [x[4] for x in sides]
print('%s: %d markers, %d sides, mean offset %+.4f px' % (path, len(rows), len(sides), sum(allv) / len(allv)))
table('side vs motion deg (0 along, 90 across)', lambda x: x[0], [0, 15, 30, 45, 60, 75, 90.01])
table('side length px', lambda x: x[1], [0, 15, 18, 21, 24, 27, 30, 40, 100])
table('view deg', lambda x: x[3], [0, 20, 40, 50, 60, 70, 90])
print('\n| side length px | along (0-30) | mid (30-60) | across (60-90) |\n|---|---|---|---|')
for lo, hi in zip([0, 18, 22, 26, 100][:-1], [18, 22, 26, 100]):
    cells = []
    for plo, phi_ in ((0, 30), (30, 60), (60, 90.01)):
        v = [x[4] for x in sides if lo <= x[1] < hi and plo <= x[0] < phi_]
        cells.append('%+.4f (%d)' % (sum(v) / len(v), len(v)) if v else '-')
    print('| %g-%g | %s |' % (lo, hi, ' | '.join(cells)))
print('\n| view deg | along (0-30) | mid (30-60) | across (60-90) |\n|---|---|---|---|')
for lo, hi in ((0, 30), (30, 45), (45, 55), (55, 65), (65, 90)):
    cells = []
    for plo, phi_ in ((0, 30), (30, 60), (60, 90.01)):
        v = [x[4] for x in sides if lo <= x[3] < hi and plo <= x[0] < phi_]
        cells.append('%+.4f (%d)' % (sum(v) / len(v), len(v)) if v else '-')
    print('| %g-%g | %s |' % (lo, hi, ' | '.join(cells)))

import os
Lm = float(os.environ.get('MOTION', '2.5'))
table('motion across the side / cell depth across it', lambda x: Lm * x[9] / x[8], [0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 3.0, 10])
print('\n| cell depth across px | along (0-30) | mid (30-60) | across (60-90) |\n|---|---|---|---|')
for lo, hi in ((0, 1.4), (1.4, 1.8), (1.8, 2.2), (2.2, 2.6), (2.6, 10)):
    cells = []
    for plo, phi_ in ((0, 30), (30, 60), (60, 90.01)):
        v = [x[4] for x in sides if lo <= x[8] < hi and plo <= x[0] < phi_]
        cells.append('%+.4f (%d)' % (sum(v) / len(v), len(v)) if v else '-')
    print('| %g-%g | %s |' % (lo, hi, ' | '.join(cells)))
print('\n| side index | cells depth across / length along, view >= 50 deg | view < 30 deg |\n|---|---|---|')
for k in range(4):
    v = [x[8] / (x[1] / 8) for x in sides if x[7] == k and x[3] >= 50]
    w = [x[8] / (x[1] / 8) for x in sides if x[7] == k and x[3] < 30]
    print('| %d | %.3f (%d) | %.3f (%d) |' % (k, sum(v) / len(v), len(v), sum(w) / len(w), len(w)))
