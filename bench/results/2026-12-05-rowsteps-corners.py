# Issue 15, rowsteps: corners' offsets along the inward diagonal from the truth, by corner angle, from
# MCMT_TRUTH_DUMP files (2026-12-05-rowsteps-truth-dump.patch) of four runs (paths below).
import math, collections
def load(p):
    d={}
    for l in open(p):
        f=l.split(); key=(f[0],f[1],f[2])
        d[key]=(float(f[3]),[float(x) for x in f[6:14]],[float(x) for x in f[15:23]])
    return d
runs=[('main','/tmp/rs_acc/t_0'),('column rays','/tmp/rs_acc/t_c'),('row steps','/tmp/rs_clean/t_f'),('row steps, no sine gate','/tmp/rs_acc/t_1'),('row steps, no gates','/tmp/rs_acc/t_1u')]
R={n:load(p) for n,p in runs}
keys=[k for k in R['main'] if all(k in r for r in R.values())]
agg=collections.defaultdict(lambda: collections.defaultdict(list))
for k in keys:
    t=R['main'][k][1]; P=[(t[2*i],t[2*i+1]) for i in range(4)]
    cx=sum(p[0] for p in P)/4; cy=sum(p[1] for p in P)/4
    for i in range(4):
        a=P[i]; b=P[(i+1)%4]; c=P[(i+3)%4]
        v1=(b[0]-a[0],b[1]-a[1]); v2=(c[0]-a[0],c[1]-a[1])
        ang=math.degrees(math.acos((v1[0]*v2[0]+v1[1]*v2[1])/math.hypot(*v1)/math.hypot(*v2)))
        off=abs(ang-90); cls='0-10' if off<10 else '10-20' if off<20 else '20-30' if off<30 else '30-45' if off<45 else '45-90'
        acute = 'acute' if ang<90 else 'obtuse'
        ux,uy=cx-a[0],cy-a[1]; L=math.hypot(ux,uy); ux/=L; uy/=L
        for n in R:
            g=R[n][k][2]
            agg[(cls,acute)][n].append((g[2*i]-a[0])*ux+(g[2*i+1]-a[1])*uy)
print("markers in all four runs:", len(keys))
print("| corner angle off 90 deg | acute / obtuse | corners | " + " | ".join(n for n,_ in runs) + " |")
print("|---|---|---|" + "---|"*len(runs))
for key in sorted(agg):
    v=agg[key]; n=len(v['main'])
    print("| %s | %s | %d | "%(key+(n,)) + " | ".join("%+.3f"%(sum(v[m])/n) for m,_ in runs) + " |")
