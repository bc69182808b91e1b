#!/usr/bin/env python3
"""Per-side signed offsets of a bench_imaging_maps corner dump (MCMT_IMAGING_DUMP), joined to the side-model
fits of the same run (DM_SIDE_DUMP=1 of 2026-12-06-darkmap-side-dump.patch: one DMSIDE line on stderr per
refined quad with its corners and each side's last model fit). Splits the mean outward offset of each side
(px; negative: inward) by marker size, view angle, the side's direction in the image and in the marker,
the side's cell depth and whether its last fit used one surround level or the two-level (margin) model.
  python3 2026-12-06-darkmap-sides.py DUMP.csv SIDES.txt"""
import csv, math, sys
from collections import defaultdict


def dump_markers(path):
    groups = defaultdict(dict)
    for r in csv.DictReader(open(path)):
        groups[(r['camera'], r['seq'], r['id'])][int(r['corner'])] = r
    for key, g in groups.items():
        if len(g) != 4:
            continue
        t = [(float(g[k]['x']), float(g[k]['y'])) for k in range(4)]
        e = [(float(g[k]['dx']), float(g[k]['dy'])) for k in range(4)]
        yield key, t, e, float(g[0]['size_px']), float(g[0]['view_deg'])


def side_lines(path):
    index = defaultdict(list)
    for line in open(path, errors='replace'):
        if not line.startswith('DMSIDE '):
            continue
        f = line.split()[1:]
        corners = [(float(f[2 * k]), float(f[2 * k + 1])) for k in range(4)]
        sides = []
        for j in range(4):
            v = f[8 + 10 * j: 18 + 10 * j]
            sides.append(dict(modelled=int(v[0]), single=int(v[1]), cell=float(v[2]), q=float(v[3]),
                              s1=float(v[4]), s2=float(v[5]), l0=float(v[6]), l1=float(v[7]),
                              sigma=float(v[8]), gamma=float(v[9]), paper=float(f[48])))
        rec = (corners, sides)
        index[(round(corners[0][0]), round(corners[0][1]))].append(rec)
    return index


def find(index, det):
    x, y = det[0]
    best = None
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for corners, sides in index.get((round(x) + dx, round(y) + dy), []):
                # refined corner j -> dump corner m[j]
                m = []
                for c in corners:
                    d = [math.hypot(c[0] - p[0], c[1] - p[1]) for p in det]
                    k = min(range(4), key=lambda i: d[i])
                    if d[k] > 0.02:
                        break
                    m.append(k)
                if len(m) == 4 and len(set(m)) == 4:
                    best = (m, sides)
    return best


def main():
    index = side_lines(sys.argv[2])
    rows = []
    unmatched = 0
    for key, t, e, size, view in dump_markers(sys.argv[1]):
        det = [(t[k][0] + e[k][0], t[k][1] + e[k][1]) for k in range(4)]
        hit = find(index, det)
        area = sum(t[k][0] * t[(k + 1) % 4][1] - t[(k + 1) % 4][0] * t[k][1] for k in range(4))
        fit_of = {}
        if hit:
            m, sides = hit
            for j in range(4):
                a, b = m[j], m[(j + 1) % 4]
                k = a if (a + 1) % 4 == b else b if (b + 1) % 4 == a else None
                if k is not None:
                    fit_of[k] = sides[j]
        else:
            unmatched += 1
        for k in range(4):
            a, b = t[k], t[(k + 1) % 4]
            vx, vy = b[0] - a[0], b[1] - a[1]
            L = math.hypot(vx, vy)
            nx, ny = (vy / L, -vx / L) if area > 0 else (-vy / L, vx / L)
            off = ((e[k][0] + e[(k + 1) % 4][0]) * nx + (e[k][1] + e[(k + 1) % 4][1]) * ny) / 2
            # cell depth: distance from the side's line to the opposite side's midpoint over 8 cells
            c, d = t[(k + 2) % 4], t[(k + 3) % 4]
            mid = ((c[0] + d[0]) / 2, (c[1] + d[1]) / 2)
            depth = abs((mid[0] - a[0]) * nx + (mid[1] - a[1]) * ny) / 8
            ang = math.degrees(math.atan2(ny, nx)) % 360
            img_dir = 'right' if ang < 45 or ang >= 315 else 'down' if ang < 135 else 'left' if ang < 225 else 'up'
            fit = fit_of.get(k)
            kind = 'unmatched' if fit is None else 'not modelled' if not fit['modelled'] else \
                ('one level' if fit['single'] else 'two levels')
            rows.append(dict(off=off, size=size, view=view, side=k, img=img_dir, depth=depth, kind=kind,
                             fit=fit, L=L))
    n = len(rows)
    print('%s: %d sides of %d markers, %d markers without a DMSIDE line' % (sys.argv[1], n, n // 4, unmatched))
    print('| split | band | sides | share % | mean offset px | sum share of all sides\' offset % |')
    print('|---|---|---|---|---|---|')
    total = sum(r['off'] for r in rows)

    def line(split, name, sel):
        if not sel:
            return
        s = sum(r['off'] for r in sel)
        print('| %s | %s | %d | %.1f | %+.4f | %+.0f |' % (split, name, len(sel), 100.0 * len(sel) / n,
                                                           s / len(sel), 100.0 * s / total if total else 0))

    line('all', 'all', rows)
    for lo, hi in ((0, 15), (15, 20), (20, 25), (25, 100)):
        line('marker px', '%g-%g' % (lo, hi), [r for r in rows if lo <= r['size'] < hi])
    for lo, hi in ((0, 20), (20, 40), (40, 50), (50, 60), (60, 90)):
        line('view deg', '%g-%g' % (lo, hi), [r for r in rows if lo <= r['view'] < hi])
    for k in range(4):
        line('marker side', '%d (corners %d-%d)' % (k, k, (k + 1) % 4), [r for r in rows if r['side'] == k])
    for d in ('up', 'down', 'left', 'right'):
        line('image normal', d, [r for r in rows if r['img'] == d])
    for lo, hi in ((0, 1.6), (1.6, 1.9), (1.9, 2.2), (2.2, 2.6), (2.6, 10)):
        line('cell depth px', '%g-%g' % (lo, hi), [r for r in rows if lo <= r['depth'] < hi])
    for kind in ('two levels', 'one level', 'not modelled', 'unmatched'):
        line('last fit', kind, [r for r in rows if r['kind'] == kind])
    for kind in ('two levels', 'one level'):
        for lo, hi in ((0, 1.9), (1.9, 2.2), (2.2, 10)):
            line('last fit x depth', '%s, %g-%g px' % (kind, lo, hi),
                 [r for r in rows if r['kind'] == kind and lo <= r['depth'] < hi])
    two = [r['fit'] for r in rows if r['kind'] == 'two levels']
    if two:
        qs = sorted(f['q'] for f in two)
        ex = sorted((f['s1'] - f['s2']) / (f['l1'] - f['l0']) if f['l1'] != f['l0'] else 0 for f in two)
        print('\ntwo-level sides: q/cell p25 %.2f median %.2f p75 %.2f; (S1-S2)/(L1-L0) p25 %.3f median %.3f '
              'p75 %.3f' % (qs[len(qs) // 4], qs[len(qs) // 2], qs[3 * len(qs) // 4], ex[len(ex) // 4],
                            ex[len(ex) // 2], ex[3 * len(ex) // 4]))
        for lo, hi in ((0, 0.4), (0.4, 0.7), (0.7, 1.2), (1.2, 99)):
            sel = [r for r in rows if r['kind'] == 'two levels' and lo <= r['fit']['q'] < hi]
            line('two-level q/cell', '%g-%g' % (lo, hi), sel)
    # the margin's fitted level against the marker's paper level, in parts of the border-to-code contrast
    def excess(f):
        return (f['s1'] - f['paper']) / (f['l1'] - f['l0']) if f['l1'] != f['l0'] and f['paper'] > 0 else float('nan')
    two_rows = [r for r in rows if r['kind'] == 'two levels']
    if two_rows:
        at_bound = [r for r in two_rows if r['fit']['s1'] > 274.5]
        print('two-level sides with S1 at its bound 275: %d of %d (%.1f %%), mean offset %+.4f px' % (
            len(at_bound), len(two_rows), 100.0 * len(at_bound) / len(two_rows),
            sum(r['off'] for r in at_bound) / max(1, len(at_bound))))
        ex = sorted(excess(r['fit']) for r in two_rows if not math.isnan(excess(r['fit'])))
        print('(S1 - paper) / (L1 - L0): p25 %+.3f median %+.3f p75 %+.3f' % (
            ex[len(ex) // 4], ex[len(ex) // 2], ex[3 * len(ex) // 4]))
        for lo, hi in ((-9, -0.1), (-0.1, -0.02), (-0.02, 0.02), (0.02, 0.1), (0.1, 0.2), (0.2, 9)):
            line('(S1-P)/(L1-L0)', '%g..%g' % (lo, hi), [r for r in two_rows if lo <= excess(r['fit']) < hi])
    allfit = [r['fit'] for r in rows if r['fit']]
    if allfit:
        sg = sorted(f['sigma'] for f in allfit)
        gm = sorted(f['gamma'] for f in allfit)
        print('sigma median %.2f px, gamma median %.2f' % (sg[len(sg) // 2], gm[len(gm) // 2]))


main()
