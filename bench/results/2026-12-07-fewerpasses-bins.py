import sys
exec(open(__file__.replace('-bins','-log')).read().split("n=len(rows)")[0])
rr=[d for d in rows if d['rounds']]
def tab(key, bins, label):
    print("| %s | markers | round 0 > 0.005 px | round 0 > 0.02 px | 2+ rounds | 4 rounds | round fits / marker |"%label)
    print("|---|---:|---:|---:|---:|---:|---:|")
    for lo,hi in zip(bins,bins[1:]):
        g=[d for d in rr if lo<=key(d)<hi]
        if not g: continue
        n=len(g)
        print("| %g-%g | %d | %d (%.0f %%) | %d (%.0f %%) | %d | %d | %.1f |"%(lo,hi,n,sum(d['rounds'][0]['mv']>0.005 for d in g),100*sum(d['rounds'][0]['mv']>0.005 for d in g)/n,sum(d['rounds'][0]['mv']>0.02 for d in g),100*sum(d['rounds'][0]['mv']>0.02 for d in g)/n,sum(len(d['rounds'])>=2 for d in g),sum(len(d['rounds'])>=4 for d in g),sum(sum(x['fits'] for x in d['rounds']) for d in g)/n))
tab(lambda d:d['side'],[0,15,20,25,40,60,1000],"side px")
tab(lambda d:d['blur']*4*d['cells']/(4*d['side']) if d['side']>0 else 0,[0,0.3,0.4,0.5,0.6,10],"blur sigma, cells")
tab(lambda d:d['sw'],[0,1e-9,0.5,0.999,2],"skew weight")
