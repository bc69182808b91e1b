import sys, math, collections
# Per-side signed offsets (outward +) of diag_session dumps, side k = corners k, k+1 (marker frame); A vs B paired.
#   python3 2026-12-07-smallface-sides.py A.txt [B.txt]
# per-side signed offsets (outward +) from diag_session dumps; side k = corners k,k+1
def load(p):
    d = collections.defaultdict(dict)
    for l in open(p):
        if l.startswith('#'): continue
        t = l.split()
        key = (t[0], int(t[1]), int(t[2]))
        d[key][int(t[3])] = (float(t[4]), float(t[5]), float(t[6]), float(t[7]), float(t[8]), float(t[9]))
    return d
def sides(d):
    out = {}
    for key, c in d.items():
        if len(c) != 4: continue
        tc = [(c[k][2], c[k][3]) for k in range(4)]
        cx = sum(p[0] for p in tc) / 4; cy = sum(p[1] for p in tc) / 4
        for k in range(4):
            a, b = tc[k], tc[(k + 1) % 4]
            dx, dy = b[0] - a[0], b[1] - a[1]; L = math.hypot(dx, dy)
            nx, ny = dy / L, -dx / L
            if nx * ((a[0] + b[0]) / 2 - cx) + ny * ((a[1] + b[1]) / 2 - cy) < 0: nx, ny = -nx, -ny
            off = 0
            for j in (k, (k + 1) % 4):
                off += 0.5 * ((c[j][0] - c[j][2]) * nx + (c[j][1] - c[j][3]) * ny)
            out[key + (k,)] = (off, c[k][4], c[k][5])
    return out
a = sides(load(sys.argv[1]))
b = sides(load(sys.argv[2])) if len(sys.argv) > 2 else None
def rep(sel, label):
    ks = [k for k in a if sel(k)]
    if b: ks = [k for k in ks if k in b]
    if not ks: return
    m = sum(a[k][0] for k in ks) / len(ks)
    s = '%-28s n %5d  A %+.4f' % (label, len(ks), m)
    if b:
        mb = sum(b[k][0] for k in ks) / len(ks)
        d = [a[k][0] - b[k][0] for k in ks]
        md = sum(d) / len(d); se = math.sqrt(sum((x - md) ** 2 for x in d) / max(1, len(d) - 1) / len(d))
        s += '  B %+.4f  A-B %+.4f (se %.4f)' % (mb, md, se)
    print(s)
rep(lambda k: True, 'all')
for s in range(4): rep(lambda k, s=s: k[3] == s, 'side %d' % s)
for s in range(4):
    for up in (0, 1): rep(lambda k, s=s, up=up: k[3] == s and (k[2] % 2) == up, 'side %d level %d' % (s, up))
for lo, hi in ((0, 40), (40, 60), (60, 90)): rep(lambda k, lo=lo, hi=hi: lo <= a[k][2] < hi, 'view %d-%d' % (lo, hi))
