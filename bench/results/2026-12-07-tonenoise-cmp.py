import sys
def load(p):
    cams=[]; last=10**9
    for line in open(p):
        t=line.split()
        fr=int(t[0])
        if fr<last and (not cams or fr<last): 
            if fr<last: cams.append([])
        last=fr
        cams[-1].append(t)
    return cams
a=load(sys.argv[1]); b=load(sys.argv[2])
for c,(ca,cb) in enumerate(zip(a,b)):
    n=min(len(ca),len(cb)); moved=0; mx=0; dig=0; worst=None; same_set = all(x[:3]==y[:3] for x,y in zip(ca,cb)) and len(ca)==len(cb)
    hist={}
    for x,y in zip(ca[:n],cb[:n]):
        if x[:3]!=y[:3]: continue
        d=max(abs(float(p)-float(q)) for p,q in zip(x[3:11],y[3:11]))
        if d>0: moved+=1
        if d>mx: mx=d; worst=(x[0],x[1])
        import math
        k= -99 if d==0 else int(math.floor(math.log10(d)))
        hist[k]=hist.get(k,0)+1
        if x[11:]!=y[11:]: dig+=1
    print(f"cam{c}: entries {len(ca)}/{len(cb)} same (frame,id,ok) sequence {same_set}; corners moved {moved}/{n}, max {mx:.3g} px at frame,id {worst}; digests differ {dig}; log10 hist {sorted(hist.items())}")
