import sys, collections
rows=[]
for f in sys.argv[1:]:
    rows+=[l.split() for l in open(f) if l.startswith('side ')]
b=collections.defaultdict(lambda: [0,0.0,0.0,0.0,0.0,0.0])
R=collections.defaultdict(list)
e=collections.defaultdict(list)
for i in range(0,len(rows)-3,4):
    m=rows[i:i+4]
    ang=float(m[0][5]); size=float(m[0][3])
    L=[float(r[7]) for r in m]; O=[float(r[11]) for r in m]; X=[float(r[9]) for r in m]
    short = 0 if L[0]+L[2] < L[1]+L[3] else 1
    so=(O[short]+O[short+2])/2; lo=(O[1-short]+O[3-short])/2
    for key in (f"{int(ang//15)*15:2d}-{int(ang//15)*15+15} deg", 'all'):
        R[key].append(float(m[0][13]) if len(m[0])>13 else 0.0)
        x=b[key]; x[0]+=1; x[1]+=so; x[2]+=lo; x[3]+=(so+lo)/2; x[4]+=((so+lo)/2)**2
    for k in range(4):
        e[int(X[k]//2)*2].append(O[k])
print("band | n | short sides (along compressed) | long sides | marker mean (se)")
for k in sorted(b):
    n,a,c,d,d2,_=b[k]; import math; se=math.sqrt(max(d2/n-(d/n)**2,0)/n)
    print(f"{k:10s} | {n:4d} | {a/n:+.4f} | {c/n:+.4f} | {d/n:+.4f} ({se:.4f}) | radial {sum(R[k])/n:+.4f}")
print("side offset by extent across:", " ".join(f"{k}-{k+2}px {sum(v)/len(v):+.4f} ({len(v)})" for k,v in sorted(e.items())))
