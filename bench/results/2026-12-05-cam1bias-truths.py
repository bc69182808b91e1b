# diag_charuco CSVs (2026-12-05-cam1bias.md): mean size error per camera and band of view / side against
# the four truths (chessboard, local chessboard, mcmt's centres, stock OpenCV's centres).
#   python3 2026-12-05-cam1bias-truths.py A.csv [B.csv ...]
import csv, sys, math
from collections import defaultdict
fields=['size_rel','size_rel_local','size_rel_centres','size_rel_stock_centres']
for f in sys.argv[1:]:
    print(f)
    g = defaultdict(list)
    for r in csv.DictReader(open(f)):
        v=float(r['view_deg']); s=float(r['side_px'])
        g[(r['camera'],'all')].append(r)
        g[(r['camera'], ('v<55' if v<55 else 'v55+')+(' s<28' if s<28 else ' s28+'))].append(r)
    for k in sorted(g):
        rs=g[k]; out='  %s %-10s n %3d' % (k[0],k[1],len(rs))
        for fl in fields:
            xs=[float(r[fl]) for r in rs if not math.isnan(float(r[fl]))]
            out+='  %s %+.3f' % (fl[9:] or 'chess', 100*sum(xs)/len(xs) if xs else float('nan'))
        print(out)
