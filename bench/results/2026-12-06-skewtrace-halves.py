import sys, math, collections
# usage: an.py trace.txt [minpx maxpx minang maxang] [flag filter: short|skew|other|all]
args=sys.argv
f=args[1]; lo,hi,alo,ahi=(float(x) for x in args[2:6]) if len(args)>5 else (30,45,55,70)
which=args[6] if len(args)>6 else 'short'
truth={}; img=-1; last={}
dets={}
def sides(c):
    cx=sum(p[0] for p in c)/4; cy=sum(p[1] for p in c)/4
    out=[]
    for k in range(4):
        a=c[k]; b=c[(k+1)%4]; dx=b[0]-a[0]; dy=b[1]-a[1]; L=math.hypot(dx,dy)
        n=(dy/L,-dx/L)
        mx=(a[0]+b[0])/2; my=(a[1]+b[1])/2
        if n[0]*(mx-cx)+n[1]*(my-cy)<0: n=(-n[0],-n[1])
        out.append((a,b,n,L))
    return out
def angle(c,k):
    p=c[k]; a=c[(k+3)%4]; b=c[(k+1)%4]
    ux,uy=a[0]-p[0],a[1]-p[1]; vx,vy=b[0]-p[0],b[1]-p[1]
    return math.degrees(math.acos((ux*vx+uy*vy)/math.hypot(ux,uy)/math.hypot(vx,vy)))
for line in open(f):
    t=line.split()
    if not t: continue
    if t[0]=='IMG': img+=1; truth[img]=[]
    elif t[0]=='TRUTH':
        v=list(map(float,t[1:])); c=[(v[3+2*k],v[4+2*k]) for k in range(4)]
        truth[img].append((int(v[0]),v[1],v[2],c,sides(c)))
    elif t[0]=='DET':
        v=list(map(float,t[1:])); dets[(img,int(v[0]))]=[(v[1+2*k],v[2+2*k]) for k in range(4)]
    elif t[0]=='TT':
        ar,sk,rnd,half=map(int,t[1:5]); px,py,wx,wy,nx,ny,e,al,sg,fsg=map(float,t[5:15])
        cat='skew' if sk else ('short' if ar else 'other')
        best=None
        for (id,spx,ang,c,ss) in truth.get(img,[]):
            for k,(a,b,n,L) in enumerate(ss):
                if abs(n[0]*nx+n[1]*ny)<0.9: continue
                d=n[0]*(px-a[0])+n[1]*(py-a[1])
                tt=((px-a[0])*(b[0]-a[0])+(py-a[1])*(b[1]-a[1]))/L/L
                if abs(d)<2 and -0.1<tt<1.1:
                    if best is None or abs(d)<abs(best[0]): best=(d,id,k,tt,spx,ang,c,n,a)
        if best is None: continue
        d,id,k,tt,spx,ang,c,n,a=best
        dw=n[0]*(wx-a[0])+n[1]*(wy-a[1])
        last[(img,id,k,cat,half)]=(rnd,d,dw,tt,spx,ang,c,e,sg,fsg)
# pair halves
res=collections.defaultdict(list)
for (img,id,k,cat,half),v in last.items():
    if half!=0 or (which!='all' and cat!=which): continue
    o=last.get((img,id,k,cat,1))
    if not o: continue
    r0,d0,dw0,t0,spx,ang,c,e0,s0,fs=v; r1,d1,dw1,t1,_,_,_,e1,s1,_=o
    if not(lo<=spx<hi and alo<=ang<=ahi): continue
    if (img,id) not in dets: continue
    A0=angle(c,k); A1=angle(c,(k+1)%4)  # corner at start (half 0 end) and end
    # acute end: the smaller angle
    if A0<A1: acute=(d0,t0,dw0,e0,s0); obt=(d1,t1,dw1,e1,s1); amin=A0; amax=A1
    else: acute=(d1,t1,dw1,e1,s1); obt=(d0,t0,dw0,e0,s0); amin=A1; amax=A0
    res['acute'].append(acute); res['obtuse'].append(obt); res['ang'].append((amin,amax,spx,ang,fs))
n=len(res['acute'])
def m(lst,i): return sum(x[i] for x in lst)/max(1,len(lst))
print(f"{which} sides {lo}-{hi}px {alo}-{ahi}deg: {n} sides")
if n:
    print(" half    edge-truth px   along   whole-line-truth px   half e   half sigma")
    for nm in ('acute','obtuse'):
        L=res[nm]; print(f" {nm:7s} {m(L,0):+.4f} (sd {math.sqrt(max(0,m([(x[0]**2,) for x in L],0)-m(L,0)**2)):.3f})  {m(L,1):.3f}   {m(L,2):+.4f}   {m(L,3):+.4f}  {m(L,4):.3f}")
    print(f" acute-obtuse {m(res['acute'],0)-m(res['obtuse'],0):+.4f} px; corner angles {m(res['ang'],0):.1f}/{m(res['ang'],1):.1f}, side {m(res['ang'],2):.1f} px, whole sigma {m(res['ang'],4):.3f}")
