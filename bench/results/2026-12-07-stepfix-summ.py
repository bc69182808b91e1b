import sys, math
rows=[[float(x) for x in l.split()] for l in open(sys.argv[1])]
rows=[r for r in rows if math.isfinite(r[3])]
names="cell sig ex0 exu q0 qu oku okt du dt".split()
def pct(c,p): c=sorted(c); return c[min(len(c)-1,int(p*len(c)))]
print(sys.argv[1], len(rows))
for i,n in enumerate(names):
    c=[r[i] for r in rows if math.isfinite(r[i])]
    print("%4s"%n, " ".join("%8.4f"%pct(c,p) for p in (.1,.25,.5,.75,.9)), " mean %.4f"%(sum(c)/len(c)))
for th in (-0.05,0.0,0.05,0.1,0.15,0.2,0.3):
    sel=[r for r in rows if r[3]>th]
    print("exu>%.2f: %d (%.2f)"%(th,len(sel),len(sel)/len(rows)), "tie move per finite fit: %.4f"%(sum(r[9]-r[8] for r in sel if math.isfinite(r[9]-r[8]))/len(rows)))
for th in (0.3,0.4,0.5,0.6):
    sel=[r for r in rows if r[5]<th]
    print("qu<%.2f: %d (%.2f)"%(th,len(sel),len(sel)/len(rows)))
print("dip cells pct:", " ".join("%.3f"%pct([r[10] for r in rows],p) for p in (.1,.25,.5,.75,.9)))
print("dip - (q0+sig) cells pct:", " ".join("%.3f"%pct([r[10]-r[4]-r[1] for r in rows],p) for p in (.1,.25,.5,.75,.9)))
