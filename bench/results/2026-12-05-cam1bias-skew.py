# diag_charuco CSVs (2026-12-05-cam1bias.md): skew error (|angle - 90| detected minus predicted, mean of
# the 4 corners) per camera and band.   python3 2026-12-05-cam1bias-skew.py A.csv [B.csv ...]
import csv, sys, math
from collections import defaultdict
def ang(p, a, q):
    u=(p[0]-a[0],p[1]-a[1]); v=(q[0]-a[0],q[1]-a[1])
    return math.degrees(math.acos((u[0]*v[0]+u[1]*v[1])/math.hypot(*u)/math.hypot(*v)))
for f in sys.argv[1:]:
    g=defaultdict(list)
    for r in csv.DictReader(open(f)):
        G=[(float(r['gx%d'%k]),float(r['gy%d'%k])) for k in range(4)]
        W=[(float(r['wx%d'%k]),float(r['wy%d'%k])) for k in range(4)]
        e=sum(abs(ang(G[(k+3)%4],G[k],G[(k+1)%4])-90)-abs(ang(W[(k+3)%4],W[k],W[(k+1)%4])-90) for k in range(4))/4
        sk=sum(abs(ang(W[(k+3)%4],W[k],W[(k+1)%4])-90) for k in range(4))/4
        v=float(r['view_deg']); s=float(r['side_px'])
        grp=r['camera']+' '+('v<55' if v<55 else 'v55+')+(' s<28' if s<28 else ' s28+')
        g[grp].append((e,sk)); g[r['camera']+' all'].append((e,sk))
    print(f)
    for k in sorted(g):
        xs=g[k]; n=len(xs); m=sum(x for x,_ in xs)/n; sd=math.sqrt(sum((x-m)**2 for x,_ in xs)/n)
        print('  %-16s n %3d true skew %5.1f deg  skew error %+.3f deg (se %.3f)' % (k,n,sum(y for _,y in xs)/n,m,sd/math.sqrt(n)))
