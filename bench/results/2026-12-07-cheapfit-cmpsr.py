import sys, math
def load(p):
    out = []
    for line in open(p):
        f = line.split()
        out.append((int(f[0]), int(f[1]), [float.fromhex(x) for x in f[2:10]]))
    return out
a, b = load(sys.argv[1]), load(sys.argv[2])
if len(a) != len(b) or any(x[:2] != y[:2] for x, y in zip(a, b)):
    print("different marker lists", len(a), len(b))
for mode in (0, 1):
    d = []
    for x, y in zip(a, b):
        if x[0] != mode or x[:2] != y[:2]: continue
        d.append(max(math.hypot(x[2][2*k]-y[2][2*k], x[2][2*k+1]-y[2][2*k+1]) for k in range(4)))
    d.sort()
    n = len(d)
    print("mode", "accurate" if mode == 0 else "fast", "markers", n, "max %.4f mean %.4f median %.5f p90 %.4f >0.001 %d >0.02 %d" % (d[-1], sum(d)/n, d[n//2], d[int(0.9*n)], sum(v > 0.001 for v in d), sum(v > 0.02 for v in d)))
