#!/usr/bin/env python3
"""Per-quad fitted values of TurnSkewedSides (scratch STDUMP lines on stderr): blur px, blur in cells, mean side
px, the turn's weight, per side sigma, gamma, contrast, L0, L1, S1, S2. Percentiles per file."""
import sys, statistics as st
def pct(v, p):
    v = sorted(v); return v[min(len(v) - 1, int(p / 100 * len(v)))] if v else float('nan')
for path in sys.argv[1:]:
    rows = []
    for line in open(path, errors='replace'):
        if not line.startswith('STDUMP'): continue
        f = [float(x) for x in line.split()[1:]]
        blur_px, blur_cells, side, weight = f[:4]
        sides = [f[4 + 7 * k: 11 + 7 * k] for k in range(4)]
        gam = st.mean(s[1] for s in sides)
        con = st.mean(s[2] for s in sides)
        L0 = st.mean(s[3] for s in sides); L1 = st.mean(s[4] for s in sides)
        sig = st.mean(s[0] for s in sides)
        rows.append(dict(blur_px=blur_px, blur_cells=blur_cells, side=side, weight=weight, gamma=gam, contrast=con,
                         L0=L0, L1=L1, sig_side=sig, cell=side / 8, sig_over_cell_side=sig / (side / 8)))
    print('%s: %d quads' % (path, len(rows)))
    for k in ['blur_px', 'blur_cells', 'side', 'cell', 'weight', 'gamma', 'contrast', 'L0', 'L1', 'sig_side']:
        v = [r[k] for r in rows]
        print('  %-10s p5 %.3f  p50 %.3f  p95 %.3f' % (k, pct(v, 5), pct(v, 50), pct(v, 95)))
