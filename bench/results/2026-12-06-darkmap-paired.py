#!/usr/bin/env python3
"""Paired per-marker comparison of two bench_imaging_maps corner dumps of the same session (MCMT_IMAGING_DUMP;
e.g. main and an env switch): for markers detected in both, the mean size error about the true centroid and
the long diagonal's length error (%) in A, in B and B - A, by size and view band, leaving out markers with a
corner farther than 0.5 px from the truth in either.
  python3 2026-12-06-darkmap-paired.py A.csv B.csv"""
import math, sys
exec(open(__file__.replace('paired', 'sides')).read().replace('\nmain()\n', '\n'))
sys.path.insert(0, '.')
import importlib.util, os
spec = importlib.util.spec_from_file_location('hm', os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                                  '2026-12-06-hardmap-dump.py'))
src = open(spec.origin).read().split('\nfor path in sys.argv[1:]:')[0]
hm = {}
exec(src, hm)


def load(path):
    out = {}
    for key, t, e, size, view in dump_markers(path):
        if max(math.hypot(*x) for x in e) > 0.5:
            out[key] = None
            continue
        s, ld, sd, side = hm['measures'](t, e)
        out[key] = (size, view, s, ld)
    return out


a, b = load(sys.argv[1]), load(sys.argv[2])
keys = [k for k in a if k in b and a[k] and b[k]]
print('%d markers in both (corners within 0.5 px in both)' % len(keys))
print('| band | markers | size % A | size % B | B - A | long diag % A | long diag % B | B - A |')
print('|---|---|---|---|---|---|---|---|')


def line(name, sel):
    if not sel:
        return
    n = len(sel)
    sa = sum(a[k][2] for k in sel) / n
    sb = sum(b[k][2] for k in sel) / n
    la = sum(a[k][3] for k in sel) / n
    lb = sum(b[k][3] for k in sel) / n
    print('| %s | %d | %+.3f | %+.3f | %+.3f | %+.3f | %+.3f | %+.3f |' % (name, n, sa, sb, sb - sa, la, lb, lb - la))


line('all', keys)
for lo, hi in ((0, 15), (15, 20), (20, 25)):
    line('%g-%g px' % (lo, hi), [k for k in keys if lo <= a[k][0] < hi])
for lo, hi in ((0, 20), (20, 40), (40, 50), (50, 60), (60, 90)):
    line('%g-%g deg' % (lo, hi), [k for k in keys if lo <= a[k][1] < hi])
