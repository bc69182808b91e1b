# Per-side signed offsets (px, + outward) from a bench_imaging_maps dump, binned by view angle, marker size,
# and the side's cell depth (extent across / cells); optionally the difference of two dumps on common markers.
import sys, csv, math, collections
def read(path):
    ms = collections.defaultdict(dict)
    for r in csv.DictReader(open(path)):
        k = (r['condition'], r['camera'], r['seq'], r['id'])
        c = int(r['corner'])
        if c < 0 or c > 3: continue
        ms[k][c] = (float(r['x']), float(r['y']), float(r['dx']), float(r['dy']), float(r['view_deg']), float(r['size_px']))
    out = {}
    for k, m in ms.items():
        if len(m) != 4: continue
        t = [(m[i][0], m[i][1]) for i in range(4)]; e = [(m[i][2], m[i][3]) for i in range(4)]
        cx = sum(p[0] for p in t) / 4; cy = sum(p[1] for p in t) / 4
        sides = []
        for s in range(4):
            a, b = t[s], t[(s + 1) % 4]
            nx, ny = b[1] - a[1], a[0] - b[0]; L = math.hypot(nx, ny); nx /= L; ny /= L
            if nx * ((a[0] + b[0]) / 2 - cx) + ny * ((a[1] + b[1]) / 2 - cy) < 0: nx, ny = -nx, -ny
            ext = 0.5 * (abs(nx * (t[(s + 2) % 4][0] - a[0]) + ny * (t[(s + 2) % 4][1] - a[1])) + abs(nx * (t[(s + 3) % 4][0] - a[0]) + ny * (t[(s + 3) % 4][1] - a[1])))
            off = 0.5 * (nx * (e[s][0] + e[(s + 1) % 4][0]) + ny * (e[s][1] + e[(s + 1) % 4][1]))
            sides.append((ext, off))
        out[k] = (m[0][4], m[0][5], sides)
    return out
CELLS = float(sys.argv[3]) if len(sys.argv) > 3 else 6.0
def table(d, keyf, edges, name):
    acc = collections.defaultdict(lambda: [0, 0.0, 0.0, 0.0])
    for k, v in d.items():
        for s in v:
            b = keyf(s)
            bi = sum(1 for x in edges if b >= x) - 1
            a = acc[bi]; a[0] += 1; a[1] += s[0]; a[2] += s[1]; a[3] += s[2] if len(s) > 2 else 0
    print(f"| {name} | sides | mean | " + " | ".join(h for h in HEAD) + " |")
    print("|---|---|---|" + "---|" * len(HEAD))
    for bi in sorted(acc):
        a = acc[bi]
        lo = edges[bi]; hi = edges[bi + 1] if bi + 1 < len(edges) else 'inf'
        print(f"| {lo}-{hi} | {a[0]} | {a[1]/a[0]:.2f} | " + " | ".join(f"{x/a[0]:+.4f}" for x in a[2:2+len(HEAD)]) + " |")
A = read(sys.argv[1]); B = read(sys.argv[2]) if len(sys.argv) > 2 and sys.argv[2] != '-' else None
rows = {}
for k, (view, size, sides) in A.items():
    if B is not None and k not in B: continue
    for s in range(4):
        ext, off = sides[s]
        offb = B[k][2][s][1] if B is not None else 0.0
        rows[(k, s)] = (view, size, ext / CELLS, off, offb)
HEAD = ['A', 'B', 'B-A'] if B is not None else ['A']
def rowsof(f):
    return {k: [f(v), v[3], v[4], v[4] - v[3]][:1] + ([v[3], v[4], v[4] - v[3]] if B is not None else [v[3]]) for k, v in rows.items()}
# generic binning: key value first then values
def tab(idx, edges, name):
    acc = collections.defaultdict(lambda: [0, 0.0] + [0.0] * len(HEAD))
    for k, v in rows.items():
        key = v[idx]
        bi = max(0, sum(1 for x in edges if key >= x) - 1)
        vals = [v[3], v[4], v[4] - v[3]] if B is not None else [v[3]]
        a = acc[bi]; a[0] += 1; a[1] += key
        for i, x in enumerate(vals): a[2 + i] += x
    print(f"\n| {name} | sides | mean | " + " | ".join(HEAD) + " |")
    print("|---|---|---|" + "---|" * len(HEAD))
    for bi in sorted(acc):
        a = acc[bi]; hi = edges[bi + 1] if bi + 1 < len(edges) else '+'
        print(f"| {edges[bi]}-{hi} | {a[0]} | {a[1]/a[0]:.2f} | " + " | ".join(f"{x/a[0]:+.4f}" for x in a[2:]) + " |")
tab(0, [0, 30, 45, 60, 67, 75], 'view deg')
tab(1, [0, 15, 20, 25, 30, 40], 'marker px')
tab(2, [0, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0], 'cell depth px')
