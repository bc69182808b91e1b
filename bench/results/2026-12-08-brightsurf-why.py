#!/usr/bin/env python3
"""Why the side fits of a brightsurf trace (2026-12-08-brightsurf-trace.patch, MCMT_SIDE_TRACE) took one surround
level: per role, the last fit two-level or one-level with the reason of the pass that chose it (FitSideModels:
1 faint, 2 unseen, 4 halo, 8 margin at the border's level; 32 paper_reach, 64 levels inside bounds, 128 S1 within
kPaperMarginContrast of L1), and the two-level fit's levels there. Issue 15, helper brightsurf.
  python3 2026-12-08-brightsurf-why.py TRACE CSV"""
import sys, math
from collections import defaultdict, Counter
sys.path.insert(0, __import__('os').path.dirname(__import__('os').path.abspath(__file__)))
F = ('ref id pass side cell e sigma L0 L1 S1 S2 q gamma single step detr refit paper e0 q0 S1_0 S2_0 reach '
     'outer_res outer_data dip rise plateau_res why se sq sreach L0t L1t S1t S2t gt').split()
from corner_dump import marker_rows, side_roles, truth_and_error
def load(path):
    recs = defaultdict(list); cam = seq = None; last = {}
    for line in open(path):
        w = line.split()
        if w[0] == 'F': cam, seq = w[1], w[2]; continue
        d = dict(zip(F, [float(x) for x in w[1:]]))
        key = (cam, seq, str(int(d['id'])))
        if d['ref'] > last.get(key, -1): last[key] = d['ref']; recs[key] = []
        if d['ref'] == last[key]: recs[key].append(d)
    return recs
recs = load(sys.argv[1])
cnt = Counter(); offs = defaultdict(list); qs = defaultdict(list)
for key, c in marker_rows(sys.argv[2]).items():
    if key not in recs: continue
    s = side_roles(*truth_and_error(c))
    for k in range(4):
        fits = [d for d in recs[key] if int(d['side']) == k]
        if not fits: continue
        final = fits[-1]
        if final['single'] == 0: cls = 'two-level'
        else:
            first = [d for d in fits if d['single'] > 0 and int(d['why']) != 16]
            w = int(first[0]['why']) if first else -1
            cls = 'single why=%d (pass %d)' % (w, first[0]['pass'] if first else -1)
            cls = 'single why=%d' % w
            if first: qs[(s[k]['role'], w)].append((first[0]['sq'], first[0]['sreach'], first[0]['sigma'], first[0]['cell']))
        cnt[(s[k]['role'], cls)] += 1; offs[(s[k]['role'], cls)].append(s[k]['off'])
for key in sorted(cnt):
    v = offs[key]; m = sum(v)/len(v)
    extra = ''
    if (key[0], int(key[1].split('=')[1]) if '=' in key[1] else None) in qs:
        z = qs[(key[0], int(key[1].split('=')[1]))]
        extra = ' two-level fit before: q %.2f c, reach %.2f c, sigma %.2f px, cell %.2f px' % tuple(sum(x[i] for x in z)/len(z) for i in range(4))
    print('%s %s: %d sides, offset %+.4f%s' % (key[0], key[1], cnt[key], m, extra))
print('-- unseen (why=2) sides by the cause')
b = defaultdict(list)
for key, c in marker_rows(sys.argv[2]).items():
    if key not in recs: continue
    s = side_roles(*truth_and_error(c))
    for k in range(4):
        fits = [d for d in recs[key] if int(d['side']) == k]
        if not fits or fits[-1]['single'] == 0: continue
        first = [d for d in fits if d['single'] > 0 and int(d['why']) != 16]
        if not first or int(first[0]['why']) != 2: continue
        d = first[0]
        excess = (d['sq'] - d['sreach']) * d['cell'] / d['sigma']
        cause = ('cell<1.5' if d['cell'] < 1.5 else 'cell>=1.5') + (', beyond 2 sigma' if excess > 2 else ', within 2 sigma')
        b[(s[k]['role'] in ('bottom', 'far'), cause)].append(s[k]['off'])
for k in sorted(b):
    v = b[k]; print('bottom/far' if k[0] else 'top/near', k[1], len(v), '%+.4f' % (sum(v) / len(v)))
recs = load(sys.argv[1])  # (again)
b = defaultdict(list)
for key, c in marker_rows(sys.argv[2]).items():
    if key not in recs: continue
    s = side_roles(*truth_and_error(c))
    for k in range(4):
        fits = [d for d in recs[key] if int(d['side']) == k]
        if not fits or fits[-1]['single'] == 0: continue
        first = [d for d in fits if d['single'] > 0 and int(d['why']) != 16]
        if not first or not (int(first[0]['why']) & 2): continue
        d = first[0]; w = int(d['why'])
        cause = ('cell<1.5' if d['cell'] < 1.5 else 'cell>=1.5') + (' paper_reach' if w & 32 else '') + (' S1~L1' if w & 128 else ' S1!~L1')
        b[(s[k]['role'] in ('bottom', 'far'), cause)].append((s[k]['off'], d['L0t'], d['L1t'], d['S1t'], d['S2t'], d['gt'], (d['S1t'] - d['L1t']) / (d['L1t'] - d['L0t']), d['sq'], d['sreach'], d['pass'], d['sigma']))
print('role | cause | sides | offset | L0 | L1 | S1 | S2 | gamma | (S1-L1)/(L1-L0) | q c | reach c | pass | sigma')
for k in sorted(b):
    v = b[k]; m = [sum(x[i] for x in v) / len(v) for i in range(11)]
    print('bottom/far' if k[0] else 'top/near', '|', k[1], '|', len(v), '| %+.4f | %.1f | %.1f | %.1f | %.1f | %.3f | %+.3f | %.2f | %.2f | %.1f | %.2f' % tuple(m))
