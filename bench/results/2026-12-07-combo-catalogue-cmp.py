import sys, math
def load(f):
    d={}
    for l in open(f):
        v=l.split(); d[(int(v[1]),int(v[2]))]=list(map(float,v[3:]))
    return d
def offs(x):
    t=[(x[2+2*k],x[3+2*k]) for k in range(4)]; f=[(x[10+2*k],x[11+2*k]) for k in range(4)]
    cx=sum(p[0] for p in t)/4; cy=sum(p[1] for p in t)/4
    # outward normal of side s (k -> k+1): perpendicular pointing away from centre
    def n(s):
        a=t[s]; b=t[(s+1)%4]; dx=b[0]-a[0]; dy=b[1]-a[1]; L=math.hypot(dx,dy); nx,ny=dy/L,-dx/L
        mx=(a[0]+b[0])/2-cx; my=(a[1]+b[1])/2-cy
        if nx*mx+ny*my<0: nx,ny=-nx,-ny
        return nx,ny
    o=[]
    for k in range(4):
        e=(f[k][0]-t[k][0],f[k][1]-t[k][1]); s=0
        for side in ((k+3)%4,k):
            nx,ny=n(side); s+=0.5*(nx*e[0]+ny*e[1])
        o.append(s)
    sides=[math.hypot(t[(k+1)%4][0]-t[k][0],t[(k+1)%4][1]-t[k][1]) for k in range(4)]
    return o,f,sides
a=load(sys.argv[1]); b=load(sys.argv[2])
rows=[]; tot_a=tot_b=0; n=0
for k in a:
    if k not in b: print('missing in b',k); continue
    oa,fa,sd=offs(a[k]); ob,fb,_=offs(b[k])
    mv=max(math.hypot(fb[i][0]-fa[i][0],fb[i][1]-fa[i][1]) for i in range(4))
    rows.append((mv,k,a[k][0],a[k][1],oa,ob,sd)); tot_a+=sum(oa); tot_b+=sum(ob); n+=4
for k in b:
    if k not in a: print('missing in a',k)
rows.sort(key=lambda r:-r[0])
print("mean offset %.4f -> %.4f (%d corners)"%(tot_a/n,tot_b/n,n))
for r in rows[:int(sys.argv[3]) if len(sys.argv)>3 else 10]:
    print("move %.3f img %d id %3d side %.1f (short %.1f long %.1f) view %.1f  off %s -> %s  contrib %+.4f"%(r[0],r[1][0],r[1][1],r[2],min(r[6]),max(r[6]),r[3],
      " ".join("%+.3f"%x for x in r[4])," ".join("%+.3f"%x for x in r[5]),(sum(r[5])-sum(r[4]))/n))
for th in (1e-3,0.01,0.05):
    print(">%g: %d"%(th,sum(1 for r in rows if r[0]>th)))
