# settled vs unsettled refinements (MCMT_TRACE_REFINE trace of rulec's patch, fixed-tone config, one
# camera) joined with two diag_charuco CSVs.   python3 2026-12-05-cam1bias-settled.py TRACE A.csv B.csv
import csv, sys, math, re
from collections import defaultdict
uns = {}
frame = None; cur = None
for line in open(sys.argv[1]):
    if line.startswith('FRAME'): frame = int(line.split()[1]) - 1
    elif line.startswith(' MARKER'): cur = None
    elif line.startswith('  unsettled'): cur = int(line.split()[1])
    elif line.startswith(' END'):
        mid = int(line.split()[2]); uns[(frame, mid)] = cur
a = {(int(r['frame']),int(r['id'])): r for r in csv.DictReader(open(sys.argv[2]))}
b = {(int(r['frame']),int(r['id'])): r for r in csv.DictReader(open(sys.argv[3]))}
g = defaultdict(list)
for k in a:
    if k not in b or k not in uns: continue
    v=float(a[k]['view_deg']); s=float(a[k]['side_px'])
    grp=('v<55' if v<55 else 'v55+')+(' s<28' if s<28 else ' s28+')
    st = 'unsettled' if (uns[k] or 0) >= 2 else 'settled'
    for fl in ['size_rel','size_rel_stock_centres']:
        g[(grp, st, fl)].append((100*float(a[k][fl]), 100*float(b[k][fl])))
for k in sorted(g):
    xs = g[k]; n=len(xs)
    ma=sum(x for x,_ in xs)/n; mb=sum(y for _,y in xs)/n
    sa=math.sqrt(sum((x-ma)**2 for x,_ in xs)/n); sb=math.sqrt(sum((y-mb)**2 for _,y in xs)/n)
    print('%-10s %-10s %-24s n %3d  main %+.3f (sd %.3f)  E %+.3f (sd %.3f)' % (k[0],k[1],k[2],n,ma,sa,mb,sb))
