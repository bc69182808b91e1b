import sys, math
def pct(a,p):
    a=sorted(a); 
    if not a: return float('nan')
    k=(len(a)-1)*p/100; f=int(k); c=min(f+1,len(a)-1); return a[f]+(a[c]-a[f])*(k-f)
def pc(a): return '%.2f/%.2f/%.2f'%(pct(a,10),pct(a,50),pct(a,90))
def load(fn):
    rows=[]
    for line in open(fn):
        if "WMFIT" not in line: continue
        line=line[line.index("WMFIT"):]
        t=line.split(); d={}; i=1
        while i<len(t):
            if t[i]=='res':
                d['res']=[float(x) for x in t[i+1:i+17]]; break
            d[t[i]]=float(t[i+1]); i+=2
        rows.append(d)
    return rows
for fn in sys.argv[1:]:
    R=load(fn)
    print(fn, len(R), 'single share %.2f'%(sum(r['single'] for r in R)/len(R)))
    for lo,hi in [(1,1.5),(1.5,2),(2,2.5),(2.5,4)]:
        A=[r for r in R if lo<=r['cell']<hi]
        S=[r for r in A if r['single']==0]
        if not S: continue
        qc=[r['q']/r['cell'] for r in S]; s1=[(r['S1']-r['L0'])/(r['L1']-r['L0']) for r in S]; s2=[(r['S2']-r['L0'])/(r['L1']-r['L0']) for r in S]
        sig=[r['sigma'] for r in S]; g=[r['gamma'] for r in S]; pap=[(r['paper']-r['L0'])/(r['L1']-r['L0']) for r in S if r['paper']>0]
        w=[r['w'] for r in S]
        print(' cell %.1f-%.1f fits %d (single %.2f) q/c %s S1n %s S2n %s P %s sigma %s gamma %s qbound %.2f w>0 %.2f'%(lo,hi,len(S),1-len(S)/len(A),pc(qc),pc(s1),pc(s2),pc(pap),pc(sig),pc(g),sum(1 for x in qc if x<0.21)/len(qc),sum(1 for x in w if x>0)/len(w)))
    S=[r for r in R if r['single']==0 and 1.5<=r['cell']<3]
    n=16
    mean=[]; rms=[]
    for b in range(n):
        v=[r['res'][b] for r in S if not math.isnan(r['res'][b])]
        mean.append(sum(v)/len(v) if v else float('nan')); rms.append(math.sqrt(sum(x*x for x in v)/len(v)) if v else float('nan'))
    print(' (u-e)/c  ', ' '.join('%6.2f'%(-1.5+0.25*b+0.125) for b in range(n)))
    print(' res mean ', ' '.join('%6.3f'%x for x in mean))
    print(' res rms  ', ' '.join('%6.3f'%x for x in rms))
