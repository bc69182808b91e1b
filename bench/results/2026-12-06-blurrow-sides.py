#!/usr/bin/env python3
"""Per-side signed offsets (outward +, px) of bench_imaging_maps corner dumps (MCMT_IMAGING_DUMP) joined to
the side-model fits of the same run (DM_SIDE_DUMP=1 of 2026-12-06-blurrow-switches.patch: one DMSIDE line
on stderr per refined quad with each side's last fit), split by marker size, view angle, the side's cell
depth (true geometry) and fit type, with the fitted blur sigma and gamma of each band. Given a second
run (DUMP2 SIDES2) the sides present in both are paired and the second run's offset change is shown.
  python3 2026-12-06-blurrow-sides.py DUMP.csv SIDES.txt [DUMP2.csv SIDES2.txt]"""
import importlib.util, os, sys

here = os.path.dirname(os.path.abspath(__file__))
spec = importlib.util.spec_from_file_location('dm', os.path.join(here, '2026-12-06-darkmap-sides.py'))
dm = importlib.util.module_from_spec(spec)
sys_argv = sys.argv
sys.argv = ['x']
src = open(os.path.join(here, '2026-12-06-darkmap-sides.py')).read().replace('\nmain()\n', '\n')
exec(compile(src, 'darkmap-sides', 'exec'), dm.__dict__)
sys.argv = sys_argv


def side_rows(dump, sides):
    index = dm.side_lines(sides)
    out = {}
    for key, t, e, size, view in dm.dump_markers(dump):
        det = [(t[k][0] + e[k][0], t[k][1] + e[k][1]) for k in range(4)]
        hit = dm.find(index, det)
        area = sum(t[k][0] * t[(k + 1) % 4][1] - t[(k + 1) % 4][0] * t[k][1] for k in range(4))
        fit_of = {}
        if hit:
            m, sd = hit
            for j in range(4):
                a, b = m[j], m[(j + 1) % 4]
                k = a if (a + 1) % 4 == b else b if (b + 1) % 4 == a else None
                if k is not None:
                    fit_of[k] = sd[j]
        for k in range(4):
            a, b = t[k], t[(k + 1) % 4]
            vx, vy = b[0] - a[0], b[1] - a[1]
            L = (vx * vx + vy * vy) ** 0.5
            nx, ny = (vy / L, -vx / L) if area > 0 else (-vy / L, vx / L)
            off = ((e[k][0] + e[(k + 1) % 4][0]) * nx + (e[k][1] + e[(k + 1) % 4][1]) * ny) / 2
            c, d = t[(k + 2) % 4], t[(k + 3) % 4]
            mid = ((c[0] + d[0]) / 2, (c[1] + d[1]) / 2)
            depth = abs((mid[0] - a[0]) * nx + (mid[1] - a[1]) * ny) / 8
            fit = fit_of.get(k)
            kind = 'unmatched' if fit is None else 'not modelled' if not fit['modelled'] else \
                ('one level' if fit['single'] else 'two levels')
            out[key + (k,)] = dict(off=off, size=size, view=view, depth=depth, kind=kind, fit=fit)
    return out


def mean(xs):
    return sum(xs) / len(xs) if xs else float('nan')


def table(rows, other=None):
    print('| split | band | sides | mean offset px | fitted sigma px | fitted gamma |%s' %
          (' paired | offset change px |' if other is not None else ''))
    print('|---|---|---|---|---|---|%s' % ('---|---|' if other is not None else ''))

    def line(split, name, keys):
        if not keys:
            return
        sel = [rows[k] for k in keys]
        fits = [r['fit'] for r in sel if r['fit'] and r['fit']['modelled']]
        s = '| %s | %s | %d | %+.4f | %.3f | %.3f |' % (split, name, len(sel), mean([r['off'] for r in sel]),
                                                     mean([f['sigma'] for f in fits]),
                                                     mean([f['gamma'] for f in fits]))
        if other is not None:
            both = [k for k in keys if k in other]
            s += ' %d | %+.4f |' % (len(both), mean([other[k]['off'] - rows[k]['off'] for k in both]))
        print(s)

    ks = list(rows)
    line('all', 'all', ks)
    for lo, hi in ((0, 13), (13, 15), (15, 20), (20, 25), (25, 100)):
        line('marker px', '%g-%g' % (lo, hi), [k for k in ks if lo <= rows[k]['size'] < hi])
    for lo, hi in ((0, 20), (20, 40), (40, 50), (50, 60), (60, 75), (75, 90)):
        line('view deg', '%g-%g' % (lo, hi), [k for k in ks if lo <= rows[k]['view'] < hi])
    for lo, hi in ((0, 1.0), (1.0, 1.5), (1.5, 2.0), (2.0, 2.5), (2.5, 3.0), (3.0, 10)):
        line('cell depth px', '%g-%g' % (lo, hi), [k for k in ks if lo <= rows[k]['depth'] < hi])
    for kind in ('two levels', 'one level', 'not modelled', 'unmatched'):
        line('last fit', kind, [k for k in ks if rows[k]['kind'] == kind])
    for lo, hi in ((0, 1.0), (1.0, 1.2), (1.2, 1.4), (1.4, 1.6), (1.6, 9)):
        line('fitted sigma px', '%g-%g' % (lo, hi),
             [k for k in ks if rows[k]['fit'] and rows[k]['fit']['modelled'] and lo <= rows[k]['fit']['sigma'] < hi])
    for lo, hi in ((0, 1.6), (1.6, 2.0), (2.0, 2.4), (2.4, 2.8), (2.8, 9)):
        line('fitted gamma', '%g-%g' % (lo, hi),
             [k for k in ks if rows[k]['fit'] and rows[k]['fit']['modelled'] and lo <= rows[k]['fit']['gamma'] < hi])


a = side_rows(sys.argv[1], sys.argv[2])
b = side_rows(sys.argv[3], sys.argv[4]) if len(sys.argv) > 4 else None
print('%s: %d sides' % (sys.argv[1], len(a)))
table(a, b)
