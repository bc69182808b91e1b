#!/usr/bin/env python3
"""Paired per-side comparison of two diag_side_bias SIDES=FILE dumps of the same renders (same seed, same
markers, same starts; 2026-12-06-simsize13-diag-and-reach.patch). Each line: the side's signed offset
(px, outward +), the marker's view angle (deg) and side (px), then its last model fit: sigma, L0, L1, S1,
S2, q, gamma, cell. Line i is side i % 4 of its marker. Prints A - B per band of contrast (A's L1 - L0),
of view angle, and per side and view angle.
  python3 2026-12-06-simsize13-sides.py A.txt B.txt"""
import math
import sys


def load(p):
    return [list(map(float, l.split())) for l in open(p)]


a, b = load(sys.argv[1]), load(sys.argv[2])
assert len(a) == len(b), 'not the same renders'


def stats(sel, label):
    n = len(sel)
    if not n:
        return
    d = [a[i][0] - b[i][0] for i in sel]
    m = sum(d) / n
    se = math.sqrt(sum((x - m) ** 2 for x in d) / max(n - 1, 1) / n)
    av = lambda t, c: sum(t[i][c] for i in sel) / n
    print('%s: n %d offset A %+.4f B %+.4f, A-B %+.4f (se %.4f); gamma %.3f/%.3f sigma %.3f/%.3f '
          'contrast %.0f/%.0f S1-L0 %.0f/%.0f q %.2f/%.2f' %
          (label, n, av(a, 0), av(b, 0), m, se, av(a, 9), av(b, 9), av(a, 3), av(b, 3), av(a, 5) - av(a, 4),
           av(b, 5) - av(b, 4), av(a, 6) - av(a, 4), av(b, 6) - av(b, 4), av(a, 8), av(b, 8)))


idx = range(len(a))
stats(list(idx), 'all')
for lo, hi in ((0, 110), (110, 130), (130, 150), (150, 170), (170, 300)):
    stats([i for i in idx if lo <= a[i][5] - a[i][4] < hi], 'contrast A %d-%d' % (lo, hi))
for lo, hi in ((0, 40), (40, 60), (60, 90)):
    stats([i for i in idx if lo <= a[i][1] < hi], 'view %d-%d' % (lo, hi))
for k in range(4):
    for lo, hi in ((0, 40), (40, 60), (60, 90)):
        stats([i for i in idx if i % 4 == k and lo <= a[i][1] < hi], 'side %d view %d-%d' % (k, lo, hi))
