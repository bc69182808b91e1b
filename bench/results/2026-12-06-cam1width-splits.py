# diag_charuco CSV (2026-12-06-cam1width.md): cam1's width bias (mean outward offset of opposite sides,
# as 2026-12-05-cam1bias-widths.py) by cell depth, split by what a codec, the motion or the geometry
# could make of it: the frame's MPEG-4 picture type (I / P, from ffprobe), the marker's speed between
# frames (px per frame, from the chessboard-predicted corners of the same id one frame apart), the
# sides' direction (horizontal / vertical) and the marker's place in the image.
#   ffprobe -v error -select_streams v -show_entries frame=pict_type -of csv=p=0 cam_1.mp4 > types.txt
#   python3 2026-12-06-cam1width-splits.py CAMERA A.csv types.txt
import csv, sys, math
from collections import defaultdict


def dist_pt_line(p, a, b):
    dx, dy = b[0] - a[0], b[1] - a[1]
    return abs((p[0] - a[0]) * dy - (p[1] - a[1]) * dx) / math.hypot(dx, dy)


def band(d):
    return '<2.5' if d < 2.5 else '2.5-3.5' if d < 3.5 else '3.5-4.5' if d < 4.5 else '4.5-6' if d < 6 else '6+'


BANDS = ['<2.5', '2.5-3.5', '3.5-4.5', '4.5-6', '6+']
cam, path, types_path = sys.argv[1], sys.argv[2], sys.argv[3]
types = [[x for x in l.strip().split(',') if x in ('I', 'P', 'B')][0] for l in open(types_path) if l.strip()]
rows = [r for r in csv.DictReader(open(path)) if r['camera'] == cam]
centre = {}
for r in rows:
    centre[(int(r['frame']), r['id'])] = (sum(float(r['wx%d' % k]) for k in range(4)) / 4,
                                         sum(float(r['wy%d' % k]) for k in range(4)) / 4)
groups = defaultdict(lambda: defaultdict(list))
for r in rows:
    f = int(r['frame'])
    w = [(float(r['wx%d' % k]), float(r['wy%d' % k])) for k in range(4)]
    c = centre[(f, r['id'])]
    speeds = [math.hypot(c[0] - centre[(g, r['id'])][0], c[1] - centre[(g, r['id'])][1])
              for g in (f - 1, f + 1) if (g, r['id']) in centre]
    speed = sum(speeds) / len(speeds) if speeds else float('nan')
    for s in (0, 1):
        d = 0.5 * (dist_pt_line(w[(s + 2) % 4], w[s], w[(s + 1) % 4]) +
                   dist_pt_line(w[(s + 3) % 4], w[s], w[(s + 1) % 4])) / 6
        off = 0.5 * (float(r['side%d_px' % s]) + float(r['side%d_px' % (s + 2)]))
        b = band(d)
        groups['all'][b].append(off)
        groups['frame ' + (types[f] if f < len(types) else '?')][b].append(off)
        if not math.isnan(speed):
            groups['speed < 8 px/frame' if speed < 8 else 'speed >= 8 px/frame'][b].append(off)
        groups['horizontal sides' if r['side%d_horizontal' % s] == '1' else 'vertical sides'][b].append(off)
        groups['x < 640' if c[0] < 640 else 'x >= 640'][b].append(off)
        groups['y < 360' if c[1] < 360 else 'y >= 360'][b].append(off)


def cell(xs):
    if not xs:
        return '-'
    m = sum(xs) / len(xs)
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / max(len(xs) - 1, 1))
    return '%+.3f (%d, se %.3f)' % (m, len(xs), sd / math.sqrt(len(xs)))


print('| split | ' + ' | '.join(BANDS) + ' |')
print('|---' * (len(BANDS) + 1) + '|')
for k in sorted(groups):
    print('| %s | %s |' % (k, ' | '.join(cell(groups[k][b]) for b in BANDS)))
