#!/usr/bin/env python3
"""Per-side signed offsets (px, + outward) of a bench_imaging_maps corner dump (MCMT_IMAGING_DUMP) joined
to the side-model fits of the same run (DM_SIDE_DUMP=1 of 2026-12-06-nomargin-dump.patch: one DMSIDE line
per refined quad, its corners, each side's last fit and, at the end, the number of border-coloured cells in
each side's first code row). Reuses 2026-12-06-darkmap-sides.py's join; splits by fit type x size / view /
image direction / dark cells next to the side / fitted gamma / blur, and prints the share of the total.
  python3 2026-12-06-nomargin-sides.py DUMP.csv SIDES.txt"""
import csv, math, sys
from collections import defaultdict
import importlib.util, os

here = os.path.dirname(os.path.abspath(__file__))


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
        dark = [int(x) for x in f[49:53]] if len(f) >= 53 else [-1] * 4
        sides = []
        for j in range(4):
            v = f[8 + 10 * j: 18 + 10 * j]
            sides.append(dict(modelled=int(v[0]), single=int(v[1]), cell=float(v[2]), q=float(v[3]),
                              s1=float(v[4]), s2=float(v[5]), l0=float(v[6]), l1=float(v[7]),
                              sigma=float(v[8]), gamma=float(v[9]), paper=float(f[48]), dark=dark[j]))
        index[(round(corners[0][0]), round(corners[0][1]))].append((corners, sides))
    return index


def find(index, det):
    x, y = det[0]
    best = None
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for corners, sides in index.get((round(x) + dx, round(y) + dy), []):
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


def corner_angle(t, k):
    """The quad's interior angle at corner k, deg."""
    a, b, c = t[(k - 1) % 4], t[k], t[(k + 1) % 4]
    v1, v2 = (a[0] - b[0], a[1] - b[1]), (c[0] - b[0], c[1] - b[1])
    cos = (v1[0] * v2[0] + v1[1] * v2[1]) / math.hypot(*v1) / math.hypot(*v2)
    return math.degrees(math.acos(max(-1.0, min(1.0, cos))))


def rows_of(dump, sides_path):
    index = side_lines(sides_path)
    rows = []
    for key, t, e, size, view in dump_markers(dump):
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
        for k in range(4):
            a, b = t[k], t[(k + 1) % 4]
            vx, vy = b[0] - a[0], b[1] - a[1]
            L = math.hypot(vx, vy)
            nx, ny = (vy / L, -vx / L) if area > 0 else (-vy / L, vx / L)
            off = ((e[k][0] + e[(k + 1) % 4][0]) * nx + (e[k][1] + e[(k + 1) % 4][1]) * ny) / 2
            ang = math.degrees(math.atan2(ny, nx)) % 360
            img = 'right' if ang < 45 or ang >= 315 else 'down' if ang < 135 else 'left' if ang < 225 else 'up'
            fit = fit_of.get(k)
            kind = 'unmatched' if fit is None else 'not modelled' if not fit['modelled'] else \
                ('one level' if fit['single'] else 'two levels')
            a0, a1 = corner_angle(t, k), corner_angle(t, (k + 1) % 4)
            d0 = e[k][0] * nx + e[k][1] * ny
            d1 = e[(k + 1) % 4][0] * nx + e[(k + 1) % 4][1] * ny
            rows.append(dict(off=off, size=size, view=view, img=img, kind=kind, fit=fit, key=key, side=k,
                             amin=min(a0, a1), acute=d0 if a0 < a1 else d1, obtuse=d1 if a0 < a1 else d0))
    return rows


def main():
    rows = rows_of(sys.argv[1], sys.argv[2])
    n = len(rows)
    total = sum(r['off'] for r in rows)
    print('%s: %d sides; total offset %+.2f px (mean %+.4f)' % (sys.argv[1], n, total, total / n))
    print('| split | band | sides | mean offset px | share of the total % |')
    print('|---|---|---|---|---|')

    def line(split, name, sel):
        if sel:
            s = sum(r['off'] for r in sel)
            print('| %s | %s | %d | %+.4f | %+.0f |' % (split, name, len(sel), s / len(sel), 100 * s / total))

    kinds = ('one level', 'two levels')
    for kind in kinds + ('not modelled', 'unmatched'):
        line('fit', kind, [r for r in rows if r['kind'] == kind])
    for kind in kinds:
        K = [r for r in rows if r['kind'] == kind]
        for lo, hi in ((0, 15), (15, 20), (20, 100)):
            line(kind + ' x px', '%g-%g' % (lo, hi), [r for r in K if lo <= r['size'] < hi])
        for lo, hi in ((0, 40), (40, 55), (55, 65), (65, 90)):
            line(kind + ' x deg', '%g-%g' % (lo, hi), [r for r in K if lo <= r['view'] < hi])
        for d in ('up', 'down', 'left', 'right'):
            line(kind + ' x normal', d, [r for r in K if r['img'] == d])
        for lo, hi in ((0, 1), (1, 3), (3, 5), (5, 7)):
            line(kind + ' x dark cells in row 1', '%d-%d' % (lo, hi - 1), [r for r in K if lo <= r['fit']['dark'] < hi])
        for lo, hi in ((0, 0.9), (0.9, 0.97), (0.97, 1.03), (1.03, 1.1), (1.1, 9)):
            line(kind + ' x gamma', '%g-%g' % (lo, hi), [r for r in K if lo <= r['fit']['gamma'] < hi])
        for lo, hi in ((0, 0.6), (0.6, 0.7), (0.7, 0.8), (0.8, 0.9), (0.9, 9)):
            line(kind + ' x sigma px', '%g-%g' % (lo, hi), [r for r in K if lo <= r['fit']['sigma'] < hi])
        for lo, hi in ((0, 1.6), (1.6, 2.0), (2.0, 2.4), (2.4, 9)):
            line(kind + ' x cell px', '%g-%g' % (lo, hi), [r for r in K if lo <= r['fit']['cell'] < hi])
    for kind in kinds:
        K = [r for r in rows if r['kind'] == kind]
        for lo, hi in ((0, 45), (45, 50), (50, 55), (55, 60), (60, 70), (70, 80), (80, 91)):
            line(kind + ' x smaller corner angle deg', '%g-%g' % (lo, hi), [r for r in K if lo <= r['amin'] < hi])
    print('\n| fit | smaller corner angle deg | sides | normal error at the acute end px | at the obtuse end px |')
    print('|---|---|---|---|---|')
    for kind in kinds:
        for lo, hi in ((0, 60), (60, 75), (75, 91)):
            sel = [r for r in rows if r['kind'] == kind and lo <= r['amin'] < hi]
            if sel:
                print('| %s | %g-%g | %d | %+.4f | %+.4f |' % (kind, lo, hi, len(sel), sum(r['acute'] for r in sel) / len(sel),
                                                          sum(r['obtuse'] for r in sel) / len(sel)))
    one = [r for r in rows if r['kind'] == 'one level']
    if one:
        def med(v):
            v = sorted(v)
            return v[len(v) // 2]
        print('\none level: median S %.1f L0 %.1f L1 %.1f sigma %.3f gamma %.3f' % (
            med([r['fit']['s1'] for r in one]), med([r['fit']['l0'] for r in one]),
            med([r['fit']['l1'] for r in one]), med([r['fit']['sigma'] for r in one]),
            med([r['fit']['gamma'] for r in one])))


if __name__ == '__main__':
    main()
