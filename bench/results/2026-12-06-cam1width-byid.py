# diag_charuco CSV (2026-12-06-cam1width.md): a camera's width bias (mean outward offset of opposite sides,
# as 2026-12-05-cam1bias-widths.py) per marker id: mean cell depth, mean offset, the slope of offset on cell
# depth within the id (px per px; pooled over ids, inverse-variance) against the slope across all ids, and
# each id's two pairs of sides apart. With the picture types (ffprobe, as 2026-12-06-cam1width-splits.py),
# also each frame's mean residual from the camera's linear trend (offset = a + b depth). Last, the
# within-marker slope: per marker, pair 0/2's offset minus pair 1/3's regressed (through 0) on their depth
# difference, px per px (a marker-wide scale error cancels), all markers and by view < / >= 50 deg; with
# STOCK=1 against the stock-OpenCV-centres homography instead (diag_charuco's side*_stock_px columns).
#   python3 2026-12-06-cam1width-byid.py A.csv CAMERA [types.txt]
import csv, math, os, sys
from collections import defaultdict
def dpl(p,a,b):
    dx,dy=b[0]-a[0],b[1]-a[1]; return abs((p[0]-a[0])*dy-(p[1]-a[1])*dx)/math.hypot(dx,dy)
cam=sys.argv[2]
g=defaultdict(list)
for r in csv.DictReader(open(sys.argv[1])):
    if r['camera']!=cam: continue
    w=[(float(r['wx%d'%k]),float(r['wy%d'%k])) for k in range(4)]
    for s in (0,1):
        d=0.5*(dpl(w[(s+2)%4],w[s],w[(s+1)%4])+dpl(w[(s+3)%4],w[s],w[(s+1)%4]))/6
        off=0.5*(float(r['side%d_px'%s])+float(r['side%d_px'%(s+2)]))
        g[int(r['id'])].append((d,off,s,float(r['view_deg']),int(r['frame'])))
def fit(pts):
    n=len(pts); mx=sum(p[0] for p in pts)/n; my=sum(p[1] for p in pts)/n
    sxx=sum((p[0]-mx)**2 for p in pts)
    b=sum((p[0]-mx)*(p[1]-my) for p in pts)/sxx if sxx>0 else float('nan')
    res=[p[1]-my-b*(p[0]-mx) for p in pts]; sd=math.sqrt(sum(x*x for x in res)/max(n-2,1))
    return mx,my,b,sd/math.sqrt(sxx) if sxx>0 else float('nan')
print('id  n  mean depth  mean offset  within-id slope px/px (se)  [pair 0/2 | pair 1/3 offsets]')
num=den=0
for i in sorted(g):
    pts=g[i]
    mx,my,b,se=fit(pts)
    p0=[p[1] for p in pts if p[2]==0]; p1=[p[1] for p in pts if p[2]==1]
    print('%2d %3d  %.2f  %+.3f  %+.4f (%.4f)  [%+.3f | %+.3f]'%(i,len(pts),mx,my,b,se,sum(p0)/max(len(p0),1),sum(p1)/max(len(p1),1)))
    if se==se and se>0: num+=b/se**2; den+=1/se**2
print('pooled within-id slope %+.4f (se %.4f)'%(num/den,1/math.sqrt(den)))
allp=[p for i in g for p in g[i]]
print('overall slope (across ids) %+.4f'%fit(allp)[2])

if len(sys.argv) > 3:
    types = [[x for x in l.strip().split(',') if x in ('I', 'P', 'B')][0] for l in open(sys.argv[3]) if l.strip()]
    mx, my, b, _ = fit(allp)
    a = my - b * mx
    print('trend: offset = %+.3f %+.4f * depth' % (a, b))
    frames = defaultdict(list)
    for p in allp:
        frames[p[4]].append(p[1] - a - b * p[0])
    for f in sorted(frames):
        print('frame %3d %s residual %+.3f (%d pairs)' % (f, types[f], sum(frames[f]) / len(frames[f]), len(frames[f])))

within = []  # (depth difference, offset difference, view) per marker
for r in csv.DictReader(open(sys.argv[1])):
    if r['camera'] != cam:
        continue
    w = [(float(r['wx%d' % k]), float(r['wy%d' % k])) for k in range(4)]
    d, o = [], []
    for s in (0, 1):
        d.append(0.5 * (dpl(w[(s + 2) % 4], w[s], w[(s + 1) % 4]) + dpl(w[(s + 3) % 4], w[s], w[(s + 1) % 4])) / 6)
        key = 'side%d_stock_px' if os.environ.get('STOCK') else 'side%d_px'
        o.append(0.5 * (float(r[key % s]) + float(r[key % (s + 2)])))
    if any(math.isnan(x) for x in o):
        continue
    within.append((d[0] - d[1], o[0] - o[1], float(r['view_deg'])))
for name, sel in [('all', lambda v: True), ('view < 50', lambda v: v < 50), ('view >= 50', lambda v: v >= 50)]:
    xy = [(x, y) for x, y, v in within if sel(v)]
    if len(xy) < 3:
        continue
    sxx = sum(x * x for x, _ in xy)
    b = sum(x * y for x, y in xy) / sxx
    sd = math.sqrt(sum((y - b * x) ** 2 for x, y in xy) / (len(xy) - 1))
    print('within-marker slope, %s: %+.4f px/px (se %.4f, %d markers)' % (name, b, sd / math.sqrt(sxx), len(xy)))
