# per-side offset (px, outward +) of the refined corners' sides from the true sides; mean fitted levels
import sys, math
T=None; offs=[]; levels=[]; last_aes={}
for line in open(sys.argv[1]):
    f=line.split()
    if not f: continue
    if f[0]=='AES':
        last_aes[int(f[1])]=[float(x) for x in f[2:]]
    elif f[0]=='M': last_aes={}
    elif f[0]=='T': T=[(float(f[1+2*k]),float(f[2+2*k])) for k in range(4)]
    elif f[0]=='C':
        if f[1]!='1': continue
        C=[(float(f[2+2*k]),float(f[3+2*k])) for k in range(4)]
        cx=sum(p[0] for p in T)/4; cy=sum(p[1] for p in T)/4
        for k in range(4):
            a=T[k]; b=T[(k+1)%4]
            dx,dy=b[0]-a[0],b[1]-a[1]; L=math.hypot(dx,dy); nx,ny=dy/L,-dx/L
            if (a[0]-cx)*nx+(a[1]-cy)*ny<0: nx,ny=-nx,-ny
            d=lambda p:(p[0]-a[0])*nx+(p[1]-a[1])*ny
            offs.append(0.5*(d(C[k])+d(C[(k+1)%4])))
        for v in last_aes.values(): levels.append(v)
n=len(offs)
m=sum(offs)/n
print("sides %d mean offset %+.4f px" % (n, m), end='')
if levels:
    # params: e sigma L0 L1 S1 S2 Q gamma single
    cols=list(zip(*levels))
    med=lambda c: sorted(c)[len(c)//2]
    print("  median sigma %.3f L0 %.1f L1 %.1f S1 %.1f gamma %.3f single %.0f%%" % (med(cols[2]),med(cols[3]),med(cols[4]),med(cols[5]),med(cols[8]),100*sum(cols[9])/len(cols[9])))
else: print()
