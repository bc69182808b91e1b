#!/usr/bin/env python3
"""Tables of the blurgap runs (issue 15, helper blurgap): for each renderer and optics the map's scale error
per radius and the per-side offsets by size band, pooled over the radii: absolute (outward +) and the paired
change against the same renderer's blur 0 at the same radius (markers (radius, camera, seq, id) both found).
  python3 2026-12-08-blurgap-table.py RUNS_DIR   (files m300-RADIUS-RENDERER-TAG.{out,csv} of run2.sh)"""
import math, os, sys
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from corner_dump import marker_rows, side_offsets, truth_and_error
d = sys.argv[1]
RADII = ('1.3', '1.0', '0.7')
TAGS = (('blur_sigma_0', 'none'), ('blur_sigma_0_6', 'blur 0.6'), ('blur_sigma_1_05', 'blur 1.05'),
        ('blur_sigma_1_4', 'blur 1.4'), ('defocus_radius_0_8', 'defocus 0.8'))
BANDS = ((0, 15), (15, 20), (20, 25), (25, 35))


def load(path):
    res = {}
    if not os.path.exists(path):
        return res
    for key, c in marker_rows(path).items():
        t, e = truth_and_error(c)
        res[key] = (float(c[0]['size_px']), side_offsets(t, e))
    return res


def mapline(path):
    if not os.path.exists(path):
        return 'n/a'
    f = open(path).read().strip().split('\n')[-1].split('|')
    if len(f) < 4 or f[1].strip().startswith('imaging'):
        return 'n/a'
    s = f[3].strip()
    return 'no map' if s.startswith('(no map') else s


def stat(v):
    n = len(v)
    if n < 2:
        return '-'
    m = sum(v) / n
    se = math.sqrt(sum((x - m) ** 2 for x in v) / (n - 1) / n)
    return '%+.4f (%.4f) n %d' % (m, se, n // 4)


data = {}
for r in RADII:
    for rend in ('sim', 'reference'):
        for tag, _ in TAGS:
            data[(r, rend, tag)] = load('%s/m300-%s-%s-%s.csv' % (d, r, rend, tag))
print('| renderer | optics | map %% at %s m | %s |' % (' / '.join(RADII),
      ' | '.join('%d-%d px: offset / paired change vs none, px (se) n' % b for b in BANDS)))
print('|---|---|---|' + '---|' * len(BANDS))
for rend in ('sim', 'reference'):
    for tag, name in TAGS:
        maps = ' / '.join(mapline('%s/m300-%s-%s-%s.out' % (d, r, rend, tag)) for r in RADII)
        cells = []
        for lo, hi in BANDS:
            a, ch = [], []
            for r in RADII:
                A, B = data[(r, rend, tag)], data[(r, rend, 'blur_sigma_0')]
                for k, v in A.items():
                    if lo <= v[0] < hi:
                        a += v[1]
                        if k in B:
                            ch += [v[1][s] - B[k][1][s] for s in range(4)]
            cells.append('%s / %s' % (stat(a).rsplit(' n', 1)[0] if len(a) > 1 else '-', stat(ch)))
        print('| %s | %s | %s | %s |' % (rend, name, maps, ' | '.join(cells)))
