# diag_charuco CSVs (2026-12-05-cam1bias.md): each camera's size error split into the sides' widths
# and the corner angles.   python3 2026-12-05-cam1bias-split.py A.csv [B.csv ...]
# Each marker's size error split into a width part (the sides' outward offsets, opposite sides paired:
# 2 (o_A + o_B) / (w_A + w_B), w the distance between the pair's true lines) and the rest (the corner
# angles: skew), per camera and band.
import csv, sys, math
from collections import defaultdict
def dist(p, a, b):
    dx, dy = b[0]-a[0], b[1]-a[1]
    return abs((p[0]-a[0])*dy - (p[1]-a[1])*dx) / math.hypot(dx, dy)
for f in sys.argv[1:]:
    g = defaultdict(list)
    for r in csv.DictReader(open(f)):
        W = [(float(r['wx%d'%k]), float(r['wy%d'%k])) for k in range(4)]
        o = [float(r['side%d_px'%s]) for s in range(4)]
        w = [0.5*(dist(W[(s+2)%4], W[s], W[(s+1)%4]) + dist(W[(s+3)%4], W[s], W[(s+1)%4])) for s in (0, 1)]
        width = 2 * ((o[0]+o[2])/2 + (o[1]+o[3])/2) / (w[0]+w[1])
        size = float(r['size_rel'])
        v = float(r['view_deg']); s = float(r['side_px'])
        for grp in [r['camera']+' all', r['camera']+' '+('v<55' if v<55 else 'v55+')+(' s<28' if s<28 else ' s28+')]:
            g[grp].append((size, width))
    print(f)
    for k in sorted(g):
        xs = g[k]; n = len(xs)
        ms = 100*sum(a for a,_ in xs)/n; mw = 100*sum(b for _,b in xs)/n
        print('  %-16s n %3d  size %+.3f %% = widths %+.3f + angles %+.3f' % (k, n, ms, mw, ms-mw))
