# Issue 15, rowsteps: per-side offsets from the true lines (outward +) on bench_accuracy --quick, from
# MCMT_TRUTH_DUMP files (2026-12-05-rowsteps-truth-dump.patch) of main, MCMT_COLUMN_RAYS=1 and MCMT_ROW_STEPS=1 (paths below).
import math, sys
def load(p):
    d={}
    for l in open(p):
        f=l.split()
        key=(f[0],f[1],f[2]); ang=float(f[3]); side=float(f[4])
        t=[float(x) for x in f[6:14]]; g=[float(x) for x in f[15:23]]
        d[key]=(ang,side,t,g)
    return d
def side_info(t, g):
    P=[(t[2*k],t[2*k+1]) for k in range(4)]; G=[(g[2*k],g[2*k+1]) for k in range(4)]
    cx=sum(p[0] for p in P)/4; cy=sum(p[1] for p in P)/4
    out=[]
    for k in range(4):
        a=P[k]; b=P[(k+1)%4]; dx=b[0]-a[0]; dy=b[1]-a[1]; L=math.hypot(dx,dy); nx,ny=dy/L,-dx/L
        if (a[0]-cx)*nx+(a[1]-cy)*ny<0: nx,ny=-nx,-ny
        o0=(G[k][0]-a[0])*nx+(G[k][1]-a[1])*ny; o1=(G[(k+1)%4][0]-a[0])*nx+(G[(k+1)%4][1]-a[1])*ny
        # depth: distance from the opposite side's midpoint to this side's line, / 8 cells
        c=P[(k+2)%4]; d=P[(k+3)%4]; mx=(c[0]+d[0])/2; my=(c[1]+d[1])/2
        depth=abs((mx-a[0])*nx+(my-a[1])*ny)/8
        # corner angles at a and b (deg)
        def ang(p,q,r):
            v1=(q[0]-p[0],q[1]-p[1]); v2=(r[0]-p[0],r[1]-p[1])
            return math.degrees(math.acos((v1[0]*v2[0]+v1[1]*v2[1])/math.hypot(*v1)/math.hypot(*v2)))
        A0=ang(a,b,P[(k+3)%4]); A1=ang(b,a,P[(k+2)%4])
        out.append(((o0+o1)/2, depth, min(A0,A1), o0, o1))
    return out
runs={n:load(p) for n,p in [('main','/tmp/rs_acc/t_0'),('column','/tmp/rs_acc/t_c'),('rowsteps','/tmp/rs_clean/t_f')]}
keys=[k for k in runs['main'] if all(k in r for r in runs.values())]
print("markers in all three:", len(keys))
# aggregate: 60-75 deg markers, sides by cell depth class and by min corner angle class
import collections
agg=collections.defaultdict(lambda: collections.defaultdict(list))
for k in keys:
    ang=runs['main'][k][0]
    band='0-40' if ang<40 else '40-60' if ang<60 else '60-75'
    for n,r in runs.items():
        _,_,t,g=r[k]
        for (o,depth,mina,o0,o1) in side_info(t,g):
            dc='cell>=3px' if depth>=3 else 'cell<3px'
            ac='acute<60' if mina<60 else 'acute60-75' if mina<75 else 'acute>=75'
            agg[(band,dc,ac)][n].append(o)
print("| view | side's cell depth | smaller end angle | sides | main mean / rms | column rays | row steps |")
print("|---|---|---|---|---|---|---|")
for key in sorted(agg):
    v=agg[key]; n=len(v['main'])
    print("| %s | %s | %s | %d | "%(key+(n,)) + " | ".join("%+.3f / %.3f"%(sum(v[m])/n,(sum(x*x for x in v[m])/n)**.5) for m in ('main','column','rowsteps'))+" |")
# steep marker with the largest inward move under column rays
best=None
for k in keys:
    if runs['main'][k][0]<60: continue
    sm=side_info(*runs['main'][k][2:]); sc=side_info(*runs['column'][k][2:])
    move=sum(a[0]-b[0] for a,b in zip(sm,sc))
    if best is None or move>best[0]: best=(move,k)
def show(k, why):
    print("\nmarker seed %s image %s id %s view %.1f deg side %.1f px (%s)"%(k+runs['main'][k][:2]+(why,)))
    print("| side | cell depth px | smaller end angle deg | main (end0 / end1) | column rays | row steps |")
    print("|---|---|---|---|---|---|")
    inf={n:side_info(*runs[n][k][2:]) for n in runs}
    for s in range(4):
        m=inf['main'][s]
        print("| %d | %.2f | %.0f | %+.3f (%+.3f / %+.3f) | %+.3f (%+.3f / %+.3f) | %+.3f (%+.3f / %+.3f) |"%((s,m[1],m[2])+tuple(x for n in ('main','column','rowsteps') for x in (inf[n][s][0],inf[n][s][3],inf[n][s][4]))))
show(best[1], "column rays move its sides inward by %.3f px in sum" % best[0])

cands=[]
for k in keys:
    if runs['main'][k][0]<60: continue
    sm=side_info(*runs['main'][k][2:]); sc=side_info(*runs['column'][k][2:]); sr=side_info(*runs['rowsteps'][k][2:])
    wide=[s for s in range(4) if sm[s][1]>=3]
    if not wide: continue
    colmove=sum(sm[s][0]-sc[s][0] for s in wide)
    cands.append((colmove,k))
cands.sort(reverse=True)
for c,k in cands[:3]: show(k, "column rays move its sides of cells >= 3 px inward by %.3f px in sum"%c)
