#!/usr/bin/env python3
"""Issue 15 (helper tail): mean error of the quad's acute angles (detected - true, deg; + = too square) per
acute-angle bin and view band, from a bench_imaging_maps MCMT_IMAGING_DUMP. With B: A less B, paired."""
import math, sys
from collections import defaultdict
from corner_dump import marker_rows, truth_and_error
def load(p):
    out={}
    for key,c in marker_rows(p).items():
        t,e=truth_and_error(c)
        out[key]=(t,[(t[k][0]+e[k][0],t[k][1]+e[k][1]) for k in range(4)],float(c[0]['view_deg']))
    return out
def angles(q):
    a=[]
    for k in range(4):
        p,u,w=q[k],q[(k-1)%4],q[(k+1)%4]
        v1=(u[0]-p[0],u[1]-p[1]); v2=(w[0]-p[0],w[1]-p[1])
        a.append(math.degrees(math.acos((v1[0]*v2[0]+v1[1]*v2[1])/math.hypot(*v1)/math.hypot(*v2))))
    return a
A=load(sys.argv[1]); B=load(sys.argv[2]) if len(sys.argv)>2 else None
acc=defaultdict(list)
for key,(t,d,view) in A.items():
    if B is not None and key not in B: continue
    at=angles(t); ad=angles(d)
    if B: ab=angles(B[key][1])
    k=min(range(4),key=lambda i:at[i])
    ac=min(at[k],at[(k+2)%4])
    # acute corners: k and k+2 (opposite) ; error = detected - true averaged over the two acute corners
    err=0.5*((ad[k]-at[k])+(ad[(k+2)%4]-at[(k+2)%4]))
    if B: err-=0.5*((ab[k]-at[k])+(ab[(k+2)%4]-at[(k+2)%4]))
    ab_=int(at[k]//5)*5
    for b in ('all','view %s'%('0-40' if view<40 else '40-60' if view<60 else '60-90'),'acute %d-%d'%(ab_,ab_+5)):
        acc[b].append(err)
for b in sorted(acc):
    v=acc[b]; n=len(v); m=sum(v)/n; se=math.sqrt(sum((x-m)**2 for x in v)/max(n-1,1)/n)
    print('| %s | %d | %+.3f (%.3f) |'%(b,n,m,se))
