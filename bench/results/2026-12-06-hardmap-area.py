#!/usr/bin/env python3
"""A narrow paper margin under blur, fitted as the side model would (1-D, linear light, no noise).
Truth: border L0 inside (u < 0, with a code row of the paper's level from -c), margin P on [0, q], surface S
beyond, all blurred by a Gaussian sigma; samples every 0.25 px from -2c to 1.6c + 1 px (the profiles' reach).
Fits by Gauss-Newton (numeric Jacobian): the one-level model (edge e, L0, L1, S, sigma free) and the two-level
model (e, L0, L1, S1, S2, q, sigma free; q >= 0.2 c) from a start of q = c, S1 at the profile's level there.
Prints the edge's error in px.
  python3 2026-12-06-hardmap-area.py"""
import math


def Phi(z):
    return 0.5 * math.erfc(-z / math.sqrt(2))


def profile(u, e, L0, L1, S1, S2, q, sigma, c):
    # regions from inside out: code row L1 below -c, border L0 on [-c, e], margin S1 on [e, e+q], S2 beyond
    f = L1 * (1 - Phi((u - (e - c)) / sigma))
    f += L0 * (Phi((u - (e - c)) / sigma) - Phi((u - e) / sigma))
    f += S1 * (Phi((u - e) / sigma) - Phi((u - e - q) / sigma))
    f += S2 * Phi((u - e - q) / sigma)
    return f


def solve(a, b):
    n = len(b)
    m = [row[:] + [b[i]] for i, row in enumerate(a)]
    for i in range(n):
        p = max(range(i, n), key=lambda r: abs(m[r][i]))
        m[i], m[p] = m[p], m[i]
        if abs(m[i][i]) < 1e-14:
            return [0.0] * n
        for r in range(n):
            if r != i:
                f = m[r][i] / m[i][i]
                for k in range(i, n + 1):
                    m[r][k] -= f * m[i][k]
    return [m[i][n] / m[i][i] for i in range(n)]


def fit(us, ys, model, p, lo, hi, iters=200):
    lam = 1e-3

    def cost(p):
        return sum((model(u, p) - y) ** 2 for u, y in zip(us, ys))

    c0 = cost(p)
    for _ in range(iters):
        J = []
        for u in us:
            row = []
            for k in range(len(p)):
                d = 1e-6
                q = p[:]
                q[k] += d
                row.append((model(u, q) - model(u, p)) / d)
            J.append(row)
        r = [y - model(u, p) for u, y in zip(us, ys)]
        n = len(p)
        A = [[sum(J[i][a] * J[i][b] for i in range(len(us))) for b in range(n)] for a in range(n)]
        g = [sum(J[i][a] * r[i] for i in range(len(us))) for a in range(n)]
        improved = False
        for _ in range(8):
            Al = [[A[a][b] + (lam * A[a][a] + 1e-12 if a == b else 0) for b in range(n)] for a in range(n)]
            s = solve(Al, g)
            q = [min(hi[k], max(lo[k], p[k] + s[k])) for k in range(n)]
            cq = cost(q)
            if cq < c0:
                p, c0, lam, improved = q, cq, max(1e-9, lam * 0.3), True
                break
            lam *= 10
        if not improved:
            break
    return p, c0


def case(S, q_cells, c=2.2, sigma=0.9, L0=0.04 * 255, P=0.85 * 255):
    S = S * 255
    q = q_cells * c
    us = [-2 * c + 0.25 * j for j in range(int((3.6 * c + 1) / 0.25) + 1)]
    ys = [profile(u, 0.0, L0, P, P, S, q, sigma, c) for u in us]
    one = lambda u, p: profile(u, p[0], p[1], p[2], p[3], p[3], 0.0, p[4], c)
    p1, c1 = fit(us, ys, one, [0.0, L0, P, S, 0.8], [-c, -50, -50, -50, 0.15], [c, 300, 300, 300, 4])
    two = lambda u, p: profile(u, p[0], p[1], p[2], p[3], p[4], p[5], p[6], c)
    start = [0.0, L0, P, profile(c / 2, 0, L0, P, P, S, q, sigma, c), S, c, 0.8]
    p2, c2 = fit(us, ys, two, start, [-c, -50, -50, -50, -50, 0.2 * c, 0.15],
                 [c, 300, 300, 300, 300, 4 * c, 4])
    tied = lambda u, p: profile(u, p[0], p[1], p[2], p[2], p[3], p[4], p[5], c)
    p3, c3 = fit(us, ys, tied, [0.0, L0, P, S, c, 0.8], [-c, -50, -50, -50, 0.2 * c, 0.15],
                 [c, 300, 300, 300, 4 * c, 4])
    area = q_cells * (P - S) / (P - L0)
    print('| %.2f | %.2f | %.3f | %+.3f (rms %.2f) | %+.3f (q %.2f c, S1 %.0f, rms %.3f) | %+.3f (q %.2f c) |' % (
        S / 255, q_cells, area, p1[0], math.sqrt(c1 / len(us)), p2[0], p2[5] / c, p2[3],
        math.sqrt(c2 / len(us)), p3[0], p3[4] / c))


print('| surface | margin cells | area a | one level: e px | two levels, free: e px | margin = paper: e px |')
print('|---|---|---|---|---|---|')
for S, qc in ((0.7, 0.3), (0.5, 0.3), (0.7, 1.0), (0.5, 1.0), (0.06, 0.5), (0.45, 0.5), (0.7, 0.0001)):
    case(S, qc)
