# diag_charuco CSVs (2026-12-05-cam1bias.md): mean outward offset of opposite sides (translation-free)
# by the cell depth across them.   python3 2026-12-05-cam1bias-widths.py CAMERA A.csv [B.csv ...]
import csv, sys, math
from collections import defaultdict
def dist_pt_line(p, a, b):
    dx, dy = b[0]-a[0], b[1]-a[1]; L = math.hypot(dx, dy)
    return abs((p[0]-a[0])*dy - (p[1]-a[1])*dx) / L
for f in sys.argv[2:]:
    g = defaultdict(list)
    for r in csv.DictReader(open(f)):
        if r['camera'] != sys.argv[1]: continue
        w = [(float(r['wx%d'%k]), float(r['wy%d'%k])) for k in range(4)]
        for s in (0, 1):
            # sides s and s+2: side s from corner s to s+1; opposite side from s+2 to s+3
            d = 0.5 * (dist_pt_line(w[(s+2)%4], w[s], w[(s+1)%4]) + dist_pt_line(w[(s+3)%4], w[s], w[(s+1)%4])) / 6
            off = 0.5 * (float(r['side%d_px'%s]) + float(r['side%d_px'%(s+2)]))
            b = '<2.5' if d < 2.5 else '2.5-3.5' if d < 3.5 else '3.5-4.5' if d < 4.5 else '4.5-6' if d < 6 else '6+'
            g[b].append(off)
    print(f, '  '.join('%s: n %d %+.3f px' % (b, len(g[b]), sum(g[b])/len(g[b])) for b in ['<2.5','2.5-3.5','3.5-4.5','4.5-6','6+'] if g[b]))
