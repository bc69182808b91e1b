import re,subprocess,sys
def load(f):
    out=subprocess.run(['callgrind_annotate','--threshold=100',f],capture_output=True,text=True).stdout
    d={}
    for l in out.splitlines():
        m=re.match(r'\s*([\d,]+) \([^)]*\)\s+\S*?:(.*?)( \[.*\])?$',l)
        if not m: continue
        name=re.sub(r'\(anonymous namespace\)::','',m.group(2))
        name=name.split('(')[0]
        d[name]=d.get(name,0)+int(m.group(1).replace(',',''))
    return d
fs=sys.argv[1:]
ds=[load(f) for f in fs]
keys=set().union(*ds)
rows=sorted(keys,key=lambda k:-sum(abs(ds[i+1].get(k,0)-ds[i].get(k,0)) for i in range(len(ds)-1)))
for k in rows[:22]:
    print(f"{k[-60:]:60s} {ds[0].get(k,0)/1e6:8.3f} "+' '.join(f"{(ds[i+1].get(k,0)-ds[i].get(k,0))/1e6:+8.3f}" for i in range(len(ds)-1)))
