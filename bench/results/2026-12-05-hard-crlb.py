#!/usr/bin/env python3
"""A Cramer-Rao-like floor for hard's corners: the side model's parameters (e, sigma, L0, L1, S1, S2, q;
gamma when encoded) from every pixel of one side's window (u from -1.6 cells to 1.6 cells + 1 px, one
sample per px^2, half the rays with code row 1 of the other colour), white noise of the renderer's level
(read 2, shot 0.1 v; encoded: times the curve's slope and the sharpening's noise gain). The edge's
standard deviation at the side's end is twice its mean's (line with free tilt), a corner's median error
about 1.18 of that (two sides at right angles).
  crlb.py [gamma (1)] [sharpen (0)] [margin cells (0.3)] [surround (0.7)] [held]
"""
import math, sys

gamma = float(sys.argv[1]) if len(sys.argv) > 1 else 1.0
sharpen = float(sys.argv[2]) if len(sys.argv) > 2 else 0.0
margin = float(sys.argv[3]) if len(sys.argv) > 3 else 0.3
surround = float(sys.argv[4]) if len(sys.argv) > 4 else 0.7
held = len(sys.argv) > 5 and sys.argv[5] == 'held'  # gamma known (held), not fitted per side
light = 1.0
ink, paper = 0.04 * 255 * light, 0.85 * 255 * light
S2 = surround * 255 * light


def Phi(z):
    return 0.5 * math.erfc(-z / math.sqrt(2))


def model(th, u, other):
    e, s, L0, L1, S1, S2_, q, g = th
    c = cell
    bounds = [e + q, e, e - c, e - 2 * c]
    levels = [S2_, S1, L0, L0 + (L1 - L0) * other, L0]
    f = 0
    for k in range(5):
        up = 1.0 if k == 0 else Phi((bounds[k - 1] - u) / s)
        lo = 0.0 if k == 4 else Phi((bounds[k] - u) / s)
        f += levels[k] * (up - lo)
    return 255 * (max(f, 0.5) / 255) ** (1 / g)


def noise(v_lin):
    sd = math.sqrt(4 + 0.1 * v_lin)
    slope = (1 / gamma) * (max(v_lin, 0.5) / 255) ** (1 / gamma - 1)
    gain = math.sqrt((1 + sharpen) ** 2 - 2 * (1 + sharpen) * sharpen / (2 * math.pi) + sharpen ** 2 / (4 * math.pi))
    return sd * slope * gain


def inv(m):
    n = len(m)
    a = [row[:] + [1.0 if i == j else 0.0 for j in range(n)] for i, row in enumerate(m)]
    for i in range(n):
        p = max(range(i, n), key=lambda r: abs(a[r][i]))
        a[i], a[p] = a[p], a[i]
        d = a[i][i]
        a[i] = [x / d for x in a[i]]
        for r in range(n):
            if r != i:
                f = a[r][i]
                a[r] = [x - f * y for x, y in zip(a[r], a[i])]
    return [row[n:] for row in a]


print('| side px | cell px | blur | sigma(e) mean px | at the end | corner median px |')
print('|---|---|---|---|---|---|')
for side in (20, 32, 50):
    for blur in (0.6, 0.75):
        cell = side / 8.0
        th = [0.0, blur, ink, paper, paper, S2, margin * cell, gamma]
        free = list(range(8 if gamma != 1 and not held else 7))
        F = [[0.0] * len(free) for _ in free]
        u = -1.6 * cell
        while u < 1.6 * cell + 1:
            for other in (0.0, 1.0):
                f0 = model(th, u, other)
                grads = []
                for k in free:
                    h = 1e-4 * max(1.0, abs(th[k]))
                    tp = th[:]; tp[k] += h
                    tm = th[:]; tm[k] -= h
                    grads.append((model(tp, u, other) - model(tm, u, other)) / (2 * h))
                lin = 255 * (f0 / 255) ** gamma
                w = side / 2 / noise(lin) ** 2  # half the side's pixels of each pattern, 1 px apart in u
                for a in range(len(free)):
                    for b in range(len(free)):
                        F[a][b] += w * grads[a] * grads[b]
            u += 1.0
        sd = math.sqrt(inv(F)[0][0])
        print('| %d | %.1f | %.2f | %.4f | %.4f | %.4f |' % (side, cell, blur, sd, 2 * sd, 1.18 * 2 * sd))
