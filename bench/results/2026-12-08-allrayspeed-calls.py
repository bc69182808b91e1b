import sys,re,collections
# sum calls to functions matching patterns in a callgrind out file (name compression aware)
pats=sys.argv[2:]
names={}
tot=collections.Counter()
cur_cfn=None
for line in open(sys.argv[1],errors='replace'):
    m=re.match(r'(c?fn)=\((\d+)\)(?: (.*))?',line)
    if m:
        k,i,n=m.groups()
        if n: names[i]=n
        if k=='cfn': cur_cfn=names.get(i)
        continue
    if line.startswith('calls=') and cur_cfn:
        c=int(line.split('=')[1].split()[0])
        for p in pats:
            if p in cur_cfn: tot[p]+=c
print(' '.join(f'{p.split("::")[-1]}={tot[p]}' for p in pats))
