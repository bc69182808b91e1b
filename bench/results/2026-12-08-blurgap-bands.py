#!/usr/bin/env python3
"""Per-side signed offsets of bench_imaging_maps corner dumps (MCMT_IMAGING_DUMP) by marker size band
(issue 15, helper blurgap). Side offset: the mean of its two corners' errors along the true side's outward
normal, px (outward +), as 2026-12-07-seeds13-split.py.
  python3 2026-12-08-blurgap-bands.py A.csv [B.csv]
Prints: band, markers, mean offset (se), and with B also the paired change A - B on the markers (camera,
seq, id) both found, and the offset of B on those markers."""
import math, sys
from corner_dump import marker_rows, side_offsets, truth_and_error

BANDS = ((0, 12), (12, 15), (15, 20), (20, 25), (25, 35), (35, 99))


def load(path):
    res = {}
    for key, c in marker_rows(path).items():
        t, e = truth_and_error(c)
        res[key] = (float(c[0]['size_px']), side_offsets(t, e), float(c[0]['view_deg']))
    return res


def stat(v):
    n = len(v)
    if n == 0:
        return 0, float('nan'), float('nan')
    m = sum(v) / n
    se = math.sqrt(sum((x - m) ** 2 for x in v) / max(n - 1, 1) / n)
    return n, m, se


A = load(sys.argv[1])
B = load(sys.argv[2]) if len(sys.argv) > 2 else None
for lo, hi in BANDS + ((0, 99),):
    keys = [k for k, v in A.items() if lo <= v[0] < hi]
    a = [o for k in keys for o in A[k][1]]
    n, m, se = stat(a)
    if n == 0:
        continue
    line = '%s | %d | %+.4f (%.4f)' % ('all' if hi == 99 and lo == 0 else '%d-%d' % (lo, hi), n // 4, m, se)
    if B is not None:
        both = [k for k in keys if k in B]
        d = [A[k][1][s] - B[k][1][s] for k in both for s in range(4)]
        nb, mb, seb = stat(d)
        n0, m0, se0 = stat([o for k in both for o in B[k][1]])
        line += ' | %d | %+.4f (%.4f) | %+.4f (%.4f)' % (nb // 4, m0, se0, mb, seb)
    print('| ' + line + ' |')
