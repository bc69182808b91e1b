#!/usr/bin/env python3
"""Corner errors of a bench_imaging_maps dump (MCMT_IMAGING_DUMP), per marker: the least-squares size error
about the true centroid (%), the long / short diagonals' length errors (%), the mean side offset along the
outward normals (px), split by size and view band.
  python3 2026-12-06-hardmap-dump.py DUMP.csv [DUMP2.csv ...]"""
import csv, math, sys
from collections import defaultdict


def markers(path):
    groups = defaultdict(dict)
    for r in csv.DictReader(open(path)):
        key = (r['condition'], r['camera'], r['seq'], r['id'])
        groups[key][int(r['corner'])] = r
    for key, g in groups.items():
        if len(g) != 4:
            continue
        t = [(float(g[k]['x']), float(g[k]['y'])) for k in range(4)]
        e = [(float(g[k]['dx']), float(g[k]['dy'])) for k in range(4)]
        yield key, t, e, float(g[0]['size_px']), float(g[0]['view_deg'])


def measures(t, e):
    cx = sum(p[0] for p in t) / 4
    cy = sum(p[1] for p in t) / 4
    num = den = 0.0
    for (x, y), (dx, dy) in zip(t, e):
        rx, ry = x - cx, y - cy
        num += rx * dx + ry * dy
        den += rx * rx + ry * ry
    size = 100 * num / den
    diag = []
    for a, b in ((0, 2), (1, 3)):
        l0 = math.hypot(t[b][0] - t[a][0], t[b][1] - t[a][1])
        l1 = math.hypot(t[b][0] + e[b][0] - t[a][0] - e[a][0], t[b][1] + e[b][1] - t[a][1] - e[a][1])
        diag.append((l0, 100 * (l1 / l0 - 1)))
    diag.sort(reverse=True)
    # orientation: sign of the area so the normal (dy, -dx) points outward
    area = sum(t[k][0] * t[(k + 1) % 4][1] - t[(k + 1) % 4][0] * t[k][1] for k in range(4))
    side = 0.0
    for k in range(4):
        a, b = t[k], t[(k + 1) % 4]
        vx, vy = b[0] - a[0], b[1] - a[1]
        L = math.hypot(vx, vy)
        nx, ny = (vy / L, -vx / L) if area > 0 else (-vy / L, vx / L)
        side += ((e[k][0] + e[(k + 1) % 4][0]) * nx + (e[k][1] + e[(k + 1) % 4][1]) * ny) / 2 / 4
    return size, diag[0][1], diag[1][1], side


def band(v, edges):
    for lo, hi in edges:
        if lo <= v < hi:
            return '%g-%g' % (lo, hi)
    return 'other'


for path in sys.argv[1:]:
    rows = [(s, v) + measures(t, e) for _, t, e, s, v in markers(path)]
    print('\n%s: %d markers' % (path, len(rows)))
    print('| band | markers | size % | long diag % | short diag % | side offset px |')
    print('|---|---|---|---|---|---|')
    def line(name, sel):
        if not sel:
            return
        n = len(sel)
        m = [sum(r[i] for r in sel) / n for i in range(2, 6)]
        print('| %s | %d | %+.3f | %+.3f | %+.3f | %+.4f |' % (name, n, *m))
    line('all', rows)
    for edges, idx, unit in (([(0, 15), (15, 20), (20, 25), (25, 35), (35, 100)], 0, 'px'),
                             ([(0, 20), (20, 40), (40, 60), (60, 90)], 1, 'deg')):
        for lo, hi in edges:
            line('%g-%g %s' % (lo, hi, unit), [r for r in rows if lo <= r[idx] < hi])
