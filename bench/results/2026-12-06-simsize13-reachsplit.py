#!/usr/bin/env python3
"""Paired per-side split of two bench_imaging_maps corner dumps (MCMT_IMAGING_DUMP) of the same session, A and
B (e.g. SS_REACH=1.8 and main). Markers are matched by (camera, seq, id); only markers with four corners in
both are used. Per marker side k (ArUco corners k -> k+1 of the true quad; 0 top, 1 right, 2 bottom, 3 left
in the marker's frame; the four-sided body stands upright, so side 0 borders the body's top face, side 2 its
lower edge), the side's signed offset (px, outward +) is the mean of its two corners' errors along the true
side's outward normal; its cell depth across the edge is the distance from the opposite side's midpoint to
the side's line / 8 (DICT_6X6 plus border). Of sides 1 / 3 the longer in the image is the "near" one (it
borders the neighbouring face the camera also sees), the shorter the "far" one (the body's silhouette: the
background lies 3 cells beyond). rel % = 100 * offset / that distance across (the side's share of the
marker's size error; opposite sides add).
  python3 2026-12-06-simsize13-reachsplit.py A.csv B.csv [label]"""
import math
import sys

from corner_dump import marker_rows, truth_and_error


def markers(path):
    return {key: (*truth_and_error(c), float(c[0]['view_deg']), float(c[0]['size_px']),
                  c[0]['fully_visible'] == '1') for key, c in marker_rows(path).items()}


def sides(t, e):
    cx = sum(p[0] for p in t) / 4
    cy = sum(p[1] for p in t) / 4
    res = []
    for k in range(4):
        a, b = t[k], t[(k + 1) % 4]
        L = math.hypot(b[0] - a[0], b[1] - a[1])
        n = ((b[1] - a[1]) / L, -(b[0] - a[0]) / L)
        mx, my = (a[0] + b[0]) / 2, (a[1] + b[1]) / 2
        if n[0] * (mx - cx) + n[1] * (my - cy) < 0:
            n = (-n[0], -n[1])
        o = 0.5 * sum(e[j][0] * n[0] + e[j][1] * n[1] for j in (k, (k + 1) % 4))
        p, q = t[(k + 2) % 4], t[(k + 3) % 4]
        across = abs((0.5 * (p[0] + q[0]) - mx) * n[0] + (0.5 * (p[1] + q[1]) - my) * n[1])
        res.append(dict(off=o, L=L, across=across, cell=across / 8, ny=n[1]))
    near = 1 if res[1]['L'] >= res[3]['L'] else 3
    for k in range(4):
        res[k]['role'] = {0: 'top', 2: 'bottom'}.get(k, 'near' if k == near else 'far')
    return res


A, B = markers(sys.argv[1]), markers(sys.argv[2])
label = sys.argv[3] if len(sys.argv) > 3 else ''
keys = sorted(set(A) & set(B))
rows = []
for key in keys:
    ta, ea, view, size, fv = A[key]
    tb, eb, _, _, _ = B[key]
    sa, sb = sides(ta, ea), sides(tb, eb)
    for k in range(4):
        rows.append(dict(view=view, size=size, k=k, role=sa[k]['role'], cell=sa[k]['cell'], a=sa[k]['off'],
                         b=sb[k]['off'], ra=100 * sa[k]['off'] / sa[k]['across'],
                         rb=100 * sb[k]['off'] / sb[k]['across'], ny=sa[k]['ny']))
print('%s: %d markers in both (A %d, B %d); side 0 normal points up in the image on %.0f %% of markers' %
      (label, len(keys), len(A), len(B), 100 * sum(r['ny'] < 0 for r in rows if r['k'] == 0) / max(len(keys), 1)))


def line(sel, name):
    n = len(sel)
    if n < 2:
        return
    d = [r['a'] - r['b'] for r in sel]
    m = sum(d) / n
    se = math.sqrt(sum((x - m) ** 2 for x in d) / (n - 1) / n)
    ra = sum(r['ra'] for r in sel) / n
    rb = sum(r['rb'] for r in sel) / n
    print('| %s | %d | %.2f | %+.4f | %+.4f | **%+.4f** (%.4f) | %+.3f | %+.3f | %+.3f |' %
          (name, n, sum(r['cell'] for r in sel) / n, sum(r['b'] for r in sel) / n, sum(r['a'] for r in sel) / n,
           m, se, rb, ra, ra - rb))


print('\n| sides | n | cell px | offset B px | offset A px | A - B px (se) | rel B %% | rel A %% | A - B %% |')
print('|---|---|---|---|---|---|---|---|---|')
line(rows, 'all')
VIEWS = ((0, 40), (40, 60), (60, 90))
CELLS = ((0, 1.0), (1.0, 1.5), (1.5, 2.5), (2.5, 99))
for lo, hi in VIEWS:
    line([r for r in rows if lo <= r['view'] < hi], 'view %d-%d' % (lo, hi))
for lo, hi in CELLS:
    line([r for r in rows if lo <= r['cell'] < hi], 'cell %.1f-%.1f' % (lo, hi))
for role in ('top', 'bottom', 'near', 'far'):
    line([r for r in rows if r['role'] == role], role)
print()
for role in ('top', 'bottom', 'near', 'far'):
    for lo, hi in VIEWS:
        line([r for r in rows if r['role'] == role and lo <= r['view'] < hi], '%s, view %d-%d' % (role, lo, hi))
print()
for role in ('top', 'bottom', 'near', 'far'):
    for lo, hi in CELLS:
        line([r for r in rows if r['role'] == role and lo <= r['cell'] < hi],
             '%s, cell %.1f-%.1f' % (role, lo, hi))
# Marker size: the mean of the four sides' rel % (each opposite pair adds to the width's error), per view.
print('\n| markers | n | size error B %% | size error A %% | A - B %% (se) |')
print('|---|---|---|---|---|')
for lo, hi in ((0, 90),) + VIEWS:
    ms = [rows[i:i + 4] for i in range(0, len(rows), 4) if lo <= rows[i]['view'] < hi]
    if len(ms) < 2:
        continue
    sb = [0.5 * sum(r['rb'] for r in m) for m in ms]
    sa = [0.5 * sum(r['ra'] for r in m) for m in ms]
    d = [x - y for x, y in zip(sa, sb)]
    mu = sum(d) / len(d)
    se = math.sqrt(sum((x - mu) ** 2 for x in d) / (len(d) - 1) / len(d))
    print('| view %d-%d | %d | %+.3f | %+.3f | %+.4f (%.4f) |' % (lo, hi, len(ms), sum(sb) / len(sb),
                                                            sum(sa) / len(sa), mu, se))
# Per marker: width (near + far rel %), height (top + bottom rel %) and the far - near offset (px), A - B.
print('\n| markers, A - B | n | width %% (se) | height %% (se) | far - near px (se) | bottom - top px (se) |')
print('|---|---|---|---|---|---|')


def ms(vals):
    mu = sum(vals) / len(vals)
    return mu, math.sqrt(sum((x - mu) ** 2 for x in vals) / (len(vals) - 1) / len(vals))


for lo, hi in ((0, 90),) + VIEWS:
    mk = [{r['role']: r for r in rows[i:i + 4]} for i in range(0, len(rows), 4) if lo <= rows[i]['view'] < hi]
    if len(mk) < 2:
        continue
    d = lambda r: r['ra'] - r['rb']
    dp = lambda r: r['a'] - r['b']
    cols = [ms([d(m['near']) + d(m['far']) for m in mk]), ms([d(m['top']) + d(m['bottom']) for m in mk]),
            ms([dp(m['far']) - dp(m['near']) for m in mk]), ms([dp(m['bottom']) - dp(m['top']) for m in mk])]
    print('| view %d-%d | %d | %s |' % (lo, hi, len(mk), ' | '.join('%+.4f (%.4f)' % c for c in cols)))
