import csv, sys, math, collections
def load(p):
    d = {}
    rows = list(csv.DictReader(open(p)))
    by = collections.defaultdict(list)
    for r in rows: by[(r['radius'], r['camera'], r['seq'], r['id'])].append(r)
    for k, rs in by.items():
        cx = sum(float(r['x']) for r in rs) / len(rs); cy = sum(float(r['y']) for r in rs) / len(rs)
        for r in rs:
            ox, oy = float(r['x']) - cx, float(r['y']) - cy; n = math.hypot(ox, oy) or 1
            d[k + (r['corner'],)] = ((float(r['dx']) * ox + float(r['dy']) * oy) / n, float(r['size_px']), float(r['err']))
    return d
a, b = load(sys.argv[1]), load(sys.argv[2])
ma = {k[:4] for k in a}; mb = {k[:4] for k in b}
print('markers: A', len(ma), 'B', len(mb), 'only A', len(ma - mb), 'only B', len(mb - ma))
common = [k for k in a if k in b]
def stats(keys, lab):
    if not keys: return
    ra = [a[k][0] for k in keys]; rb = [b[k][0] for k in keys]
    diff = [y - x for x, y in zip(ra, rb)]
    moved = sum(1 for x in diff if abs(x) > 1e-4)
    print(f'{lab}: n {len(keys)} radial A {sum(ra)/len(ra):+.4f} B {sum(rb)/len(rb):+.4f} diff {sum(diff)/len(diff):+.4f} moved {moved}')
stats(common, 'all common')
for lo, hi in [(0, 15), (15, 20), (20, 25), (25, 30), (30, 40), (40, 1000)]:
    stats([k for k in common if lo <= a[k][1] < hi], f'size {lo}-{hi}px')
for lab, only, src in [('only A', ma - mb, a), ('only B', mb - ma, b)]:
    ks = [k for k in src if k[:4] in only]
    if ks: print(lab, 'corners', len(ks), 'radial mean %+.4f' % (sum(src[k][0] for k in ks) / len(ks)), 'size mean %.1f' % (sum(src[k][1] for k in ks) / len(ks)), 'err mean %.3f' % (sum(src[k][2] for k in ks)/len(ks)))
