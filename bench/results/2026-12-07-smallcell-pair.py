#!/usr/bin/env python3
# Issue 15 (helper smallcell): paired difference B - A of two smallcell-sweep.py outputs (RAW=1), per row.
#   python3 2026-12-07-smallcell-pair.py A.txt B.txt
import sys, statistics
def load(f):
    d = {}
    for l in open(f):
        if ' RAW ' not in l: continue
        h, r = l.split(' RAW ')
        k = tuple(h.split()[:3]); d[k] = [float(x) for x in r.split()]
    return d
a, b = load(sys.argv[1]), load(sys.argv[2])
print('cell blur roll  meanA  meanB  B-A (se)')
for k in a:
    if k not in b or len(a[k]) != len(b[k]): continue
    d = [y - x for x, y in zip(a[k], b[k])]
    print(f"{k[0]} {k[1]} {k[2]:>5} {statistics.mean(a[k]):+.4f} {statistics.mean(b[k]):+.4f} {statistics.mean(d):+.4f} ({statistics.pstdev(d)/len(d)**0.5:.4f})")
