#!/usr/bin/env python3
"""Corner-angle errors of bench_imaging_maps corner dumps (MCMT_IMAGING_DUMP): per marker the error (deg)
of its most acute interior angle (the long diagonal's ends; negative: the quad comes out too square) and
the long / short diagonals' length errors (%), split by view angle and by the true acute angle.
  python3 2026-12-06-blurrow-angles.py DUMP.csv [DUMP2.csv ...]"""
import csv, math, sys
from collections import defaultdict


def markers(path):
    groups = defaultdict(dict)
    for r in csv.DictReader(open(path)):
        if r.get('corner') is None:
            continue
        groups[(r['camera'], r['seq'], r['id'])][int(r['corner'])] = r
    for g in groups.values():
        if len(g) == 4:
            t = [(float(g[k]['x']), float(g[k]['y'])) for k in range(4)]
            e = [(float(g[k]['dx']), float(g[k]['dy'])) for k in range(4)]
            yield t, e, float(g[0]['size_px']), float(g[0]['view_deg'])


def angle(q, k):
    a, b, c = q[(k + 3) % 4], q[k], q[(k + 1) % 4]
    u = (a[0] - b[0], a[1] - b[1])
    v = (c[0] - b[0], c[1] - b[1])
    return math.degrees(math.acos((u[0] * v[0] + u[1] * v[1]) / math.hypot(*u) / math.hypot(*v)))


def diag(q, a, b):
    return math.hypot(q[b][0] - q[a][0], q[b][1] - q[a][1])


for path in sys.argv[1:]:
    rows = []
    for t, e, size, view in markers(path):
        d = [(t[k][0] + e[k][0], t[k][1] + e[k][1]) for k in range(4)]
        k = min(range(4), key=lambda i: angle(t, i))
        acute = angle(t, k)
        la, lb = ((k, (k + 2) % 4), ((k + 1) % 4, (k + 3) % 4))
        long_err = 100 * (diag(d, *la) / diag(t, *la) - 1)
        short_err = 100 * (diag(d, *lb) / diag(t, *lb) - 1)
        rows.append(dict(view=view, size=size, acute=acute, err=angle(d, k) - acute, long=long_err,
                         short=short_err))
    print('%s: %d markers' % (path, len(rows)))
    print('| band | markers | acute angle error deg | long diag % | short diag % |')
    print('|---|---|---|---|---|')

    def line(name, sel):
        if sel:
            n = len(sel)
            print('| %s | %d | %+.3f | %+.3f | %+.3f |' % (name, n, sum(r['err'] for r in sel) / n,
                                                         sum(r['long'] for r in sel) / n,
                                                         sum(r['short'] for r in sel) / n))

    line('all', rows)
    for lo, hi in ((0, 20), (20, 40), (40, 50), (50, 60), (60, 90)):
        line('view %g-%g deg' % (lo, hi), [r for r in rows if lo <= r['view'] < hi])
    for lo, hi in ((0, 60), (60, 70), (70, 80), (80, 90)):
        line('true acute angle %g-%g deg' % (lo, hi), [r for r in rows if lo <= r['acute'] < hi])
