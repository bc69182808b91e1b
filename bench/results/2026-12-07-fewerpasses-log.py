import sys, re, collections
rows=[]
for l in open(sys.argv[1]):
    if not l.startswith('FP '): continue
    t=l.split()
    d=dict(path=t[1], side=float(t[3]), blur=float(t[5]), cells=int(t[7]), ch=t[9], uns=int(t[11]),
           sw=float(t[13]), sp=int(t[14]), smove=float(t[15]), sfits=int(t[16]), first=int(t[18]))
    r=t[20:]; rounds=[]
    for i in range(0,len(r),6): rounds.append(dict(mv=float(r[i+1]),passes=int(r[i+2]),fits=int(r[i+3]),rep=int(r[i+4]),cyc=float(r[i+5])))
    d['rounds']=rounds; rows.append(d)
n=len(rows); print("refinements",n)
print("paths",collections.Counter(d['path'] for d in rows))
print("rounds per marker",collections.Counter(len(d['rounds']) for d in rows))
fi=sum(d['first'] for d in rows); rf=sum(sum(x['fits'] for x in d['rounds']) for d in rows); sf=sum(d['sfits'] for d in rows)
print("side fits: first %d rounds %d skew %d  (per refinement %.1f %.1f %.1f)"%(fi,rf,sf,fi/n,rf/n,sf/n))
r0=[d['rounds'][0] for d in rows if d['rounds']]
print("round0 passes",collections.Counter(x['passes'] for x in r0))
for th in (0.001,0.002,0.005,0.01,0.02,0.05):
    print(" round0 moved > %.3f: %d of %d"%(th,sum(x['mv']>th for x in r0),len(r0)))
print("round0 repeated choices", sum(x['rep'] for x in r0))
print("choices", collections.Counter(d['ch'] for d in rows).most_common(6))
sk=[d for d in rows if d['sp']>0]
print("skew passes ran on %d; weight distribution:"%len(sk), collections.Counter(round(d['sw'],1) for d in sk))
for th in (0.001,0.005,0.02,0.05,0.1):
    print(" skew moved > %.3f: %d"%(th,sum(d['smove']>th for d in sk)))
# which markers move in round 0 > 0.005
big=[d for d in rows if d['rounds'] and d['rounds'][0]['mv']>0.005]
for d in big[:40]: print("  r0>0.005: side %.1f blur %.2f ch %s rounds %s skew %.2f"%(d['side'],d['blur'],d['ch'],[(round(x['mv'],4),x['passes'],round(x['cyc'],4)) for x in d['rounds']],d['sw']))

for k in range(4):
    rr=[d['rounds'][k] for d in rows if len(d['rounds'])>k]
    print("round %d: %d refinements, fits %d, passes %d"%(k,len(rr),sum(x['fits'] for x in rr),sum(x['passes'] for x in rr)))
print("rounds>=1 with cycle distance < 0.002/0.005/0.01/0.02:",[sum(1 for d in rows for x in d['rounds'][1:] if x['cyc']<t and x['mv']>=0.005) for t in (0.002,0.005,0.01,0.02)])
