import csv,sys,math
from collections import defaultdict
def load(p):
    g=defaultdict(dict)
    for r in csv.DictReader(open(p)):
        g[(r['camera'],r['seq'],r['id'])][int(r['corner'])]=(float(r['dx']),float(r['dy']),float(r['size_px']),float(r['view_deg']))
    return g
a=load(sys.argv[1]); b=load(sys.argv[2])
for k in sorted(set(a)|set(b)):
    ea=a.get(k); eb=b.get(k)
    ma=max(math.hypot(*ea[c][:2]) for c in ea) if ea else None
    mb=max(math.hypot(*eb[c][:2]) for c in eb) if eb else None
    if ma is None or mb is None or abs(mb-ma)>0.3:
        print(k,'size %.1f view %.0f'%((ea or eb)[0][2],(ea or eb)[0][3]),ma,'->',mb)
