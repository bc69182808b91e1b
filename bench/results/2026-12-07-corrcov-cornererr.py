#!/usr/bin/env python3
# True corner errors of a session's detections (residuals.csv's observed corners minus the ground truth's
# projection; pinhole, no distortion) and their correlation structure.
#   2026-12-07-corrcov-cornererr.py GROUND_TRUTH.yaml RESIDUALS.csv [write-variants DIR]
# (residuals.csv of mcmt-mapper's output folder; /usr/bin/python3 with python3-numpy, python3-yaml).
# Prints: the errors' size, outward offset, autocorrelation over frames, per-track means; the share of the
# variance in cluster means (track / marker / camera, image or marker-local coordinates) for the true errors
# and the residuals; the per-track bias sigma by the method of moments; the relative outward offset kappa.
# write-variants DIR: det.csv files for mcmt-import --csv (observed, iid, noscale, onlyscale, shuffled).
import csv, sys, collections
import numpy as np, yaml

def rotation(w, x, y, z):
    n = np.sqrt(w*w+x*x+y*y+z*z); w, x, y, z = w/n, x/n, y/n, z/n
    return np.array([[1-2*(y*y+z*z), 2*(x*y-z*w), 2*(x*z+y*w)],
                     [2*(x*y+z*w), 1-2*(x*x+z*z), 2*(y*z-x*w)],
                     [2*(x*z-y*w), 2*(y*z+x*w), 1-2*(x*x+y*y)]])
def pose(d):
    m = np.eye(4); m[:3, :3] = rotation(*d['rotation_wxyz']); m[:3, 3] = d['translation']; return m

gt = yaml.safe_load(open(sys.argv[1]))
cams = {n: c for n, c in gt['cameras'].items()}
cam_from_rig = {n: np.linalg.inv(pose(c['rig_from_cam'])) for n, c in cams.items()}
markers = {int(k): v for k, v in gt['markers'].items()}
frames = {f['seq']: pose(f['rig_from_object']) for f in gt['frames']}
def truth(cam, mid, seq):
    s = markers[mid]['size'] / 2
    pts = np.array([[-s, s, 0, 1], [s, s, 0, 1], [s, -s, 0, 1], [-s, -s, 0, 1]]).T
    p = cam_from_rig[cam] @ frames[seq] @ pose(markers[mid]['object_from_marker']) @ pts
    c = cams[cam]
    return np.stack([c['fx'] * p[0] / p[2] + c['cx'], c['fy'] * p[1] / p[2] + c['cy']], 1)

obs = collections.defaultdict(dict)
status = {}
for r in csv.DictReader(open(sys.argv[2])):
    k = (r['camera'], int(r['id']), int(r['seq']))
    obs[k][int(r['corner'])] = (float(r['x']), float(r['y']))
    status[k] = r['status']
E, keys, outward, side = {}, [], {}, {}
for k, c in obs.items():
    o = np.array([c[i] for i in range(4)])
    t = truth(*k)
    e = o - t
    E[k] = e
    cen = t.mean(0)
    u = (t - cen) / np.linalg.norm(t - cen, axis=1, keepdims=True)
    outward[k] = float(np.mean(np.sum(e * u, 1)))  # common outward offset, px
    side[k] = float(np.mean(np.linalg.norm(t - np.roll(t, 1, 0), axis=1)))
keys = sorted(E, key=lambda k: (k[0], k[1], k[2]))
allE = np.concatenate([E[k] for k in keys])
print(f"{len(keys)} observations; corner error mean {allE.mean(0)}, sd {allE.std(0)} px, rms {np.sqrt((allE**2).mean()):.4f}")
ow = np.array([outward[k] for k in keys]); sd = np.array([side[k] for k in keys])
print(f"outward offset: mean {ow.mean():+.4f} px (sd {ow.std():.4f}); relative to half side: mean {np.mean(ow/(sd/2))*100:+.4f} %")
# share of variance: translation (common), outward (scale), the rest
tr = np.array([E[k].mean(0) for k in keys])
print(f"per-observation common shift rms {np.sqrt((tr**2).mean()):.4f} px; outward rms {np.sqrt((ow**2).mean()):.4f} px")
# autocorrelation over consecutive frames of the same (cam, marker, corner)
tracks = collections.defaultdict(list)
for k in keys: tracks[k[:2]].append(k[2])
for lag in (1, 2, 3, 5, 10, 20):
    a, b = [], []
    for (cam, mid), seqs in tracks.items():
        s = set(seqs)
        for q in seqs:
            if q + lag in s:
                a.append(E[(cam, mid, q)].ravel()); b.append(E[(cam, mid, q + lag)].ravel())
    a, b = np.array(a), np.array(b)
    corr = np.sum(a * b) / np.sqrt(np.sum(a * a) * np.sum(b * b))
    oa = [outward[(c, m, q)] for (c, m), seqs in tracks.items() for q in seqs if q + lag in set(seqs)]
    ob = [outward[(c, m, q + lag)] for (c, m), seqs in tracks.items() for q in seqs if q + lag in set(seqs)]
    print(f"lag {lag:2d}: corner error corr {corr:+.3f} (pairs {len(a)}); outward corr {np.corrcoef(oa, ob)[0,1]:+.3f}")
# per (camera, marker) track mean error: how much of the error is a constant per track
print("per track: n, mean outward px, mean corner error (x,y) per corner rms, share of variance in track means")
tot = 0; bet = 0
for (cam, mid), seqs in sorted(tracks.items()):
    e = np.array([E[(cam, mid, q)] for q in seqs])  # n x 4 x 2
    m = e.mean(0)
    tot += np.sum(e**2); bet += len(seqs) * np.sum(m**2)
    print(f"  {cam} m{mid}: n {len(seqs):3d}, outward {np.mean([outward[(cam, mid, q)] for q in seqs]):+.4f}, track-mean rms {np.sqrt(np.mean(m**2)):.4f}")
print(f"share of corner error variance in per-track means: {bet/tot:.3f}")
# batch means on outward per track

obs2 = collections.defaultdict(dict)
for r in csv.DictReader(open(sys.argv[2])):
    k = (r['camera'], int(r['id']), int(r['seq']))
    obs2[k][int(r['corner'])] = (float(r['x']), float(r['y']), float(r['dx']), float(r['dy']), r['status'])

# cluster shares
def local(t, e):
    # corner errors in the marker's image frame: along side 0->1 (u) and perpendicular (v), per corner
    u = t[1] - t[0]; u /= np.linalg.norm(u); v = np.array([-u[1], u[0]])
    return np.stack([e @ u, e @ v], 1)
for which in ('true', 'residual'):
  for coords in ('image', 'local'):
    E2 = {}
    for k, c in obs2.items():
        if any(c[i][4] != 'inlier' for i in range(4)): continue
        o = np.array([c[i][:2] for i in range(4)]); t = truth(*k)
        e = o - t if which == 'true' else -np.array([c[i][2:4] for i in range(4)])
        E2[k] = local(t, e) if coords == 'local' else e
    for name, cl in (('track', lambda k: k[:2]), ('marker', lambda k: k[1]), ('camera', lambda k: k[0])):
        g = collections.defaultdict(list)
        for k, e in E2.items(): g[cl(k)].append(e)
        num = sum(len(v) * np.sum(np.mean(v, 0)**2) for v in g.values())
        den = sum(np.sum(np.array(v)**2) for v in g.values())
        N = len(E2); T = len(g)
        # overdispersion of cluster means: 1 for independent errors
        print(f"{which:8s} {coords:5s} cluster {name:6s}: T {T:2d}, share {num/den:.4f}, overdispersion {num/den*N/T:.2f}")

# bias sigma
for which in ('true', 'residual'):
    g = collections.defaultdict(list)
    for k, c in obs2.items():
        if any(c[i][4] != 'inlier' for i in range(4)): continue
        o = np.array([c[i][:2] for i in range(4)]).ravel()
        e = o - truth(*k).ravel() if which == 'true' else np.array([c[i][2:4] for i in range(4)]).ravel()
        g[k[:2]].append(e)
    N = sum(len(v) for v in g.values()); T = len(g)
    ss = sum(np.sum(np.array(v)**2) for v in g.values())
    between = sum(np.sum(np.sum(v, 0)**2) / len(v) for v in g.values())
    sw2 = (ss - between) / (8 * (N - T)); sb2 = (between - 8 * sw2 * T) / (8 * N)
    print(f"{which}: sw {np.sqrt(sw2):.4f} px, sb {np.sqrt(max(sb2,0)):.4f} px")

# kappa
for which in ('true', 'residual'):
    g = collections.defaultdict(list)
    for k, c in obs2.items():
        if any(c[i][4] != 'inlier' for i in range(4)): continue
        o = np.array([c[i][:2] for i in range(4)])
        e = o - truth(*k) if which == 'true' else -np.array([c[i][2:4] for i in range(4)])
        cen = o.mean(0); d = o - cen; dist = np.linalg.norm(d, axis=1)
        g[k[:2]].append(np.mean(np.sum(e * d / dist[:, None], 1)) / np.mean(dist))
    allk = np.concatenate([np.array(v) for v in g.values()])
    N = len(allk); T = len(g)
    ss = sum(np.sum((np.array(v) - np.mean(v))**2) for v in g.values())
    sw2 = ss / (N - T)
    between = sum(len(v) * np.mean(v)**2 for v in g.values())
    means = np.array([np.mean(v) for v in g.values()])
    sb2 = (sum(len(v) * (np.mean(v) - allk.mean())**2 for v in g.values()) - (T - 1) * sw2) / N
    print(f"{which:8s}: kappa mean {100*allk.mean():+.3f} %, track means sd {100*means.std():.3f} %, between-track sigma {100*np.sqrt(max(sb2,0)):.3f} % (rms incl. mean {100*np.sqrt(max((between - T*sw2)/N,0)):.3f} %), within {100*np.sqrt(sw2):.3f} %")

if len(sys.argv) > 4 and sys.argv[3] == 'write-variants':
    import os
    out = sys.argv[4]; os.makedirs(out, exist_ok=True)
    rng = np.random.default_rng(1)
    sig = allE.std()
    def write(name, fn):
        with open(os.path.join(out, name + '.csv'), 'w') as f:
            f.write('utime,seq,camera,id,x0,y0,x1,y1,x2,y2,x3,y3\n')
            for k in sorted(obs, key=lambda k: (k[2], k[0], k[1])):
                t = truth(*k); c = fn(k, t)
                utime = 1000000000000 + int(round(k[2] * 1e6 / 30))
                f.write(f"{utime},{k[2]},{k[0]},{k[1]}," + ",".join(f"{v:.6f}" for v in c.ravel()) + "\n")
    write('observed', lambda k, t: t + E[k])
    write('iid', lambda k, t: t + rng.normal(0, sig, (4, 2)))
    def noscale(k, t):
        cen = t.mean(0); u = (t - cen) / np.linalg.norm(t - cen, axis=1, keepdims=True)
        return t + E[k] - outward[k] * u
    write('noscale', noscale)
    def onlyscale(k, t):
        cen = t.mean(0); u = (t - cen) / np.linalg.norm(t - cen, axis=1, keepdims=True)
        return t + outward[k] * u
    write('onlyscale', onlyscale)
    # the same errors, each track's errors shuffled over its frames (breaks the frame-to-frame correlation)
    perm = {}
    for (cam, mid), seqs in tracks.items():
        p = rng.permutation(len(seqs))
        for i, q in enumerate(seqs): perm[(cam, mid, q)] = (cam, mid, seqs[p[i]])
    write('shuffled', lambda k, t: t + E[perm[k]])
