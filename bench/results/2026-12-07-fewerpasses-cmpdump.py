import sys, math
def load(p):
    d={}
    order=[]
    for l in open(p):
        t=l.split(); 
        if len(t)<9: continue
        order.append((t[0],[float(x) for x in t[1:9]]))
    return order
a=load(sys.argv[1]); b=load(sys.argv[2])
# match by id and nearest centre
used=set(); moves=[]; unmatched=0
for ida,ca in a:
    best=None
    for j,(idb,cb) in enumerate(b):
        if idb!=ida or j in used: continue
        m=max(math.hypot(ca[2*k]-cb[2*k],ca[2*k+1]-cb[2*k+1]) for k in range(4))
        if best is None or m<best[0]: best=(m,j)
    if best is None or best[0]>5: unmatched+=1; continue
    used.add(best[1]); moves.append(best[0])
moves.sort(); n=len(moves)
print("n %d unmatched %d/%d mean %.4f max %.3f >0.002 %d >0.005 %d >0.02 %d" % (n,unmatched,len(b)-len(used),sum(moves)/n,moves[-1],sum(m>0.002 for m in moves),sum(m>0.005 for m in moves),sum(m>0.02 for m in moves)))
