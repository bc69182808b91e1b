#!/usr/bin/env python3
"""Why each side of a bench_imaging_maps run was fitted with one surround level, from the FM fields of
2026-12-06-faintmargin-dump.patch's DMSIDE lines (per side: reason 1 faint, 2 unseen, 3 halo, 4 contrast,
5 kept one level from the previous pass (warm), 0 two levels kept; and the two-level fit before the
refit: q / cell, S1, S2, e), joined to the corner dump by 2026-12-06-nomargin-sides.py's rows_of.
  python3 2026-12-06-faintmargin-reasons.py DUMP.csv SIDES.txt"""
import collections, importlib.util, os, sys

here = os.path.dirname(os.path.abspath(__file__))
spec = importlib.util.spec_from_file_location('nm', os.path.join(here, '2026-12-06-nomargin-sides.py'))
nm = importlib.util.module_from_spec(spec)
spec.loader.exec_module(nm)


def side_lines(path):
    out = collections.defaultdict(list)
    for line in open(path, errors='replace'):
        if not line.startswith('DMSIDE '):
            continue
        f = line.split()[1:]
        i = f.index('FM')
        corners = [(float(f[2 * k]), float(f[2 * k + 1])) for k in range(4)]
        sides = []
        for j in range(4):
            v = f[8 + 10 * j:18 + 10 * j]
            w = f[i + 6 * j:i + 6 * j + 6]
            sides.append(dict(modelled=int(v[0]), single=int(v[1]), cell=float(v[2]), q=float(v[3]),
                              s1=float(v[4]), s2=float(v[5]), l0=float(v[6]), l1=float(v[7]),
                              sigma=float(v[8]), gamma=float(v[9]), paper=float(f[48]), dark=0,
                              reason=int(w[1]), q2=float(w[2]), s1_2=float(w[3]), s2_2=float(w[4]),
                              e2=float(w[5])))
        out[(round(corners[0][0]), round(corners[0][1]))].append((corners, sides))
    return out


def main():
    nm.side_lines = side_lines
    rows = nm.rows_of(sys.argv[1], sys.argv[2])
    total = sum(r['off'] for r in rows)
    print('%s: %d sides, total %+.2f px' % (sys.argv[1], len(rows), total))
    names = {0: 'two levels kept', 1: 'faint', 2: 'unseen', 3: 'halo', 4: 'contrast', 5: 'one level kept (warm)'}
    med = lambda v: sorted(v)[len(v) // 2]
    g = collections.defaultdict(list)
    for r in rows:
        if r['fit'] and r['fit']['modelled']:
            g[(r['kind'], r['fit']['reason'])].append(r)
    print('| fit | reason | sides | mean offset px | share % | two-level fit before: q/cell | S1-P | S2-P | e px | smaller angle < 60 deg |')
    print('|---|---|---|---|---|---|---|---|---|---|')
    for k in sorted(g):
        sel = g[k]
        s = sum(r['off'] for r in sel)
        f = [r['fit'] for r in sel]
        two = k[1] != 0
        print('| %s | %s | %d | %+.4f | %+.0f | %s | %s | %s | %s | %d |' % (
            k[0], names[k[1]], len(sel), s / len(sel), 100 * s / total,
            '%.2f' % med([x['q2'] for x in f]) if two else '',
            '%+.1f' % med([x['s1_2'] - x['paper'] for x in f]) if two else '',
            '%+.1f' % med([x['s2_2'] - x['paper'] for x in f]) if two else '',
            '%+.3f' % med([x['e2'] for x in f]) if two else '', sum(1 for r in sel if r['amin'] < 60)))


if __name__ == '__main__':
    main()
