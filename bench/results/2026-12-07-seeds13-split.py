#!/usr/bin/env python3
"""Split of bench_imaging_maps corner dumps (MCMT_IMAGING_DUMP), issue 15 (helper seeds13).
Side offset: the mean of its two corners' errors along the true side's outward normal (px, outward +); roles
and cell depth as 2026-12-06-simsize13-reachsplit.py (side 0 top, 2 bottom, of 1 / 3 the longer in the image
"near", the shorter "far"); size % = 2 x the sides' mean offset / distance across (a marker's size error).
  python3 2026-12-07-seeds13-split.py A.csv [B.csv]         by camera, role, view, cell, camera x role / view
  python3 2026-12-07-seeds13-split.py --ids A.csv [B.csv]   by marker id and side k (ArUco corners k -> k+1)
With B, each side's offset is A's less B's on the markers (camera, seq, id) found in both (paired)."""
import math, sys
from collections import defaultdict

IDS = '--ids' in sys.argv
if IDS:
    sys.argv.remove('--ids')

from corner_dump import marker_rows, truth_and_error

def markers(path):
    return {key: (*truth_and_error(c), float(c[0]['view_deg']), float(c[0]['size_px']),
                  c[0]['fully_visible'] == '1', c[0]['occluded'] == '1') for key, c in marker_rows(path).items()}

def sides(t, e):
    cx = sum(p[0] for p in t) / 4; cy = sum(p[1] for p in t) / 4
    res = []
    for k in range(4):
        a, b = t[k], t[(k + 1) % 4]
        L = math.hypot(b[0] - a[0], b[1] - a[1])
        n = ((b[1] - a[1]) / L, -(b[0] - a[0]) / L)
        mx, my = (a[0] + b[0]) / 2, (a[1] + b[1]) / 2
        if n[0] * (mx - cx) + n[1] * (my - cy) < 0: n = (-n[0], -n[1])
        o = 0.5 * sum(e[j][0] * n[0] + e[j][1] * n[1] for j in (k, (k + 1) % 4))
        p, q = t[(k + 2) % 4], t[(k + 3) % 4]
        across = abs((0.5 * (p[0] + q[0]) - mx) * n[0] + (0.5 * (p[1] + q[1]) - my) * n[1])
        res.append(dict(off=o, L=L, across=across, cell=across / 8))
    near = 1 if res[1]['L'] >= res[3]['L'] else 3
    for k in range(4):
        res[k]['role'] = {0: 'top', 2: 'bottom'}.get(k, 'near' if k == near else 'far')
    return res



def by_id(A, B):
    acc = defaultdict(list)
    for key, (t, e, view, size, fv, occ) in A.items():
        if B is not None and key not in B:
            continue
        s = sides(t, e)
        sb = sides(B[key][0], B[key][1]) if B else None
        for k in range(4):
            d = s[k]['off'] - (sb[k]['off'] if sb else 0.0)
            acc[(int(key[2]), str(k))].append(d)
            acc[(int(key[2]), 'all')].append(d)
    for key in sorted(acc):
        v = acc[key]
        n = len(v)
        m = sum(v) / n
        se = math.sqrt(sum((x - m) ** 2 for x in v) / max(n - 1, 1) / n)
        print('id %d side %s: n %d offset %+.4f (%.4f)' % (key[0], key[1], n, m, se))


A = markers(sys.argv[1])
B = markers(sys.argv[2]) if len(sys.argv) > 2 else None
if IDS:
    by_id(A, B)
    sys.exit(0)

rows = []
for key, (t, e, view, size, fv, occ) in A.items():
    if B is not None and key not in B: continue
    s = sides(t, e)
    sb = sides(B[key][0], B[key][1]) if B is not None else None
    for k in range(4):
        off = s[k]['off'] - (sb[k]['off'] if sb else 0.0)
        rows.append(dict(cam=key[0], view=view, size=size, role=s[k]['role'], cell=s[k]['cell'], off=off,
                         rel=100 * off / s[k]['across'], occ=occ, fv=fv))

def line(sel, name):
    n = len(sel)
    if n < 2: return
    m = sum(r['off'] for r in sel) / n
    se = math.sqrt(sum((r['off'] - m) ** 2 for r in sel) / (n - 1) / n)
    rel = sum(r['rel'] for r in sel) / n
    print('| %s | %d | %.2f | %.1f | %+.4f (%.4f) | %+.3f |' % (name, n // 1, sum(r['cell'] for r in sel) / n,
          sum(r['size'] for r in sel) / n, m, se, 2 * rel))

print('| group | sides | cell px | size px | offset px (se), outward + | size % (2 x rel) |')
print('|---|---|---|---|---|---|')
line(rows, 'all')
for c in sorted(set(r['cam'] for r in rows)):
    line([r for r in rows if r['cam'] == c], 'camera ' + c)
for role in ('top', 'bottom', 'near', 'far'):
    line([r for r in rows if r['role'] == role], role)
for lo, hi in ((0, 40), (40, 60), (60, 90)):
    line([r for r in rows if lo <= r['view'] < hi], 'view %d-%d' % (lo, hi))
for lo, hi in ((0, 1.0), (1.0, 1.5), (1.5, 2.5), (2.5, 99)):
    line([r for r in rows if lo <= r['cell'] < hi], 'cell %.1f-%.1f' % (lo, hi))
line([r for r in rows if r['occ']], 'occluded')
if True:
    for c in sorted(set(r['cam'] for r in rows)):
        for role in ('top', 'bottom', 'near', 'far'):
            line([r for r in rows if r['cam'] == c and r['role'] == role], 'cam %s %s' % (c, role))
        for lo, hi in ((0, 40), (40, 60), (60, 90)):
            line([r for r in rows if r['cam'] == c and lo <= r['view'] < hi], 'cam %s view %d-%d' % (c, lo, hi))
