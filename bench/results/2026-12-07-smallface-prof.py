# Per-side fitted levels and mean profile beyond the edge (in units of L1 - L0) from the scratch patch dump
# (MCMT_SF_DUMP=1 diag_session ... 2> F): python3 2026-12-07-smallface-prof.py F
import sys,statistics as st,collections
L=[l for l in open(sys.argv[1]) if l.startswith('SF')]
rows=[]
for l in L:
    h,prof=l.split('|')
    t=h.split()
    d={t[i]:float(t[i+1]) for i in range(1,len(t)-1,2)}
    pr=[tuple(map(float,x.split(':'))) for x in prof.split()]
    rows.append((d,pr))
for side in range(4):
    R=[r for r in rows if r[0]['side']==side and not r[0]['single']]
    print('side',side,'n',len(R), ' '.join('%s %.2f'%(k, st.median([d[k] for d,_ in R])) for k in ['cell','sig','L0','L1','S1','S2','q','end']))
    acc=collections.defaultdict(list)
    for d,pr in R:
        con=d['L1']-d['L0']
        for u,v in pr: acc[round(u*4)/4].append((v-d['L0'])/con)
    print('   '+' '.join('%.2f:%.3f'%(k,st.mean(acc[k])) for k in sorted(acc) if len(acc[k])>len(R)/3))
