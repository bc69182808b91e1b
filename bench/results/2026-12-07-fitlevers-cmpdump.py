import sys, math
def load(p):
    out=[]
    for l in open(p):
        t=l.split()
        if len(t)==9: out.append((tuple(t[:1]), [float(x) for x in t[1:9]]))
        elif len(t)==13: out.append((tuple(t[:5]), [float.fromhex(x) for x in t[5:13]]))
    return out
a=load(sys.argv[1]); b=load(sys.argv[2])
from collections import defaultdict
da=defaultdict(list); db=defaultdict(list)
for k,c in a: da[k].append(c)
for k,c in b: db[k].append(c)
moves=[]; una=0
for k in da:
    bs=list(db.get(k,[]))
    for ca in da[k]:
        best=None
        for j,cb in enumerate(bs):
            m=max(math.hypot(ca[2*i]-cb[2*i],ca[2*i+1]-cb[2*i+1]) for i in range(4))
            if best is None or m<best[0]: best=(m,j)
        if best is None or best[0]>5: una+=1; continue
        bs.pop(best[1]); moves.append(best[0])
moves.sort(); n=len(moves)
print(f"lines {len(a)} vs {len(b)}, matched {n}, unmatched {una}; max corner move px: median {moves[n//2]:.2e} p90 {moves[int(.9*n)]:.4f} p99 {moves[int(.99*n)]:.4f} max {moves[-1]:.4f}; >0.01 {sum(m>0.01 for m in moves)} >0.05 {sum(m>0.05 for m in moves)} identical {sum(m==0 for m in moves)}")
