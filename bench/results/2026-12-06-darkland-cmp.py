import csv,sys,math
from collections import defaultdict
def load(p):
    g=defaultdict(dict)
    for r in csv.DictReader(open(p)):
        g[(r['camera'],r['seq'],r['id'])][int(r['corner'])]=(float(r['dx']),float(r['dy']),float(r['size_px']),float(r['view_deg']))
    return g
a=load(sys.argv[1]); b=load(sys.argv[2])
ch=0; bad_a=bad_b=0
for k in sorted(set(a)|set(b)):
    ea=a.get(k); eb=b.get(k)
    ma=max(math.hypot(*ea[c][:2]) for c in ea) if ea else None
    mb=max(math.hypot(*eb[c][:2]) for c in eb) if eb else None
    if ma is not None and ma>0.5: bad_a+=1
    if mb is not None and mb>0.5: bad_b+=1
    if ea!=eb:
        ch+=1
        if len(sys.argv)>3: print(k, 'size %.1f view %.0f'%((ea or eb)[0][2],(ea or eb)[0][3]), 'max err', ma, '->', mb)
print('markers',len(a),len(b),'changed',ch,'with a corner >0.5px',bad_a,bad_b)
