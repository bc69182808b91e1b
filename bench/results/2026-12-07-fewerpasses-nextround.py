import sys
exec(open(__file__.replace('-nextround','-log')).read().split("n=len(rows)")[0])
bins=[0.005,0.01,0.02,0.05,0.1,1e9]
for rep in (1,0):
 for conv in (1,0):
  for lo,hi in zip(bins,bins[1:]):
    rr=[d for d in rows if len(d['rounds'])>=2 and d['rounds'][0]['rep']==rep and (d['rounds'][0]['passes']<6)==conv and lo<=d['rounds'][0]['mv']<hi]
    if not rr: continue
    m1=sorted(d['rounds'][1]['mv'] for d in rr)
    f=sum(sum(x['fits'] for x in d['rounds'][1:]) for d in rr)
    print("rep %d conv %d r0 moved %.3f-%.3f: n %d, r1 moved median %.4f, >0.002 %d >0.005 %d >0.02 %d; fits in rounds>=1 %d"%(rep,conv,lo,hi,len(rr),m1[len(m1)//2],sum(x>0.002 for x in m1),sum(x>0.005 for x in m1),sum(x>0.02 for x in m1),f))
