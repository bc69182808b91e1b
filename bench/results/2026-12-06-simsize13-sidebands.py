import sys, statistics as st
def load(f):
    rows=[]
    for l in open(f):
        p=l.split()
        if len(p)!=11: continue
        rows.append([float(x) for x in p])
    return rows
for f in sys.argv[1:]:
    r=load(f)
    print(f, len(r))
    for lo,hi in [(0,1.5),(1.5,2.5),(2.5,4),(4,99)]:
        s=[x for x in r if lo<=x[10]<hi]
        if not s: continue
        m=lambda i: st.mean(x[i] for x in s)
        # offset, sigma, L0, L1, S1, S2, q/cell, reach 1.6c+1 in cells
        print(f"  cell {lo}-{hi}: n {len(s)} off {m(0):+.4f} sigma {m(3):.3f} L0 {m(4):.1f} L1 {m(5):.1f} S1 {m(6):.1f} S2 {m(7):.1f} q/c {st.mean(x[8]/x[10] for x in s):.3f} reach/c {st.mean((1.6*x[10]+1)/x[10] for x in s):.2f}")
