# window2: views (usage: python3 THIS DEFAULT_FILE SWITCH_FILE; see 2026-12-07-window2.md)
import sys
def load(p):
    d={}
    for l in open(p):
        t=l.split()
        if t[0]!='view': continue
        d[tuple(map(int,t[1:5]))]=(float(t[6]),float(t[8]),int(t[12]),int(t[14]))
    return d
a=load(sys.argv[1]); b=load(sys.argv[2])
bins=[(0,12),(12,15),(15,20),(20,30),(30,1e9)]
print("| size px | angle deg | visible | found default | found first |")
print("|---|---|---|---|---|")
for s0,s1 in bins:
  for g0,g1 in [(0,60),(60,75),(75,90)]:
    ks=[k for k,v in a.items() if v[2] and s0<=v[1]<s1 and g0<=v[0]<g1]
    if not ks: continue
    print("| %g-%g | %g-%g | %d | %d | %d |"%(s0,s1,g0,g1,len(ks),sum(a[k][3] for k in ks),sum(b[k][3] for k in ks)))
