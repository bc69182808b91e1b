# window2: cmp_acc (usage: python3 THIS DEFAULT_FILE SWITCH_FILE; see 2026-12-07-window2.md)
import sys, difflib
def load(p):
    out=[]
    for l in open(p):
        t=l.split(); c=list(map(float,t[1:]))
        out.append((int(t[0]),c))
    return out
a=load(sys.argv[1]); b=load(sys.argv[2])
ka=[(i,round(sum(c[0::2])/4),round(sum(c[1::2])/4)) for i,c in a]
kb=[(i,round(sum(c[0::2])/4),round(sum(c[1::2])/4)) for i,c in b]
sm=difflib.SequenceMatcher(None,ka,kb,autojunk=False)
md=0; nd=0; n=0; onlya=[]; onlyb=[]
diffs=[]
for op,i1,i2,j1,j2 in sm.get_opcodes():
    if op=='equal':
        for i,j in zip(range(i1,i2),range(j1,j2)):
            d=max(abs(x-y) for x,y in zip(a[i][1],b[j][1])); n+=1
            diffs.append(d)
            if d>1e-9: nd+=1
            md=max(md,d)
    else:
        onlya+=list(range(i1,i2)); onlyb+=list(range(j1,j2))
import math
diffs.sort()
print("default %d switch %d matched %d differ %d max diff %.4f px; 99th pct %.4f; only default %d only switch %d"%(len(a),len(b),n,nd,md,diffs[int(0.99*len(diffs))],len(onlya),len(onlyb)))
def side(c):
    xs=c[0::2]; ys=c[1::2]
    return sum(math.hypot(xs[i]-xs[(i+1)%4],ys[i]-ys[(i+1)%4]) for i in range(4))/4
for i in onlya: print(" only default: line %d id %d side %.1f"%(i,a[i][0],side(a[i][1])))
for j in onlyb: print(" only switch: line %d id %d side %.1f"%(j,b[j][0],side(b[j][1])))
print("only-switch entries with a same-id default entry nearby (centre within 3 px):")
for j in onlyb:
    cb=(sum(b[j][1][0::2])/4,sum(b[j][1][1::2])/4)
    best=None
    for i in onlya:
        if a[i][0]!=b[j][0]: continue
        ca=(sum(a[i][1][0::2])/4,sum(a[i][1][1::2])/4)
        if math.hypot(ca[0]-cb[0],ca[1]-cb[1])<3:
            best=max(abs(x-y) for x,y in zip(a[i][1],b[j][1]))
    print("  line %d id %d: %s"%(j,b[j][0],"new marker" if best is None else "moved, max corner diff %.3f px"%best))
