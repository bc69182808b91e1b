import csv,math,sys
from collections import defaultdict
c=defaultdict(list)
for r in csv.DictReader(open(sys.argv[1])):
    if not r.get('n_after'): continue
    c[(r['variant'],r['cell'],r['image'],r['id'],r['corner'])].append(r)
dev=defaultdict(list)
for k,rs in c.items():
    if len(rs)<6: continue
    sp=float(rs[0]['side_px'])
    band=k[0]+' '+('15-25' if sp<25 else '25-40' if sp<40 else '40-60')
    for key in ('n_before','n_after'):
        v=[float(r[key]) for r in rs]; m=sorted(v)[len(v)//2]
        dev[band]+= [x-m for x in v]; dev[k[0]+' all']+=[x-m for x in v]
print('| band | normal-component deviations from the corner\'s median draw: 1.4826 MAD | rms | share beyond 0.3 px |')
print('|---|---|---|---|')
for b in sorted(dev):
    d=dev[b]; a=sorted(abs(x) for x in d); nz=[x for x in a if x>0]
    mad=nz[len(nz)//2]
    print('| %s | %.3f | %.3f | %.3f |'%(b,1.4826*mad,math.sqrt(sum(x*x for x in d)/len(nz)),sum(1 for x in a if x>0.3)/len(nz)))
