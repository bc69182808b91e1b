#!/usr/bin/env python3
"""Classifies the crossing-line jumps of the single-side pass maps (overshoot's MCMT_X_PASSMAP, mode '-')
by which input of CrossingLine changed between the two grid neighbours (crossjump). Input: the
MCMT_X_CROSS_DEBUG file of crossjump's probe (per map point: F's corners' places along the side E, levels
L, use_clean U, clean/valid counts C, rays n, per ray i:out:along (px from F's line, outward) or i:v (not
valid) / i:c (not clean, skipped) / i:nan:nan (no crossing), FitLine's kept rays K), and optionally the
passmap file to restrict to pairs where d_out jumps (overshoot's jump rule).
Usage: 2026-12-07-crossjump-classify.py CROSS_DEBUG [PASSMAP]"""
import collections
import statistics as st
import sys


def parse(path):
    recs = {}
    for line in open(path):
        t = line.split()
        if not t or t[0] != 'row': continue
        row, d_in = int(t[1]), round(float(t[3]), 4)
        i = t.index('E')
        r = {'E': (float(t[i + 1]), float(t[i + 2]))}
        if 'L' not in t:  # CrossingLine not reached (SampleSide failed)
            continue
        i = t.index('L')
        r['L'] = (float(t[i + 1]), float(t[i + 2]))
        r['U'] = int(t[t.index('U') + 1])
        r['n'] = int(t[t.index('n') + 1])
        rays = {}
        if 'K' not in t:  # levels closer than 8 grey: no crossing line
            r['rays'], r['K'] = rays, frozenset()
            recs[(row, d_in)] = r
            continue
        k = t.index('R') + 1
        ke = t.index('K')
        for tok in t[k:ke]:
            p = tok.split(':')
            if len(p) == 2: rays[int(p[0])] = p[1]
            elif p[1] == 'nan': rays[int(p[0])] = 'x'
            else: rays[int(p[0])] = (float(p[1]), float(p[2]))
        r['rays'] = rays
        r['K'] = frozenset(int(x) for x in t[ke + 1:])
        recs[(row, d_in)] = r
    return recs


def fit_ends(r, keep):
    """Total least squares line through the rays `keep` (in (along, out)), its out at the ends E."""
    pts = [r['rays'][i] for i in keep if isinstance(r['rays'].get(i), tuple)]
    if len(pts) < 3: return None
    mt = sum(p[1] for p in pts) / len(pts)
    mu = sum(p[0] for p in pts) / len(pts)
    sxx = sum((p[1] - mt)**2 for p in pts)
    sxy = sum((p[1] - mt) * (p[0] - mu) for p in pts)
    syy = sum((p[0] - mu)**2 for p in pts)
    import math
    ang = 0.5 * math.atan2(2 * sxy, sxx - syy)  # direction of largest spread in (t, u)
    dt, du = math.cos(ang), math.sin(ang)
    return tuple(mu + (e - mt) * du / dt for e in r['E'])


def ends_jump(a, b):
    if a is None or b is None: return float('nan')
    return max(abs(b[0] - a[0]), abs(b[1] - a[1]))


def main():
    recs = parse(sys.argv[1])
    dout_pairs = None
    if len(sys.argv) > 2:  # pairs where d_out jumps (overshoot-jumps.py's rule) and the crossing line jumps
        dout_pairs = set()
        for row, line in enumerate(l for l in open(sys.argv[2]) if l.startswith('M')):
            for part in line.rstrip('\n').split(' | ')[1:]:
                toks = part.split()
                if toks[0] != '-': continue
                pts = [t.split(':') for t in toks[1:]]
                pts = [(round(float(p[0]), 4), float(p[1])) for p in pts]
                pts = [p for p in pts if p[1] == p[1]]
                if len(pts) < 4: continue
                med = st.median([(q[1] - p[1]) / (q[0] - p[0]) for p, q in zip(pts, pts[1:])])
                for p, q in zip(pts, pts[1:]):
                    if abs((q[1] - p[1]) - med * (q[0] - p[0])) > 0.01: dout_pairs.add((row, p[0], q[0]))
    keys = sorted(recs)
    classes, primary = collections.Counter(), collections.Counter()
    pair_count = jump_count = 0
    point_jumps, set_jumps, ray_dus, level_moves = [], [], [], []
    examples = collections.defaultdict(list)
    for ka, kb in zip(keys, keys[1:]):
        if ka[0] != kb[0]: continue
        if dout_pairs is not None and (ka[0], ka[1], kb[1]) not in dout_pairs: continue
        a, b = recs[ka], recs[kb]
        pair_count += 1
        ea, eb = fit_ends(a, a['K']), fit_ends(b, b['K'])
        if ea is None or eb is None or not a['K'] or not b['K']: continue
        jump = ends_jump(ea, eb)
        if not jump > 0.05: continue
        jump_count += 1
        tags = []
        if a['n'] != b['n']: tags.append('ray count')
        if a['U'] != b['U']: tags.append('use_clean')
        va = {i for i, v in a['rays'].items() if v == 'v'}
        vb = {i for i, v in b['rays'].items() if v == 'v'}
        if va != vb: tags.append('valid')
        ca = {i for i, v in a['rays'].items() if v == 'c'}
        cb = {i for i, v in b['rays'].items() if v == 'c'}
        if a['U'] == b['U'] and ca != cb: tags.append('clean')
        used_both = [i for i in a['rays'] if a['rays'][i] not in ('v', 'c') and b['rays'].get(i) not in (None, 'v', 'c')]
        if any((a['rays'][i] == 'x') != (b['rays'][i] == 'x') for i in used_both): tags.append('crossing found/lost')
        if a['K'] != b['K']: tags.append('inliers')
        # The same kept rays in both: the part of the jump the points' own moves make.
        common = a['K'] & b['K']
        e_sa, e_sb = fit_ends(a, common), fit_ends(b, common)
        pj = ends_jump(e_sa, e_sb)
        point_jumps.append(pj)
        dus = sorted(((abs(b['rays'][i][0] - a['rays'][i][0]), i) for i in common), reverse=True)
        if dus: ray_dus.append(dus[0][0])
        level_moves.append(max(abs(b['L'][0] - a['L'][0]), abs(b['L'][1] - a['L'][1])))
        if pj > 0.05:
            # One ray's crossing jumped: without it, the common set's line does not jump.
            one = dus and dus[0][0] > 0.1 and ends_jump(fit_ends(a, common - {dus[0][1]}),
                                                        fit_ends(b, common - {dus[0][1]})) <= 0.05
            tags.append('one ray jumps' if one else 'points move together')
        else:
            set_jumps.append(jump)
        for t in tags: classes[t] += 1
        key = '+'.join(tags) or 'none'
        primary[key] += 1
        if len(examples[key]) < 3: examples[key].append((ka, kb, round(jump, 3), round(pj, 3)))
    print(f"pairs {pair_count}, crossing-line jumps > 0.05 px {jump_count}")
    print("by tag (a jump can have several):")
    for k, v in classes.most_common(): print(f"  {k}: {v} ({v / jump_count:.0%})")
    print("by combination:")
    for k, v in primary.most_common(14): print(f"  {k}: {v} ({v / jump_count:.0%})  e.g. {examples[k][:2]}")
    q = lambda xs, f: sorted(xs)[int(f * (len(xs) - 1))]
    print(f"jump of the line with the kept rays common to both (px): median {st.median(point_jumps):.3f}, "
          f"q90 {q(point_jumps, 0.9):.3f}; > 0.05 px in {sum(p > 0.05 for p in point_jumps)}")
    print(f"largest single-ray move among common kept rays (px): median {st.median(ray_dus):.3f}, "
          f"q90 {q(ray_dus, 0.9):.3f}, > 0.1 px in {sum(d > 0.1 for d in ray_dus)}")
    print(f"level move (grey): median {st.median(level_moves):.3f}, q90 {q(level_moves, 0.9):.3f}")


main()
