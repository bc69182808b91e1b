# window2: cmp_bd (usage: python3 THIS DEFAULT_FILE SWITCH_FILE; see 2026-12-07-window2.md)
import sys
def load(p):
    d={}
    for l in open(p):
        t=l.split()
        key=tuple(int(x) for x in t[:5])
        d[key]=[float.fromhex(x) for x in t[5:]]
    return d
a=load(sys.argv[1]); b=load(sys.argv[2])
for mode in (0,1):
    ka={k for k in a if k[3]==mode}; kb={k for k in b if k[3]==mode}
    common=ka&kb
    md=max((max(abs(x-y) for x,y in zip(a[k],b[k])) for k in common),default=0)
    nd=sum(1 for k in common if max(abs(x-y) for x,y in zip(a[k],b[k]))>1e-9)
    print("mode",["accurate","fast"][mode],"default",len(ka),"switch",len(kb),"only default",len(ka-kb),"only switch",len(kb-ka),"common",len(common),"differ",nd,"max diff px %.4g"%md)
    for k in sorted(ka-kb): 
        c=a[k]; xs=c[0::2]; ys=c[1::2]
        import math
        side=sum(math.hypot(xs[i]-xs[(i+1)%4],ys[i]-ys[(i+1)%4]) for i in range(4))/4
        print("  only default: width %d cam %d frame %d id %d side %.1f px"%(k[0],k[1],k[2],k[4],side))
    for k in sorted(kb-ka): print("  only switch:",k)
