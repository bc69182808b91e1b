import sys,re,statistics as st
def parse(fn):
    runs=[];cur=[];prev=0
    for line in open(fn):
        if not line.startswith('TRACE'): continue
        t=line.split()
        d={'pass':int(t[2]),'side':int(t[4])}
        main,two=line.split(' two: ')
        kv=main.split()[5:]
        for i in range(0,len(kv)-1,2):
            v=kv[i+1]
            if kv[i]=='gamma': d['gf']=v[-1]; v=v[:-1]
            d[kv[i]]=float(v) if v!='nan' else float('nan')
        tk=two.split()
        for i in range(0,len(tk)-1,2): d['t_'+tk[i]]=float(tk[i+1])
        if d['pass']<prev and cur: runs.append(cur);cur=[]
        prev=d['pass'];cur.append(d)
    if cur: runs.append(cur)
    last=[]
    for r in runs:
        mp=max(x['pass'] for x in r)
        by={}
        for x in r:
            if x['pass']==mp: by[x['side']]=x
        last+=by.values()
    return last
for fn in sys.argv[1:]:
    L=[x for x in parse(fn) if x['e']==x['e']]
    n=len(L)
    def m(k,sel=L): 
        v=[x[k] for x in sel if x[k]==x[k]]
        return st.mean(v) if v else float('nan')
    single=[x for x in L if x['single']==1]; two=[x for x in L if x['single']==0]
    unseen=[x for x in L if x['flags']>=8 and int(x['flags'])&2]
    fresh=[x for x in L if x['flags']>=8]
    print(f"{fn}: sides {n}, single {len(single)/n:.2f}, fresh-2level fits {len(fresh)}, unseen {len(unseen)} faint {sum(1 for x in fresh if int(x['flags'])&1)}, gamma free {sum(1 for x in L if x['gf']=='f')/n:.2f}")
    for name,sel in (('all',L),('single',single),('two',two)):
        if sel: print(f"  {name:6s} n {len(sel):4d} e {m('e',sel):+.3f} sigma {m('sigma',sel):.3f} gamma {m('gamma',sel):.3f} L0 {m('L0',sel):.1f} L1 {m('L1',sel):.1f} S1 {m('S1',sel):.1f} S2 {m('S2',sel):.1f} q/c {st.mean(x['q']/x['cell'] for x in sel):.2f} cell {m('cell',sel):.2f} outer {m('outer',sel):.2f}")
    if unseen: print(f"  unseen's 2-level: e {m('t_e',unseen):+.3f} gamma {m('t_gamma',unseen):.3f} L0 {m('t_L0',unseen):.1f} L1 {m('t_L1',unseen):.1f} S1 {m('t_S1',unseen):.1f} S2 {m('t_S2',unseen):.1f} q/c {st.mean(x['t_q']/x['cell'] for x in unseen):.2f}")
