#!/usr/bin/python3
# Issue 15 (widemodel): analysis of the side-fit dumps of 2026-12-05-widemodel-diag.patch.
#   MCMT_SIDE_DUMP=/tmp/wm_dumpA build/bench/diag_bistable /tmp/wm_startA.txt   (likewise B; MCMT_COLUMN_RAYS=1 ...)
#   MCMT_DIAG_TRUTH=/tmp/wm/truth build/bench/diag_bistable                     (ideal render + unit-square map)
#   python3 2026-12-05-widemodel-analysis.py summary DUMP...    per side: params, residual rms, depth spread
#   python3 2026-12-05-widemodel-analysis.py bins DUMP SIDE     per group and bin: measured, model, residual
#   python3 2026-12-05-widemodel-analysis.py truth DUMP SIDE ROI_X ROI_Y   per ray: the true cells along it,
#                                       its drift across the columns, measured vs ideal render (smoothed 0.6)
import sys
import numpy as np

def records(path):
    recs=[]; cur=None
    for line in open(path):
        t=line.split()
        if t[0]=='FIT':
            cur=dict(side=int(t[2]),ok=int(t[4]),single=int(t[6]),cell=float(t[8]),u0=float(t[10]),du=float(t[12]),bins=int(t[14]),params=np.array([float(x) for x in t[18:26]]),groups=[],bins_=[],rays=[])
        elif t[0]=='GROUP':
            cur['groups'].append(dict(pattern=(int(t[3]),int(t[4])),rays=int(t[6]),depth=(float(t[8]),float(t[9])),other=(float(t[11]),float(t[12]))))
        elif t[0]=='BIN':
            cur['bins_'].append((int(t[1]),int(t[2]),float(t[3]),float(t[4]),float(t[5]),float(t[6])))
        elif t[0]=='RAY':
            r=dict(group=int(t[1]),along=float(t[3]),shift=float(t[5]),pattern=(int(t[7]),int(t[8])),depths=(float(t[10]),float(t[11])),other=(float(t[13]),float(t[14])),o=(float(t[16]),float(t[18])),n=(float(t[20]),float(t[22])))
            r['v']=np.array([float(x) for x in t[24:]]); cur['rays'].append(r)
        elif t[0]=='END':
            cur['bins_']=np.array(cur['bins_']); recs.append(cur)
    return recs
def last(path,side):
    return [r for r in records(path) if r['side']==side][-1]


BITS_ID7 = np.array([[1, 0, 0, 0, 1, 0], [0, 0, 1, 0, 1, 0], [0, 1, 0, 1, 0, 0], [0, 0, 1, 1, 1, 1],
                     [0, 0, 1, 0, 1, 0], [0, 1, 1, 0, 1, 0]])


def cell(ux, uy):  # the marker's cell colour at unit-square points (-1 outside the marker)
    c = np.floor(ux * 8).astype(int)
    r = np.floor(uy * 8).astype(int)
    inside = (c >= 0) & (c < 8) & (r >= 0) & (r < 8)
    code = (c >= 1) & (c <= 6) & (r >= 1) & (r <= 6)
    v = np.where(inside, 0, -1)
    return np.where(code, BITS_ID7[np.clip(r - 1, 0, 5), np.clip(c - 1, 0, 5)], v)


def truth_maps(prefix='/tmp/wm/truth'):
    unit = np.fromfile(prefix + '.unit', dtype=np.float32).reshape(561, 561, 2)
    f = open(prefix + '.ideal', 'rb')
    w, h = map(int, f.readline().split())
    ideal = np.frombuffer(f.read(), dtype=np.float32).reshape(h, w)
    return unit, ideal


def bilinear(img, x, y):
    ix = np.floor(x).astype(int)
    iy = np.floor(y).astype(int)
    ax, ay = x - ix, y - iy
    return (img[iy, ix] * (1 - ax) * (1 - ay) + img[iy, ix + 1] * ax * (1 - ay) + img[iy + 1, ix] * (1 - ax) * ay +
            img[iy + 1, ix + 1] * ax * ay)


def unit_at(unit, x, y):  # the map covers x 520..660, y 500..640 at 0.25 px
    fx, fy = (x - 520) * 4, (y - 500) * 4
    return np.stack([bilinear(unit[:, :, k].astype(np.float64), fx, fy) for k in range(2)], axis=-1)


def summary(paths):
    for path in paths:
        recs = records(path)
        for side in range(4):
            r = [x for x in recs if x['side'] == side][-1]
            b = r['bins_']
            w, res, p = b[:, 3], b[:, 4] - b[:, 5], r['params']
            d = np.array([x['depths'][0] for x in r['rays']])
            print(f"{path} side {side} cell {r['cell']:.2f} e {p[0]:+.3f} sigma {p[1]:.3f} L0 {p[2]:.1f} L1 {p[3]:.1f} "
                  f"S1 {p[4]:.1f} S2 {p[5]:.1f} q {p[6]:.2f} gamma {p[7]:.2f} rms {np.sqrt(np.sum(w * res**2) / np.sum(w)):.2f} "
                  f"depths {d.min():.2f}-{d.max():.2f}")


def bins(path, side):
    r = last(path, side)
    b, e = r['bins_'], r['params'][0]
    for g, G in enumerate(r['groups']):
        print(f"group {g} rows {G['pattern']} rays {G['rays']}: u-e, measured, model, residual")
        for m in b[b[:, 0] == g]:
            print(f"  {m[2] - e:6.2f} {m[4]:7.2f} {m[5]:7.2f} {m[4] - m[5]:6.2f}")


def truth(path, side, roi_x, roi_y):
    from scipy.ndimage import gaussian_filter
    unit, ideal = truth_maps()
    smoothed = np.round(gaussian_filter(ideal.astype(np.float64), 0.6, truncate=2.0 / 0.6))
    r = last(path, side)
    e = r['params'][0]
    u = r['u0'] + np.arange(r['bins']) * r['du']
    for ray in sorted(r['rays'], key=lambda x: x['along']):
        s = ray['shift'] + u  # the dump's ray: point o + s n
        x = roi_x + ray['o'][0] + s * ray['n'][0]
        y = roi_y + ray['o'][1] + s * ray['n'][1]
        un = unit_at(unit, x, y)
        c = cell(un[:, 0], un[:, 1])
        along = [un[:, 0], 1 - un[:, 1], 1 - un[:, 0], un[:, 1]][side] * 8
        res = ray['v'] - bilinear(smoothed, x, y)
        print(f"along {ray['along'] * 8:5.2f} rows {ray['pattern']} true cells inward..outward "
              f"{''.join('x' if v < 0 else str(v) for v in c)} drift {along[0] - along[np.argmin(abs(u - e))]:+.2f} "
              f"columns, measured - ideal rms {np.sqrt(np.mean(res**2)):.2f}")


if __name__ == '__main__':
    if sys.argv[1] == 'summary':
        summary(sys.argv[2:])
    elif sys.argv[1] == 'bins':
        bins(sys.argv[2], int(sys.argv[3]))
    else:
        truth(sys.argv[2], int(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5]))
