#!/usr/bin/env python3
"""Tables from diag_hard's corner CSV (bench/detector/diag_hard.cc).

  summary FILE...   per variant: corners, offset (mean of the two normal components), median |error|,
                    by size band and view band
  repeats FILE      per corner over its noise draws: the median of the corners' mean error (bias) and
                    of their draws' scatter, the median error with the bias removed / the scatter removed
"""
import csv, math, sys
from collections import defaultdict


def median(v):
    v = sorted(v)
    n = len(v)
    return float('nan') if n == 0 else (v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2]))


def mean(v):
    return sum(v) / len(v) if v else float('nan')


def rows(files):
    for f in files:
        for r in csv.DictReader(open(f)):
            if r.get('n_after') in (None, ''):
                continue  # a line still being written
            for k in ('side_px', 'view_deg', 'corner_deg', 'ex', 'ey', 'n_before', 'n_after'):
                r[k] = float(r[k])
            yield r


def size_band(r):
    return '15-25' if r['side_px'] < 25 else '25-40' if r['side_px'] < 40 else '40-60'


def view_band(r):
    return '0-40' if r['view_deg'] < 40 else '40-60' if r['view_deg'] < 60 else '60-75'


def fig(rs):
    off = mean([0.5 * (r['n_before'] + r['n_after']) for r in rs])
    med = median([math.hypot(r['ex'], r['ey']) for r in rs])
    return '%+.3f / %.3f' % (off, med)


def summary(files):
    by = defaultdict(list)
    for r in rows(files):
        by[r['variant']].append(r)
    bands = [('size', b, size_band) for b in ('15-25', '25-40', '40-60')] + \
            [('view', b, view_band) for b in ('0-40', '40-60', '60-75')]
    print('| variant | corners | all | ' + ' | '.join(b for _, b, _ in bands) + ' |')
    print('|---' * (3 + len(bands)) + '|')
    for v, rs in by.items():
        cells = [fig([r for r in rs if f(r) == b]) for _, b, f in bands]
        print('| %s | %d | %s | %s |' % (v, len(rs), fig(rs), ' | '.join(cells)))


def repeats(files):
    corners = defaultdict(list)
    for r in rows(files):
        corners[(r['variant'], r['cell'], r['image'], r['id'], r['corner'])].append(r)
    by = defaultdict(list)
    for key, rs in corners.items():
        if len(rs) < 2:
            continue
        by[key[0]].append(rs)
    print('| variant | corners x draws | median error | median of mean error (bias) | rms scatter per axis '
          '| median error, bias removed | offset of means | bias along normals rms |')
    print('|---|---|---|---|---|---|---|---|')
    for v, cs in by.items():
        errs, bias, noise_only, sq, nb = [], [], [], [], []
        for rs in cs:
            mx, my = mean([r['ex'] for r in rs]), mean([r['ey'] for r in rs])
            bias.append(math.hypot(mx, my))
            nb += [mean([r['n_before'] for r in rs]), mean([r['n_after'] for r in rs])]
            n = len(rs)
            for r in rs:
                errs.append(math.hypot(r['ex'], r['ey']))
                noise_only.append(math.hypot(r['ex'] - mx, r['ey'] - my) * math.sqrt(n / (n - 1)))
                sq.append(((r['ex'] - mx) ** 2 + (r['ey'] - my) ** 2) * n / (n - 1) / 2)
        print('| %s | %d x %d | %.3f | %.3f | %.3f | %.3f | %+.3f | %.3f |' % (
            v, len(cs), len(cs[0]), median(errs), median(bias), math.sqrt(mean(sq)), median(noise_only),
            0.5 * mean(nb), math.sqrt(mean([x * x for x in nb]))))


if __name__ == '__main__':
    {'summary': summary, 'repeats': repeats}[sys.argv[1]](sys.argv[2:])
