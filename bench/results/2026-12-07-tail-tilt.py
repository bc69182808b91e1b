#!/usr/bin/env python3
"""Issue 15 (helper tail): per side role (as 2026-12-07-seeds13-split.py) and view band, the mean offset and the
end difference (top / bottom: near end - far end, half; near / far: corner k - corner k+1, half), px along the
outward normal, from a bench_imaging_maps MCMT_IMAGING_DUMP. With B: A less B, paired."""
import math, sys
from collections import defaultdict
from corner_dump import marker_rows, truth_and_error
def markers(path):
    return {key: (*truth_and_error(c), float(c[0]['view_deg'])) for key, c in marker_rows(path).items()}
def feats(t, e):
    cx = sum(p[0] for p in t) / 4; cy = sum(p[1] for p in t) / 4
    S=[]
    for k in range(4):
        j=(k+1)%4; a,b=t[k],t[j]
        L=math.hypot(b[0]-a[0],b[1]-a[1]); n=((b[1]-a[1])/L,-(b[0]-a[0])/L)
        if n[0]*((a[0]+b[0])/2-cx)+n[1]*((a[1]+b[1])/2-cy)<0: n=(-n[0],-n[1])
        ek=e[k][0]*n[0]+e[k][1]*n[1]; ej=e[j][0]*n[0]+e[j][1]*n[1]
        S.append(dict(L=L,ek=ek,ej=ej,k=k,j=j))
    near = 1 if S[1]['L']>=S[3]['L'] else 3
    far = 4-near
    nearc = {near, (near+1)%4}  # corners of the near side
    res={}
    for k,role in ((0,'top'),(2,'bottom'),(near,'near'),(far,'far')):
        s=S[k]
        off=(s['ek']+s['ej'])/2
        if role in ('top','bottom'):
            # near end minus far end
            en = s['ek'] if s['k'] in nearc else s['ej']; ef = s['ej'] if s['k'] in nearc else s['ek']
            tilt=(en-ef)/2
        else:
            tilt=(s['ek']-s['ej'])/2 if True else 0
        res[role]=(off,tilt)
    return res
A=markers(sys.argv[1]); B=markers(sys.argv[2]) if len(sys.argv)>2 else None
acc=defaultdict(list)
for key,(t,e,view) in A.items():
    if B is not None and key not in B: continue
    r=feats(t,e); rb=feats(*B[key][:2]) if B else None
    band='0-40' if view<40 else '40-60' if view<60 else '60-90'
    for role,(o,ti) in r.items():
        if rb: o-=rb[role][0]; ti-=rb[role][1]
        for b in ('all',band):
            acc[(role,b,'off')].append(o); acc[(role,b,'tilt')].append(ti)
def ms(v):
    n=len(v); m=sum(v)/n; se=math.sqrt(sum((x-m)**2 for x in v)/max(n-1,1)/n); return m,se,n
print('| role | band | n | offset px (se) | end difference px (se): top/bottom near end - far end |')
print('|---|---|---|---|---|')
for role in ('top','bottom','near','far'):
    for b in ('all','0-40','40-60','60-90'):
        m,se,n=ms(acc[(role,b,'off')]); m2,se2,_=ms(acc[(role,b,'tilt')])
        print('| %s | %s | %d | %+.4f (%.4f) | %+.4f (%.4f) |'%(role,b,n,m,se,m2,se2))
