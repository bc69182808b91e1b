import sys, math, collections
exec(open(__import__('os').path.join(__import__('os').path.dirname(__file__), '2026-12-06-skewtrace-halves.py')).read().split('# pair halves')[0].replace("f=args[1]","f=args[1]; args=args[:2]").replace("elif t[0]=='TT'","elif t[0]=='TTX'"))
lo,hi,alo,ahi=(float(x) for x in sys.argv[2:6]); which=sys.argv[6]
lastc={}
img=-1
for line in open(f):
    t=line.split()
    if not t: continue
    if t[0]=='IMG': img+=1
    elif t[0]=='TC':
        ar,sk,rnd,col=map(int,t[1:5]); px,py,nx,ny,e=map(float,t[5:10]); fr=[float(x) for x in t[12:21]]+[float(x) for x in t[22:29]] if len(t)>20 else None
        cat='skew' if sk else ('short' if ar else 'other')
        if which!='all' and cat!=which: continue
        best=None
        for (id,spx,ang,c,ss) in truth.get(img,[]):
            for k,(a,b,n,L) in enumerate(ss):
                if abs(n[0]*nx+n[1]*ny)<0.9: continue
                d=n[0]*(px-a[0])+n[1]*(py-a[1])
                tt=((px-a[0])*(b[0]-a[0])+(py-a[1])*(b[1]-a[1]))/L/L
                if abs(d)<2 and -0.1<tt<1.1:
                    if best is None or abs(d)<abs(best[0]): best=(d,id,k,tt,spx,ang,c)
        if best is None: continue
        d,id,k,tt,spx,ang,c=best
        if not(lo<=spx<hi and alo<=ang<=ahi) or (img,id) not in dets: continue
        A0=angle(c,k); A1=angle(c,(k+1)%4)
        ta = tt if A0<A1 else 1-tt   # from the acute end
        lastc[(img,id,k,col)]=(ta,d,e,fr)
b=collections.defaultdict(list)
for v in lastc.values(): b[min(7,int(v[0]*8))].append(v)
print(f"{which} {lo}-{hi}px {alo}-{ahi}deg columns from the acute end: edge - truth px (column e)")
for k in sorted(b):
    L=b[k]; F=[x[3] for x in L if x[3] and x[3][0]==1]
    fm=[sum(f[i] for f in F)/max(1,len(F)) for i in range(16)]
    print(f"  col {k}: n {len(L):3d}  {sum(x[1] for x in L)/len(L):+.4f}   e {sum(x[2] for x in L)/len(L):+.4f}  free: n {len(F)} e {fm[1]:+.3f} sig {fm[2]:.3f} L0 {fm[3]:.1f} L1 {fm[4]:.1f} S1 {fm[5]:.1f} gamma {fm[8]:.2f} | whole sig {fm[9]:.3f} L0 {fm[10]:.1f} L1 {fm[11]:.1f} S1 {fm[12]:.1f} g {fm[15]:.2f}")
