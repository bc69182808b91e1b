import re,sys
A=open('f4old.tr').read().splitlines(); B=open('f4new.tr').read().splitlines()
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

# fit-end tokens at the first diverging pass
from collections import Counter
def passrecs(t):
    return re.findall(r'([cm])([\d.e+-]+)/d(\d+) \[([^\]]*)\]', t.split('::',1)[1])
cnt=Counter(); kinds=Counter(); examples=[]
for c,entries in enumerate(cams):
    for ta,tb in entries:
        if c==3 and int(ta[0])>=85: continue
        i=idxA.get(key(ta[3:11]))
        if i is None: continue
        ra,rb=passrecs(A[i]),passrecs(B[i])
        k=None
        for j,(x,y) in enumerate(zip(ra,rb)):
            mx,my=float(x[1]),float(y[1])
            if x[0]!=y[0] or abs(mx-my)>max(1e-4,0.05*max(mx,my)): k=j;break
        if k is None: continue
        # first pass j<=k whose fit tokens differ
        first=None
        for j in range(k+1):
            if ra[j][3]!=rb[j][3]: first=j;break
        if first is None: cnt['same fit ends up to the diverging pass']+=1; examples.append((c,ta[0],ta[1],k,ra[k][3],'|',rb[k][3]))
        else:
            cnt['fit ends differ at pass <= diverging pass']+=1
            ta_,tb_=ra[first][3].split(),rb[first][3].split()
            for x,y in zip(ta_,tb_):
                if x!=y: kinds[(x,y)]+=1; break
            else: kinds[('len',len(ta_),len(tb_))]+=1
            examples.append((c,ta[0],ta[1],'div',k,'fitdiff',first,ra[first][3],'|',rb[first][3]))
print(dict(cnt)); print(kinds.most_common(20))
for e in examples[:25]: print(e)

# do diverging passes (same fit ends) contain unconverged fits, against all model passes?
div_with_N=0; div_total=0
for e in examples:
    if e[3]=='div': continue
    div_total+=1; div_with_N += 'N' in e[4]
allm=0; allN=0
for l in A:
    for r in passrecs(l):
        if r[0]=='m': allm+=1; allN += 'N' in r[3]
print('diverging passes with an unconverged (N) side fit: %d of %d; all model passes: %d of %d (%.0f %%)'%(div_with_N,div_total,allN,allm,100*allN/allm))

# finer: first pass whose move differs by more than TH px (moves printed to 10 digits)
for TH in (1e-9, 1e-6):
    res=Counter(); toks=Counter()
    for c,entries in enumerate(cams):
        for ta,tb in entries:
            if c==3 and int(ta[0])>=85: continue
            i=idxA.get(key(ta[3:11]))
            if i is None: continue
            d=max(abs(float(p)-float(q)) for p,q in zip(ta[3:11],tb[3:11]))
            if d<1e-7: continue
            ra,rb=passrecs(A[i]),passrecs(B[i])
            k=None
            for j,(x,y) in enumerate(zip(ra,rb)):
                if x[0]!=y[0] or abs(float(x[1])-float(y[1]))>TH: k=j;break
            if k is None: res['no pass differs']+=1; continue
            tk=ra[k][3]
            if ra[k][3]!=rb[k][3]: res['fit ends differ there']+=1
            elif 'N' in tk: res['same ends, an unconverged (N) fit in it']+=1
            else: res['same ends, all converged (D)']+=1
            res['pass kind '+ra[k][0]]+=1
    print('TH',TH,'refinements ending >=1e-7 px apart:',dict(res))

res=Counter(); diffs=Counter(); ex4=[]
for c,entries in enumerate(cams):
    for ta,tb in entries:
        if c==3 and int(ta[0])>=85: continue
        i=idxA.get(key(ta[3:11]))
        if i is None: continue
        d=max(abs(float(p)-float(q)) for p,q in zip(ta[3:11],tb[3:11]))
        if d<1e-7: continue
        ra,rb=passrecs(A[i]),passrecs(B[i])
        k=None
        for j,(x,y) in enumerate(zip(ra,rb)):
            if x[0]!=y[0] or abs(float(x[1])-float(y[1]))>1e-9: k=j;break
        if k is None: res['none']+=1; continue
        ta_,tb_=ra[k][3].split(),rb[k][3].split()
        if ta_==tb_: res['same fit ends and iteration counts']+=1; ex4.append((c,ta[0],ta[1],k,ra[k][3])); continue
        for x,y in zip(ta_,tb_):
            if x!=y:
                xa=re.match(r'([DN])([a-z]*)(\d+)\.(\d+)',x); ya=re.match(r'([DN])([a-z]*)(\d+)\.(\d+)',y)
                if xa.group(1)!=ya.group(1) or xa.group(2)!=ya.group(2): kind='end kind %s->%s'%(xa.group(1)+xa.group(2),ya.group(1)+ya.group(2))
                elif xa.group(3)!=ya.group(3) and xa.group(4)==ya.group(4): kind='iterations differ (stop test), same rejections'
                elif xa.group(4)!=ya.group(4): kind='rejected trials differ (acceptance test)'
                else: kind='?'
                diffs[kind]+=1; break
        else: diffs['number of fits']+=1
print('first diverging pass (1e-9 px) of refinements ending >=1e-7 px apart:',dict(res),dict(diffs))
for e in ex4[:8]: print(e)

import math
h=Counter(); hN=Counter()
for c,entries in enumerate(cams):
    for ta,tb in entries:
        if c==3 and int(ta[0])>=85: continue
        i=idxA.get(key(ta[3:11]))
        if i is None: continue
        d=max(abs(float(p)-float(q)) for p,q in zip(ta[3:11],tb[3:11]))
        if d<1e-7: continue
        ra,rb=passrecs(A[i]),passrecs(B[i])
        for j,(x,y) in enumerate(zip(ra,rb)):
            dd=abs(float(x[1])-float(y[1]))
            if dd>1e-9:
                same = x[3]==y[3]
                (h if same else hN)[int(math.floor(math.log10(dd)))]+=1; break
print('size of the first move difference > 1e-9 px, same fit tokens: log10 hist',sorted(h.items()),' differing tokens:',sorted(hN.items()))
