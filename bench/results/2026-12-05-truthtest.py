# diag_charuco CSVs (2026-12-05-truthtest.md): the tone-auto test's per-camera mean size error, restricted
# to markers whose view angle is at most 50 / 55 / 60 deg (and all), against the chessboard truth (the
# test's: size_rel) and against the stock-OpenCV-centres truth (size_rel_stock_centres); whether each
# would pass the tone-auto test's bounds ("auto": |camera mean| <= 0.2 %, mean over cameras <= 0.09 %) or the
# config-tone test's size bound ("config": |camera mean| <= 0.3 %), and whether every camera keeps the
# tests' 200 markers ("n"); and the per-marker skew error (|angle - 90| detected minus the chessboard's predicted, mean of
# the 4 corners, as 2026-12-05-cam1bias-skew.py) per camera and view band.
#   python3 2026-12-05-truthtest.py A.csv [B.csv ...]
import csv, sys, math
from collections import defaultdict

LIMITS = [50, 55, 60, 90]  # 90: all markers (the test as it is)
TRUTHS = [('size_rel', 'chessboard'), ('size_rel_stock_centres', 'stock centres')]


def angle(p, a, q):
    u = (p[0] - a[0], p[1] - a[1])
    v = (q[0] - a[0], q[1] - a[1])
    c = (u[0] * v[0] + u[1] * v[1]) / math.hypot(*u) / math.hypot(*v)
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


# skew error = mean over corners k of |angle_k(detected) - 90| - |angle_k(predicted) - 90|
def skew_error(r):
    got = [(float(r['gx%d' % k]), float(r['gy%d' % k])) for k in range(4)]
    want = [(float(r['wx%d' % k]), float(r['wy%d' % k])) for k in range(4)]
    e = s = 0.0
    for k in range(4):
        g = abs(angle(got[(k + 3) % 4], got[k], got[(k + 1) % 4]) - 90)
        w = abs(angle(want[(k + 3) % 4], want[k], want[(k + 1) % 4]) - 90)
        e += (g - w) / 4
        s += w / 4
    return e, s


def mean_se(xs):
    n = len(xs)
    if n == 0:
        return float('nan'), float('nan')
    m = sum(xs) / n
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / max(n - 1, 1))
    return m, sd / math.sqrt(n)


for path in sys.argv[1:]:
    rows = list(csv.DictReader(open(path)))
    cams = sorted(set(r['camera'] for r in rows))
    print(path)
    for field, name in TRUTHS:
        for lim in LIMITS:
            out, mean_abs, auto_ok, config_ok, n_ok = [], 0.0, True, True, True
            for cam in cams:
                xs = [100 * float(r[field]) for r in rows
                      if r['camera'] == cam and float(r['view_deg']) <= lim and not math.isnan(float(r[field]))]
                m, _ = mean_se(xs)
                mean_abs += abs(m) / len(cams)
                auto_ok = auto_ok and abs(m) <= 0.2
                config_ok = config_ok and abs(m) <= 0.3
                n_ok = n_ok and len(xs) >= 200
                out.append('%s %+.3f (%d)' % (cam, m, len(xs)))
            auto_ok = auto_ok and mean_abs <= 0.09
            verdict = lambda ok: 'pass' if ok else 'FAIL'
            print('  size %-13s view <= %2d: %s | mean |size| %.3f %% auto %s config %s n %s' %
                  (name, lim, '  '.join(out), mean_abs, verdict(auto_ok), verdict(config_ok), verdict(n_ok)))
    for lim in LIMITS:
        out, worst = [], 0.0
        for cam in cams:
            es = [skew_error(r) for r in rows if r['camera'] == cam and float(r['view_deg']) <= lim]
            m, se = mean_se([e for e, _ in es])
            true_skew = sum(s for _, s in es) / max(len(es), 1)
            worst = max(worst, abs(m))
            out.append('%s %+.3f (se %.3f, skew %.0f)' % (cam, m, se, true_skew))
        print('  skew error deg view <= %2d: %s | worst |mean| %.3f' % (lim, '  '.join(out), worst))
    # per-marker skew by camera and band (view < / >= 55, side < / >= 28 px), all views
    bands = defaultdict(list)
    for r in rows:
        v, s = float(r['view_deg']), float(r['side_px'])
        key = '%s %s %s' % (r['camera'], 'v<=55' if v <= 55 else 'v>55', 's<28' if s < 28 else 's>=28')
        bands[key].append(skew_error(r)[0])
    print('  skew error by band: ' + '  '.join(
        '%s %+.3f (%d, se %.3f)' % ((k,) + (mean_se(bands[k])[0], len(bands[k]), mean_se(bands[k])[1]))
        for k in sorted(bands)))
