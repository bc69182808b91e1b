#!/usr/bin/env python3
"""The side fits behind bench_imaging_maps' corner dumps (issue 15, helper brightsurf). Reads the trace of
2026-12-08-brightsurf-trace.patch (MCMT_SIDE_TRACE=FILE: each model pass's side fit) and the dump
(MCMT_IMAGING_DUMP) of the same run; keeps each marker's last refinement and each side's last fit, joins
them to the side's true offset (outward +, px; roles as 2026-12-07-seeds13-split.py).
  python3 2026-12-08-brightsurf-trace.py TRACE CSV [TRACE0 CSV0]
With the second pair (the same scene without blur), also the paired changes on the markers both found."""
import math, sys
from collections import defaultdict
from corner_dump import marker_rows, side_roles, truth_and_error

F = ('ref id pass side cell e sigma L0 L1 S1 S2 q gamma single step detr refit paper e0 q0 S1_0 S2_0 reach '
     'outer_res outer_data dip rise plateau_res').split()


def load_trace(path):
    fits = {}
    cam = seq = None
    last_ref = {}
    for line in open(path):
        w = line.split()
        if w[0] == 'F':
            cam, seq = w[1], w[2]
            continue
        d = dict(zip(F, [float(x) if x not in ('nan', '+nan', '-nan') else float('nan') for x in w[1:]]))
        key = (cam, seq, str(int(d['id'])))
        if last_ref.get(key, -1) != d['ref']:
            if last_ref.get(key, -1) < d['ref']:
                last_ref[key] = d['ref']
                fits[key] = {}
            else:
                continue
        fits[key][int(d['side'])] = d  # the last pass's fit of the side
    return fits




def join(trace, csv):
    fits = load_trace(trace)
    rows = {}
    for key, c in marker_rows(csv).items():
        if key not in fits: continue
        s = side_roles(*truth_and_error(c))
        for k in range(4):
            if k in fits[key]:
                rows[key + (k,)] = dict(fits[key][k], off=s[k]['off'], role=s[k]['role'])
    return rows


def plin(r):  # the paper's level in linear light at the fit's gamma (LinearPaper)
    return 255.0 * (r['paper'] / 255.0) ** r['gamma']


def mean(v):
    v = [x for x in v if not math.isnan(x)]
    return sum(v) / len(v) if v else float('nan')


def se(v):
    v = [x for x in v if not math.isnan(x)]
    n = len(v)
    if n < 2: return float('nan')
    m = sum(v) / n
    return math.sqrt(sum((x - m) ** 2 for x in v) / (n - 1) / n)


COLS = [('off', lambda r: r['off']), ('sigma', lambda r: r['sigma']), ('S1-P', lambda r: r['S1'] - plin(r)),
        ('S2-P', lambda r: r['S2'] - plin(r)), ('L0', lambda r: r['L0']), ('q c', lambda r: r['q']), ('single', lambda r: r['single']),
        ('step', lambda r: 0 if math.isnan(r['step']) else 1), ('refit', lambda r: r['refit'] > 0),
        ('detr', lambda r: r['detr']), ('reach c', lambda r: r['reach']), ('outres', lambda r: r['outer_res']),
        ('platres', lambda r: r['plateau_res']), ('dip c', lambda r: r['dip']), ('rise', lambda r: r['rise']),
        ('e-e0', lambda r: r['e'] - r['e0'])]


def table(rows, title, groups):
    print('\n%s\n' % title)
    print('| group | sides | ' + ' | '.join(c for c, _ in COLS) + ' |')
    print('|---' * (len(COLS) + 2) + '|')
    for name, sel in groups:
        v = [r for r in rows if sel(r)]
        if len(v) < 2: continue
        cells = []
        for c, f in COLS:
            m = mean([float(f(r)) for r in v])
            cells.append('%+.4f (%.4f)' % (m, se([float(f(r)) for r in v])) if c == 'off' else '%.3f' % m)
        print('| %s | %d | %s |' % (name, len(v), ' | '.join(cells)))


ROLE = [('all', lambda r: True)] + [(x, (lambda x: lambda r: r['role'] == x)(x))
                                     for x in ('top', 'bottom', 'near', 'far')]
A = join(sys.argv[1], sys.argv[2])
table(A.values(), 'A: ' + sys.argv[1], ROLE + [
    ('bottom, S1 > S2', lambda r: r['role'] == 'bottom' and r['S1'] > r['S2']),
    ('bottom, S1 <= S2', lambda r: r['role'] == 'bottom' and r['S1'] <= r['S2']),
    ('bottom, q > 1.5 c', lambda r: r['role'] == 'bottom' and r['q'] > 1.5),
    ('bottom, q <= 1.5 c', lambda r: r['role'] == 'bottom' and r['q'] <= 1.5),
    ('bottom, detrended', lambda r: r['role'] == 'bottom' and r['detr'] > 0),
    ('bottom, step found', lambda r: r['role'] == 'bottom' and not math.isnan(r['step'])),
    ('bottom, single', lambda r: r['role'] == 'bottom' and r['single'] > 0),
    ('all, S1 > S2', lambda r: r['S1'] > r['S2']), ('all, S1 <= S2', lambda r: r['S1'] <= r['S2'])])
if len(sys.argv) > 4:
    B = join(sys.argv[3], sys.argv[4])
    table(B.values(), 'B: ' + sys.argv[3], ROLE + [
        ('bottom, single', lambda r: r['role'] == 'bottom' and r['single'] > 0),
        ('bottom, two-level', lambda r: r['role'] == 'bottom' and r['single'] == 0),
        ('all, single', lambda r: r['single'] > 0), ('all, two-level', lambda r: r['single'] == 0)])
    both = [k for k in A if k in B]
    print('\npaired A - B (%d sides)\n' % len(both))
    print('| group | sides | ' + ' | '.join(c for c, _ in COLS) + ' |')
    print('|---' * (len(COLS) + 2) + '|')
    PAIR = [(n, (lambda f: lambda k: f(A[k]))(f)) for n, f in ROLE] + [
        ('single in both', lambda k: A[k]['single'] > 0 and B[k]['single'] > 0),
        ('single with blur only', lambda k: A[k]['single'] > 0 and B[k]['single'] == 0),
        ('single without blur only', lambda k: A[k]['single'] == 0 and B[k]['single'] > 0),
        ('two-level in both', lambda k: A[k]['single'] == 0 and B[k]['single'] == 0),
        ('bottom, single in both', lambda k: A[k]['role'] == 'bottom' and A[k]['single'] > 0 and B[k]['single'] > 0),
        ('bottom, single with blur only', lambda k: A[k]['role'] == 'bottom' and A[k]['single'] > 0 and B[k]['single'] == 0),
        ('bottom, two-level in both', lambda k: A[k]['role'] == 'bottom' and A[k]['single'] == 0 and B[k]['single'] == 0)]
    for name, sel in PAIR:
        ks = [k for k in both if sel(k)]
        if len(ks) < 2: continue
        cells = []
        for c, f in COLS:
            d = [float(f(A[k])) - float(f(B[k])) for k in ks]
            cells.append('%+.4f (%.4f)' % (mean(d), se(d)) if c == 'off' else '%+.3f' % mean(d))
        print('| %s | %d | %s |' % (name, len(ks), ' | '.join(cells)))
