# acuteend (issue 15): per-ray side model vs pixels of diag_acute_end AE_TRACE output (patch beside this file).
# usage: python3 2026-12-06-acuteend-rays.py TRACE [fit | true SIGMA [MARGIN_LEVEL]]
import sys, math
sys.path.insert(0, __import__('os').path.dirname(__file__))
model_mod = __import__('2026-12-06-acuteend-model'); globals().update({k: getattr(model_mod, k) for k in ('parse', 'model', 'Phi')})
def cross(a,b): return a[0]*b[1]-a[1]*b[0]
ms=parse(sys.argv[1])
mode=sys.argv[2] if len(sys.argv)>2 else 'fit'
classes={}
def add(key,name,val):
    d=classes.setdefault(key,{}); d.setdefault(name,[]).append(val)
for m in ms:
    if not m.get('ok'): continue
    T=m['T']
    if mode=='true': pass
    for s,sd in m['sides'].items():
        f=sd['fit']; e=f[0]; P=[e]+f[1:8];
        if mode=='true': P=[e,float(sys.argv[3]),10.2,216.75,216.75,127.5,m['cell']*math.sin(m['theta']*math.pi/180),1.0]
        single=f[8]>0; u0,du=f[9],f[10]; cell=f[12]; gfit=f[18]>0
        a=T[s]; b=T[(s+1)%4]; ab=(b[0]-a[0],b[1]-a[1])
        for r in sd['rays']:
            o=r['org']; n=r['n']
            st=cross((a[0]-o[0],a[1]-o[1]),ab)/cross(n,ab); ut=st-r['delta']
            dist=(r['along'] if s in (0,2) else 1-r['along'])*8
            key=int(dist)
            add(key,'e_fit-true',e-ut)
            # edge-only per ray: minimise sum (v - model(e')) over e'
            def cost(ee,ov=None):
                c=0
                for j,v in enumerate(r['v']):
                    if v!=v: continue
                    u=u0+j*du; c+=(v-model(u,ee,P,single,gfit,r,ov))**2
                return c
            lo,hi=ut-1.0,ut+1.0
            for it in range(40):
                m1=lo+(hi-lo)*0.382; m2=lo+(hi-lo)*0.618
                if cost(m1)<cost(m2): hi=m2
                else: lo=m1
            add(key,'e_ray-true',0.5*(lo+hi)-ut)
            add(key,'o1',r['o'][0]); add(key,'p1',r['p'][0]); add(key,'steps',r['ns'])
            for j,v in enumerate(r['v']):
                if v!=v: continue
                u=u0+j*du; x=(u-ut)/cell
                kb=math.floor(x*5+0.5)/5
                mv=model(u,ut,P,single,gfit,r)
                if len(sys.argv)>4:
                    px=(o[0]+(r['delta']+u)*n[0], o[1]+(r['delta']+u)*n[1])
                    for nb in ((s+3)%4,(s+1)%4):
                        A=T[nb]; Bq=T[(nb+1)%4]; ln=math.hypot(Bq[0]-A[0],Bq[1]-A[1])
                        C=(sum(t[0] for t in T)/4,sum(t[1] for t in T)/4)
                        dd=cross((Bq[0]-A[0],Bq[1]-A[1]),(px[0]-A[0],px[1]-A[1]))/ln
                        dc=cross((Bq[0]-A[0],Bq[1]-A[1]),(C[0]-A[0],C[1]-A[1]))/ln
                        if dc<0: dd=-dd
                        w=Phi(-dd/P[1])
                        mv=mv*(1-w)+float(sys.argv[4])*w
                add(key,('res',kb),v-mv)
print('dist-from-acute-cell  n  e_fit-true  e_ray-true  mean_o1  p1  steps')
for k in sorted(classes):
    d=classes[k]; mean=lambda x: sum(x)/len(x)
    print(k, len(d['e_fit-true']), '%+.4f %+.4f %.3f %.2f %.2f'%(mean(d['e_fit-true']),mean(d['e_ray-true']),mean(d['o1']),mean(d['p1']),mean(d['steps'])))
print('residual pixel - model(true edge, fitted levels) by (u - u_true)/cell; columns dist 1..6')
keys=sorted({kk[1] for d in classes.values() for kk in d if isinstance(kk,tuple)})
for kb in keys:
    row=['%+.1f'%kb]
    for k in sorted(classes):
        x=classes[k].get(('res',kb),[])
        row.append('%+7.2f'%(sum(x)/len(x)) if x else '    -  ')
    print(' '.join(row))
ps=[]
for m in ms:
    if not m.get('ok'): continue
    for s,sd in m['sides'].items(): ps.append(sd['fit'])
names=['e','sigma','L0','L1','S1','S2','q','gamma','single']
print('fit means:', ' '.join('%s %.3f'%(nm,sum(p[i] for p in ps)/len(ps)) for i,nm in enumerate(names)), 'n', len(ps))
