#!/usr/bin/env python3
"""Issue 15 (helper skewmix): per side of a bench_imaging_maps MCMT_IMAGING_DUMP (one condition), by the side's smaller true corner angle at its two ends: mean offset / acute end / obtuse end (px, outward +).
With B: A less B paired."""
import math, sys
from collections import defaultdict
from corner_dump import marker_rows, truth_and_error
def markers(path):
    return {key: truth_and_error(c) for key, c in marker_rows(path).items()}
def ang(t,k):
    p,u,w=t[k],t[(k-1)%4],t[(k+1)%4]
    v1=(u[0]-p[0],u[1]-p[1]); v2=(w[0]-p[0],w[1]-p[1])
    return math.degrees(math.acos(max(-1,min(1,(v1[0]*v2[0]+v1[1]*v2[1])/math.hypot(*v1)/math.hypot(*v2)))))
def sides(t,e):
    cx=sum(p[0] for p in t)/4; cy=sum(p[1] for p in t)/4; out=[]
    for k in range(4):
        j=(k+1)%4; a,b=t[k],t[j]; L=math.hypot(b[0]-a[0],b[1]-a[1]); n=((b[1]-a[1])/L,-(b[0]-a[0])/L)
        if n[0]*((a[0]+b[0])/2-cx)+n[1]*((a[1]+b[1])/2-cy)<0: n=(-n[0],-n[1])
        ek=e[k][0]*n[0]+e[k][1]*n[1]; ej=e[j][0]*n[0]+e[j][1]*n[1]
        ak,aj=ang(t,k),ang(t,j)
        acute,obt=(ek,ej) if ak<aj else (ej,ek)
        out.append((min(ak,aj),(ek+ej)/2,acute,obt))
    return out
A=markers(sys.argv[1]); B=markers(sys.argv[2]) if len(sys.argv)>2 else None
bins=[(0,45),(45,55),(55,65),(65,75),(75,90)]
acc=defaultdict(list)
for key,(t,e) in A.items():
    if B is not None and key not in B: continue
    s=sides(t,e); sb=sides(*B[key]) if B else None
    for i,(a,m,ac,ob) in enumerate(s):
        if sb: m-=sb[i][1]; ac-=sb[i][2]; ob-=sb[i][3]
        for lo,hi in bins:
            if lo<=a<hi: acc[(lo,hi)].append((m,ac,ob))
        acc['all'].append((m,ac,ob))
for k in bins+['all']:
    v=acc[k]; n=len(v)
    if not n: continue
    print('| %s | %d | %+.4f | %+.4f | %+.4f |'%(k if k=='all' else '%d-%d'%k,n,*[sum(x[i] for x in v)/n for i in range(3)]))
