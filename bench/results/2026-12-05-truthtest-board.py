# diag_charuco_board's per-marker lines (MCMT_BOARD_MARKERS=1, stderr; 2026-12-05-truthtest.md): the
# chessboard truth's size / skew error over all markers and over the markers mcmt found, and mcmt's size /
# skew error against the true corners and against the chessboard's prediction (means over markers; in
# brackets the se from the scatter of the pose means, as the markers of one pose share its homography).
#   python3 2026-12-05-truthtest-board.py LABEL=markers.csv [...]
import sys, math


def fmt(pairs):  # pairs: (pose, value)
    if not pairs:
        return 'n/a'
    m = sum(v for _, v in pairs) / len(pairs)
    by_pose = {}
    for pose, v in pairs:
        by_pose.setdefault(pose, []).append(v)
    means = [sum(vs) / len(vs) for vs in by_pose.values()]
    n = len(means)
    pm = sum(means) / n
    se = math.sqrt(sum((x - pm) ** 2 for x in means) / max(n - 1, 1) / n)
    return '%+.3f (%.3f)' % (m, se)


print('| run | markers truth / mcmt | truth size %, all | truth size %, mcmt\'s | truth skew deg, mcmt\'s | '
      'mcmt size % vs true | mcmt size % vs chessboard | mcmt skew deg vs true | mcmt skew deg vs chessboard |')
print('|---|---|---|---|---|---|---|---|---|')
for arg in sys.argv[1:]:
    label, path = arg.split('=', 1)
    truth, mcmt = {}, []
    for line in open(path):
        f = line.strip().split(',')
        if f[0] == 'truth':
            truth[(f[1], f[2])] = (float(f[4]), float(f[5]))
        elif f[0] == 'mcmt':
            mcmt.append(((f[1], f[2]), [float(x) for x in f[4:8]]))
    found = [(k[0], truth[k]) for k, _ in mcmt if k in truth]
    print('| %s | %d / %d | %s | %s | %s | %s | %s | %s | %s |' % (
        label, len(truth), len(mcmt), fmt([(k[0], t[0]) for k, t in truth.items()]),
        fmt([(p, t[0]) for p, t in found]), fmt([(p, t[1]) for p, t in found]),
        *[fmt([(k[0], v[j]) for k, v in mcmt]) for j in (0, 2, 1, 3)]))
