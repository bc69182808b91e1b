"""The reader of bench_imaging_maps corner dumps (MCMT_IMAGING_DUMP: one CSV line per detected corner) that
the split scripts beside it share (issue 15: 2026-12-06-simsize13-reachsplit.py, 2026-12-07-seeds13-split.py,
-tail-tilt.py, -tail-acute.py, -skewmix-ends.py,
2026-12-08-blurgap-bands.py, -blurgap-table.py, -brightsurf-trace.py, -brightsurf-why.py). They import it from their own folder."""
import csv
import math
from collections import defaultdict


def marker_rows(path):
    """(camera, seq, id) -> the marker's four corner rows (CSV dicts) by corner index 0-3, in the dump's order.
    Markers with fewer than four corners are left out, as are truncated lines (no `y`)."""
    g = defaultdict(dict)
    for r in csv.DictReader(open(path)):
        if r.get('y') is None:
            continue
        g[(r['camera'], r['seq'], r['id'])][int(r['corner'])] = r
    return {key: c for key, c in g.items() if len(c) == 4}


def truth_and_error(c):
    """A marker's true corners (x, y) and its detected corners' errors (dx, dy), px, corners 0-3."""
    t = [(float(c[k]['x']), float(c[k]['y'])) for k in range(4)]
    e = [(float(c[k]['dx']), float(c[k]['dy'])) for k in range(4)]
    return t, e


def side_offsets(t, e):
    """Each side's signed offset, px (outward +): the mean of its two corners' errors `e` along the true side's
    outward normal (true corners `t`), sides 0-3 from corner k to k + 1."""
    cx = sum(p[0] for p in t) / 4
    cy = sum(p[1] for p in t) / 4
    out = []
    for k in range(4):
        a, b = t[k], t[(k + 1) % 4]
        L = math.hypot(b[0] - a[0], b[1] - a[1])
        n = ((b[1] - a[1]) / L, -(b[0] - a[0]) / L)
        if n[0] * ((a[0] + b[0]) / 2 - cx) + n[1] * ((a[1] + b[1]) / 2 - cy) < 0:
            n = (-n[0], -n[1])
        out.append(0.5 * sum(e[j][0] * n[0] + e[j][1] * n[1] for j in (k, (k + 1) % 4)))
    return out


def side_roles(t, e):
    """Each side's offset (`off`, as side_offsets), true length (`L`, px) and role in the paper's rig: side 0 the
    top, side 2 the bottom, of sides 1 and 3 the longer one `near` and the other `far`."""
    res = [dict(off=o, L=math.hypot(t[(k + 1) % 4][0] - t[k][0], t[(k + 1) % 4][1] - t[k][1]))
           for k, o in enumerate(side_offsets(t, e))]
    near = 1 if res[1]['L'] >= res[3]['L'] else 3
    for k in range(4):
        res[k]['role'] = {0: 'top', 2: 'bottom'}.get(k, 'near' if k == near else 'far')
    return res
