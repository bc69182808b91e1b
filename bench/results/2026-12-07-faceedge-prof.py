import sys, collections, statistics as st
acc = collections.defaultdict(list); dips = []; n = 0; de = []
for line in open(sys.argv[1]):
    head, prof = line.split('|')
    f = head.split()
    cell, sig, e, q, L0, L1, S1, S2, dip, dE, ok = map(float, f[1:12])
    n += 1; dips.append(dip); de.append(dE)
    pts = [tuple(map(float, t.split(':'))) for t in prof.split()]
    c = L1 - L0
    if abs(c) < 1: continue
    for u, v in pts: acc[round(u * 4) / 4].append((v - L0) / c)
print('sides', n, 'dip cells median %.2f' % st.median([d for d in dips if d == d]), 'q-range')
print('dE mean %+.4f px (refit - first), median %+.4f' % (sum(de) / n, st.median(de)))
for u in sorted(acc):
    if len(acc[u]) > n / 4: print('%5.2f %.3f (%d)' % (u, st.mean(acc[u]), len(acc[u])))
qs = []
for line in open(sys.argv[1]):
    f = line.split('|')[0].split(); qs.append(float(f[4]))
print('q cells median %.2f' % st.median(qs), 'cell median', st.median(float(l.split()[1]) for l in open(sys.argv[1])))
