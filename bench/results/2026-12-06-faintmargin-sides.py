#!/usr/bin/env python3
"""Per-side fits of two bench_imaging_maps runs of the same condition (e.g. override surface=0.83 vs 0.5),
each a corner dump (MCMT_IMAGING_DUMP) and a DM_SIDE_DUMP stderr (2026-12-06-faintmargin-dump.patch).
Joins with 2026-12-06-nomargin-sides.py's rows_of, then per run: fit type x fitted margin width q, levels
S1 / S2 relative to the paper (8-bit), sigma; and paired by (camera, frame, id, side): the change of each
side's signed offset (+ outward) split by the fit type in run A x run B.
  python3 2026-12-06-faintmargin-sides.py A.csv A.txt B.csv B.txt"""
import importlib.util, os, sys
from collections import defaultdict

here = os.path.dirname(os.path.abspath(__file__))
spec = importlib.util.spec_from_file_location('nm', os.path.join(here, '2026-12-06-nomargin-sides.py'))
nm = importlib.util.module_from_spec(spec)
spec.loader.exec_module(nm)


def med(v):
    v = sorted(v)
    return v[len(v) // 2] if v else float('nan')


def qband(r):
    if r['kind'] != 'two levels':
        return r['kind']
    q = r['fit']['q']
    for lo, hi in ((0, 0.3), (0.3, 0.5), (0.5, 0.8), (0.8, 1.2), (1.2, 2.0), (2.0, 9)):
        if lo <= q < hi:
            return 'two, q %.1f-%.1f' % (lo, hi)


def table(name, rows):
    n = len(rows)
    total = sum(r['off'] for r in rows)
    print('\n%s: %d sides, total %+.2f px, mean %+.4f px' % (name, n, total, total / n))
    print('| fit | sides | mean offset px | share % | median q/cell | S1-P | S2-P | L0 | L1 | sigma px | gamma |')
    print('|---|---|---|---|---|---|---|---|---|---|---|')
    groups = defaultdict(list)
    for r in rows:
        groups[qband(r)].append(r)
    for g in sorted(groups):
        sel = groups[g]
        s = sum(r['off'] for r in sel)
        f = [r['fit'] for r in sel if r['fit']]
        if f:
            print('| %s | %d | %+.4f | %+.0f | %.2f | %+.1f | %+.1f | %.1f | %.1f | %.3f | %.3f |' % (
                g, len(sel), s / len(sel), 100 * s / total, med([x['q'] for x in f]),
                med([x['s1'] - x['paper'] for x in f]), med([x['s2'] - x['paper'] for x in f]),
                med([x['l0'] for x in f]), med([x['l1'] for x in f]), med([x['sigma'] for x in f]),
                med([x['gamma'] for x in f])))
        else:
            print('| %s | %d | %+.4f | %+.0f | | | | | | | |' % (g, len(sel), s / len(sel), 100 * s / total))


def main():
    a = nm.rows_of(sys.argv[1], sys.argv[2])
    b = nm.rows_of(sys.argv[3], sys.argv[4])
    table(sys.argv[1], a)
    table(sys.argv[3], b)
    ib = {(r['key'], r['side']): r for r in b}
    pairs = [(r, ib[(r['key'], r['side'])]) for r in a if (r['key'], r['side']) in ib]
    total = sum(x['off'] - y['off'] for x, y in pairs)
    print('\npaired: %d sides, offset change A - B total %+.2f px, mean %+.4f px' % (len(pairs), total, total / len(pairs)))
    print('| fit in A | fit in B | sides | A mean px | B mean px | change px | share of the change % |')
    print('|---|---|---|---|---|---|---|')
    groups = defaultdict(list)
    for x, y in pairs:
        groups[(qband(x), y['kind'])].append((x, y))
    for g in sorted(groups, key=lambda g: -abs(sum(x['off'] - y['off'] for x, y in groups[g]))):
        sel = groups[g]
        d = sum(x['off'] - y['off'] for x, y in sel)
        print('| %s | %s | %d | %+.4f | %+.4f | %+.4f | %+.0f |' % (
            g[0], g[1], len(sel), sum(x['off'] for x, _ in sel) / len(sel), sum(y['off'] for _, y in sel) / len(sel),
            d / len(sel), 100 * d / total))
    print('\npaired by the smaller corner angle (deg):')
    print('| angle | sides | change px | share % |')
    print('|---|---|---|---|')
    for lo, hi in ((0, 50), (50, 60), (60, 70), (70, 80), (80, 91)):
        sel = [(x, y) for x, y in pairs if lo <= x['amin'] < hi]
        if sel:
            d = sum(x['off'] - y['off'] for x, y in sel)
            print('| %g-%g | %d | %+.4f | %+.0f |' % (lo, hi, len(sel), d / len(sel), 100 * d / total))


if __name__ == '__main__':
    main()
