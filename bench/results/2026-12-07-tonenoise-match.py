import re,sys
A=open('trold.tr').read().splitlines(); B=open('trnew.tr').read().splitlines()
def passes(t):
    return [(m.group(1),float(m.group(2)),int(m.group(3))) for m in re.finditer(r'([cm])([\d.e+-]+)/d(\d+)',t.split('::')[1])]
def key(vals):
    v=[float(x) for x in vals]
    return tuple(round(v[i]-v[i%2],4) for i in range(2,8))+(round(v[0]%1,4),round(v[1]%1,4))
idxA={}
for i,l in enumerate(A): idxA.setdefault(key(l.split('::')[0].split()),i)
cams=[];last=10**9
for la,lb in zip(open('trold.dump'),open('trnew.dump')):
    ta,tb=la.split(),lb.split(); fr=int(ta[0])
    if fr<last: cams.append([])
    last=fr; cams[-1].append((ta,tb))
maxidx=0
res={}
ex=[]
for c,entries in enumerate(cams):
    for ta,tb in entries:
        i=idxA.get(key(ta[3:11]))
        d=max(abs(float(p)-float(q)) for p,q in zip(ta[3:11],tb[3:11]))
        if i is None: res['unmatched']=res.get('unmatched',0)+1; ex.append(('unmatched',c,ta[0],ta[1],d)); continue
        maxidx=max(maxidx,i)
        pa,pb=passes(A[i]),passes(B[i])
        prevA=passes(A[i-1])[-1][2] if i else 0; prevB=passes(B[i-1])[-1][2] if i else 0
        da=[p[2]-prevA for p in pa]; db=[p[2]-prevB for p in pb]
        k=None
        for j,(x,y) in enumerate(zip(pa,pb)):
            if x[0]!=y[0] or abs(x[1]-y[1])>max(1e-4,0.05*max(x[1],y[1])): k=j;break
        ra=re.findall(r'R\d [\d.e+-]+ rep\d',A[i]); rb=re.findall(r'R\d [\d.e+-]+ rep\d',B[i])
        if k is None and len(pa)==len(pb):
            cls='same-path' if d<1e-6 else 'same-path-but-moved'
        elif k is None: cls='pass-count'
        elif da[:k+1]!=db[:k+1]: cls='fitline-drop-first'
        elif pa[k][0]=='c': cls='crossing-pass'
        else: cls='model-pass'
        res[cls]=res.get(cls,0)+1
        if cls!='same-path': ex.append((cls,c,ta[0],ta[1],'%.2e'%d, k, pa[k][1] if k is not None else None, pb[k][1] if k is not None else None, 'passes',len(pa),len(pb)))
print(res, 'max trace index', maxidx, 'of', len(A))
for e in ex: print(e)
