#!/usr/bin/env python3
"""The whole pass's Jacobian about F (MCMT_X_PASSMAP_MODES=J, overshoot): per unsettled refinement the 4 x 4
matrix dd_out_j/dd_in_k by central differences (+-0.05 px), its eigenvalues (pure Python), its diagonal, and
whether the pass function jumps within +-0.05 px of F (the value at F off the mean of the two sides by more
than 0.01 px on some side). Usage: 2026-12-07-overshoot-jacobian.py FILE"""
import cmath
import statistics as st
import sys


def eig4(a):
    n = len(a)
    # Faddeev-LeVerrier: characteristic polynomial coefficients, then Durand-Kerner.
    m = [[0.0] * n for _ in range(n)]
    c = [1.0]
    for k in range(1, n + 1):
        am = [[sum(a[i][l] * m[l][j] for l in range(n)) for j in range(n)] for i in range(n)]
        m = [[am[i][j] + (c[-1] if i == j else 0.0) for j in range(n)] for i in range(n)]
        am = [[sum(a[i][l] * m[l][j] for l in range(n)) for j in range(n)] for i in range(n)]
        c.append(-sum(am[i][i] for i in range(n)) / k)
    roots = [complex(0.4, 0.9) ** i for i in range(n)]
    p = lambda z: sum(ci * z ** (n - i) for i, ci in enumerate(c))
    for _ in range(500):
        new = []
        for i, z in enumerate(roots):
            den = 1
            for j, w in enumerate(roots):
                if i != j: den *= (z - w)
            new.append(z - p(z) / den if den != 0 else z)
        roots = new
    return roots


rows = []
for line in open(sys.argv[1]):
    if ' | J' not in line: continue
    head = line.split(' | ')[0].split()
    side = int(head[2]); last = float(head[8])
    toks = line.split(' | J')[1].split()
    data = {}
    for t in toks:
        v = t.split(':')
        data[(int(v[0]), float(v[1]))] = [float(x) for x in v[2:]]
    if (0, 0.0) not in data or any((k, s) not in data for k in range(4) for s in (-0.05, 0.05)): continue
    vals = [data[(k, s)] for k in range(4) for s in (-0.05, 0.05)] + [data[(0, 0.0)]]
    if any(x != x for v in vals for x in v): continue
    J = [[(data[(k, 0.05)][j] - data[(k, -0.05)][j]) / 0.1 for k in range(4)] for j in range(4)]
    base = data[(0, 0.0)]
    jump = any(abs(base[j] - 0.5 * (data[(k, 0.05)][j] + data[(k, -0.05)][j])) > 0.01 for k in range(4)
               for j in range(4))
    jt = {th: any(abs(base[j] - 0.5 * (data[(k, 0.05)][j] + data[(k, -0.05)][j])) > th for k in range(4)
                  for j in range(4)) for th in (0.002, 0.005, 0.01)}
    rows.append((side, last, J, eig4(J), jump, base, jt))

n = len(rows)
print(f"refinements {n}")
diag = [r[2][r[0]][r[0]] for r in rows]
print(f"J[s][s] (the side that moved most) median {st.median(diag):+.3f}; < -0.5: {sum(d < -0.5 for d in diag)/n:.1%}")
alld = [r[2][j][j] for r in rows for j in range(4)]
print(f"J[j][j] all sides median {st.median(alld):+.3f}")
off = [abs(r[2][j][k]) for r in rows for j in range(4) for k in range(4) if j != k]
print(f"|J[j][k]| j != k median {st.median(off):.3f}, q90 {sorted(off)[int(.9*len(off))]:.3f}")
most_neg = [min(e.real for e in r[3]) for r in rows]
rad = [max(abs(e) for e in r[3]) for r in rows]
print(f"most negative eigenvalue (real part) median {st.median(most_neg):+.3f}; < -0.7: {sum(x < -0.7 for x in most_neg)/n:.1%};"
      f" < -1: {sum(x < -1 for x in most_neg)/n:.1%}")
print(f"spectral radius median {st.median(rad):.3f}; > 1: {sum(x > 1 for x in rad)/n:.1%}")
jumps = [r for r in rows if r[4]]
print(f"jump within +-0.05 px of F: {len(jumps)/n:.1%}")
smooth = [r for r in rows if not r[4]]
if smooth:
    sm = [min(e.real for e in r[3]) for r in smooth]
    print(f"  without a jump ({len(smooth)}): most negative eigenvalue median {st.median(sm):+.3f}; < -0.7: {sum(x < -0.7 for x in sm)/len(sm):.1%}")
big = [r for r in rows if abs(r[1]) > 0.05]
if big:
    print(f"last move > 0.05 px ({len(big)}): jump {sum(r[4] for r in big)/len(big):.1%};"
          f" eigenvalue < -0.7 {sum(min(e.real for e in r[3]) < -0.7 for r in big)/len(big):.1%}")

# By the size of the last move of the side that moved most, and the jump threshold.
print("last move bins (px): count, jump >0.002 / >0.005 / >0.01 px, eigenvalue < -0.7, spectral radius > 1")
for lo, hi in ((0, 0.005), (0.005, 0.02), (0.02, 0.05), (0.05, 0.2), (0.2, 99)):
    sel = [r for r in rows if lo <= abs(r[1]) < hi]
    if not sel: continue
    def jumped(r, th):
        side, last, J, e, j, base = r
        return j if th == 0.01 else None
    print(f"  [{lo}, {hi}): {len(sel)}", end='')
    for th in (0.002, 0.005, 0.01):
        cnt = 0
        for r in sel:
            cnt += r[6][th] if len(r) > 6 else 0
        print(f"  {cnt/len(sel):.0%}", end='')
    print(f"  {sum(min(e.real for e in r[3]) < -0.7 for r in sel)/len(sel):.0%}  {sum(max(abs(e) for e in r[3]) > 1 for r in sel)/len(sel):.0%}")
