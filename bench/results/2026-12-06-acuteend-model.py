# acuteend (issue 15): parser of diag_acute_end AE_TRACE output and the side model of detector/side_model.h per ray.
import sys, math
def Phi(z): return 0.5*math.erfc(-z/math.sqrt(2))
def parse(path):
    markers=[]; cur=None
    for line in open(path):
        t=line.split()
        if not t: continue
        if t[0]=='M': cur={'theta':float(t[2]),'cell':float(t[3]),'sides':{}}; markers.append(cur); cur['_last']=None
        elif t[0]=='AES':
            s=int(t[1]); f=list(map(float,t[2:])); cur['sides'][s]={'fit':f,'rays':[]}; cur['_last']=s
        elif t[0]=='AER':
            vi=t.index('V'); head=t[1:vi]; vals=list(map(float,t[vi+1:]))
            r={'along':float(head[0]),'delta':float(head[1]),'d':[float(head[2]),float(head[3])],'o':[float(head[4]),float(head[5])],
               'p':[int(head[6]),int(head[7])],'ns':int(head[8]),'org':(float(head[9]),float(head[10])),'n':(float(head[11]),float(head[12])),'v':vals,'steps':[]}
            k=13
            while k<len(head) and head[k]=='S':
                r['steps'].append((int(head[k+1]),float(head[k+2]),float(head[k+3]),float(head[k+4]))); k+=5
            cur['sides'][cur['_last']]['rays'].append(r)
        elif t[0]=='T': cur['T']=[(float(t[1+2*k]),float(t[2+2*k])) for k in range(4)]
        elif t[0]=='C': cur['ok']=int(t[1]); cur['C']=[(float(t[2+2*k]),float(t[3+2*k])) for k in range(4)]
    return markers
def model(u,e,P,single,gfit,r,override=None):
    # P: e sigma L0 L1 S1 S2 q gamma
    sig,L0,L1,S1,S2,q,gam=P[1],P[2],P[3],P[4],P[5],P[6],P[7]
    o=list(r['o'])
    if override: o=override
    B=[e+q,e,e-r['d'][0],e-r['d'][1]]
    lev=[S1 if single else S2,S1,L0,L0+(L1-L0)*o[0],L0+(L1-L0)*o[1]]
    ph=[Phi((b-u)/sig) for b in B]
    f=0
    for k in range(5):
        up=1.0 if k==0 else ph[k-1]; lo=0.0 if k==4 else ph[k]
        f+=lev[k]*(up-lo)
    for (row,depth,delta,sc) in r['steps']:
        bin_=row+1
        band=ph[bin_]-(0 if row==2 else ph[bin_+1])
        f+=(L1-L0)*delta*Phi((e-depth-u)/(sig*sc))*band
    if gfit:
        at=max(f,0.5); enc=255*math.exp(math.log(at/255)/gam)
        f=enc+ (enc/gam/at)*(f-at) if f<at else enc
    return f
