# diag_charuco_board's per-marker lines (MCMT_BOARD_MARKERS=1, with the pair fields; 2026-12-06-cam1width.md):
# per pair of opposite sides, its half width error (mean outward offset) by the true cell depth across it,
# for mcmt against the true corners, the chessboard's prediction against the true corners, and mcmt
# against the prediction (what the real board's truth sees); and the within-marker slope: the two pairs'
# offset difference regressed on their depth difference (px per px; a marker-wide scale error cancels).
#   python3 2026-12-06-cam1width-board.py FILE.csv [...]
import math, sys
from collections import defaultdict

BANDS = ['<2.5', '2.5-3.5', '3.5-4.5', '4.5-6', '6+']


def band(d):
    return BANDS[0] if d < 2.5 else BANDS[1] if d < 3.5 else BANDS[2] if d < 4.5 else BANDS[3] if d < 6 else BANDS[4]


for path in sys.argv[1:]:
    pairs = []  # per marker: [(depth, mcmt - true, chessboard - true) for pair 0, 1]
    for line in open(path):
        f = line.strip().split(',')
        if f[0] != 'mcmt' or len(f) < 14:
            continue
        v = [float(x) for x in f[8:14]]
        pairs.append([(v[0], v[1], v[2]), (v[3], v[4], v[5])])
    print(path, '%d markers' % len(pairs))
    for name, get in [('mcmt - true', lambda p: p[1]), ('chessboard - true', lambda p: p[2]),
                      ('mcmt - chessboard', lambda p: p[1] - p[2])]:
        g = defaultdict(list)
        for m in pairs:
            for p in m:
                g[band(p[0])].append(get(p))
        xs = [m[0][0] - m[1][0] for m in pairs]
        ys = [get(m[0]) - get(m[1]) for m in pairs]
        sxx = sum(x * x for x in xs)
        b = sum(x * y for x, y in zip(xs, ys)) / sxx
        sd = math.sqrt(sum((y - b * x) ** 2 for x, y in zip(xs, ys)) / max(len(xs) - 1, 1))
        print('  %-18s %s | within-marker slope %+.4f px/px (se %.4f)' % (
            name, '  '.join('%s %+.3f (%d)' % (k, sum(g[k]) / len(g[k]), len(g[k])) for k in BANDS if g[k]),
            b, sd / math.sqrt(sxx)))
