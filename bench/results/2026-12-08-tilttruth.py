#!/usr/bin/env python3
"""tilttruth: per marker side, the signed outward offset at each end against the chessboard's
prediction, base vs MCMT_X_CLEAN_ALL=2. Input: diag_charuco per-marker CSVs (with side{s}_clean).
usage: 2026-12-08-tilttruth.py DIR   (DIR/{base,x2}_cam{0..3}.csv)"""
import csv, math, sys, statistics as st
from collections import defaultdict

D = sys.argv[1]
MAXVIEW = float(sys.argv[2]) if len(sys.argv) > 2 else 55.0  # the tone-auto test's views
# mcmt's corners and the chessboard prediction differ by a constant image shift of about (-0.5, -0.5) px
# in every camera (a pixel-centre convention; sizes and tilts do not see it, per-side offsets do): the
# prediction is moved by SHIFT px in x and y (ideal px; 0 to see it).
SHIFT = float(sys.argv[3]) if len(sys.argv) > 3 else -0.5


def load(v):
    out = {}
    for c in range(4):
        with open(f"{D}/{v}_cam{c}.csv") as f:
            for r in csv.DictReader(f):
                g = [(float(r[f"gx{k}"]), float(r[f"gy{k}"])) for k in range(4)]
                w = [(float(r[f"wx{k}"]) + SHIFT, float(r[f"wy{k}"]) + SHIFT) for k in range(4)]
                cx, cy = sum(p[0] for p in w) / 4, sum(p[1] for p in w) / 4
                for s in range(4):
                    a, b = w[s], w[(s + 1) % 4]
                    dx, dy = b[0] - a[0], b[1] - a[1]
                    L = math.hypot(dx, dy)
                    nx, ny = dy / L, -dx / L
                    if nx * ((a[0] + b[0]) / 2 - cx) + ny * ((a[1] + b[1]) / 2 - cy) < 0:
                        nx, ny = -nx, -ny
                    ga, gb = g[s], g[(s + 1) % 4]
                    oa = nx * (ga[0] - a[0]) + ny * (ga[1] - a[1])
                    ob = nx * (gb[0] - b[0]) + ny * (gb[1] - b[1])
                    clean = r[f"side{s}_clean"]
                    ts = [(i + 0.5) / len(clean) for i, ch in enumerate(clean) if ch == "1"]
                    key = (r["camera"], int(r["frame"]), int(r["id"]), s)
                    out[key] = dict(cam=r["camera"], view=float(r["view_deg"]), L=float(r["side_px"]),
                                    oa=oa, ob=ob, ts=ts, nclean=len(ts), clean=clean,
                                    size=float(r["size_rel"]), mid=(r["camera"], int(r["frame"]), int(r["id"])))
    return out


base, x2 = load("base"), load("x2")
# IDSHIFT=1 (4th argument): also remove each id's own print shift, the mean over all its detections (base,
# views <= MAXVIEW) of the antisymmetric part of opposite sides' offsets ((o0 - o2) / 2, (o1 - o3) / 2, per
# px of side), from both variants. It cannot tell a print shift from a detection bias tied to an id's
# sides (both are fixed on the board); sizes and tilts do not see it.
if len(sys.argv) > 4 and sys.argv[4] == "1":
    acc = defaultdict(list)
    for k, d in base.items():
        if d["view"] <= MAXVIEW: acc[(k[2], k[3])].append(0.5 * (d["oa"] + d["ob"]) / d["L"])
    anti = {}
    for i in range(10):
        mm = [sum(acc[(i, s_)]) / len(acc[(i, s_)]) for s_ in range(4)]
        a0, a1 = 0.5 * (mm[0] - mm[2]), 0.5 * (mm[1] - mm[3])
        anti.update({(i, 0): a0, (i, 2): -a0, (i, 1): a1, (i, 3): -a1})
    for dd in (base, x2):
        for k, d in dd.items():
            c_ = anti[(k[2], k[3])] * d["L"]
            d["oa"] -= c_; d["ob"] -= c_
keys = sorted(set(base) & set(x2))
# Per id and side, the mean outward offset (base): the shift's check (constant per side index: a shift).
g = defaultdict(list)
for k in keys:
    if base[k]["view"] <= MAXVIEW: g[(k[2], k[3])].append(0.5 * (base[k]["oa"] + base[k]["ob"]))
print("base mean outward offset per id, sides 0..3 (px):")
for i in range(10):
    print(f"  id {i}: " + " ".join(f"{sum(g[(i, s_)]) / len(g[(i, s_)]):+.3f}" for s_ in range(4)))
print(f"sides in both: {len(keys)} (base {len(base)}, x2 {len(x2)}); views <= {MAXVIEW} deg")


def kind(d):
    """Where the side's clean rays lie: 'none' (< 4: every valid ray is used), 'start'/'end' (all in
    one half: the clean cluster's end), 'both' (clean rays in both thirds at the ends), 'spread'."""
    ts = d["ts"]
    if len(ts) < 4: return "none"
    if max(ts) < 0.5: return "start"
    if min(ts) > 0.5: return "end"
    if min(ts) < 1 / 3 and max(ts) > 2 / 3: return "both"
    return "mid"


rows = []
for k in keys:
    b, x = base[k], x2[k]
    if b["view"] > MAXVIEW: continue
    kd = kind(b)
    # near = the clean cluster's end, far = the other (for start/end sides); else a = start, b = end
    if kd == "end":
        nb, fb, nx_, fx = b["ob"], b["oa"], x["ob"], x["oa"]
    else:
        nb, fb, nx_, fx = b["oa"], b["ob"], x["oa"], x["ob"]
    span = (max(b["ts"]) - min(b["ts"])) if b["ts"] else 0
    rows.append(dict(cam=b["cam"], view=b["view"], L=b["L"], kind=kd, span=span, nclean=b["nclean"],
                     nb=nb, fb=fb, nx=nx_, fx=fx, key=k))


def band_view(v): return "0-30" if v < 30 else "30-45" if v < 45 else "45-55" if v <= 55 else ">55"
def band_size(L): return "<28" if L < 28 else "28-40" if L < 40 else ">=40"


def m(v): return sum(v) / len(v) if v else float("nan")
def se(v): return st.stdev(v) / math.sqrt(len(v)) if len(v) > 2 else float("nan")


def table(title, keyf, groups=None):
    g = defaultdict(list)
    for r in rows: g[keyf(r)].append(r)
    print(f"\n### {title}\n")
    print("| group | sides | base near | base far | base far-near | `=2` near | `=2` far | `=2` far-near | "
          "d near | d far | d mean (se) | base abs tilt | `=2` abs tilt |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in (groups or sorted(g)):
        v = g.get(name, [])
        if not v: continue
        nb = [r["nb"] for r in v]; fb = [r["fb"] for r in v]; nx = [r["nx"] for r in v]; fx = [r["fx"] for r in v]
        dm = [0.5 * (r["nx"] + r["fx"] - r["nb"] - r["fb"]) for r in v]
        print(f"| {name} | {len(v)} | {m(nb):+.4f} | {m(fb):+.4f} | {m([a-b for a,b in zip(fb,nb)]):+.4f} | "
              f"{m(nx):+.4f} | {m(fx):+.4f} | {m([a-b for a,b in zip(fx,nx)]):+.4f} | "
              f"{m([a-b for a,b in zip(nx,nb)]):+.4f} | {m([a-b for a,b in zip(fx,fb)]):+.4f} | "
              f"{m(dm):+.4f} ({se(dm):.4f}) | {m([abs(a-b) for a,b in zip(fb,nb)]):.4f} | "
              f"{m([abs(a-b) for a,b in zip(fx,nx)]):.4f} |")


K = ["none", "start", "end", "mid", "both"]
table("All cameras, by where the clean rays lie (near = start corner unless 'end')", lambda r: r["kind"], K)
for cam in ["cam0", "cam1", "cam2", "cam3"]:
    table(f"{cam}, by where the clean rays lie", lambda r, c=cam: r["kind"] if r["cam"] == c else None, K)
ONE = ("start", "end")
table("One-end sides (clean cluster at one end), by camera", lambda r: r["cam"] if r["kind"] in ONE else None,
      ["cam0", "cam1", "cam2", "cam3"])
table("One-end sides, by view band (deg)", lambda r: band_view(r["view"]) if r["kind"] in ONE else None,
      ["0-30", "30-45", "45-55", ">55"])
table("One-end sides, by marker side (px)", lambda r: band_size(r["L"]) if r["kind"] in ONE else None,
      ["<28", "28-40", ">=40"])
table("One-end sides, by clean rays' span (fraction of side)",
      lambda r: ("<0.15" if r["span"] < 0.15 else "0.15-0.3" if r["span"] < 0.3 else ">=0.3") if r["kind"] in ONE else None,
      ["<0.15", "0.15-0.3", ">=0.3"])
table("All sides, by camera", lambda r: r["cam"], ["cam0", "cam1", "cam2", "cam3"])

# Size: each side's contribution to the perimeter change is (its two end offsets' sum); mean over the
# sides of one kind, as a share of the camera's total change of sum(offsets).
print("\n### Change of the summed end offsets (x2 - base), px per marker, by side kind and end\n")
print("| camera | markers | total d(sum of 8 end offsets) | none | one-end: near | one-end: far | mid | both |")
print("|---|---|---|---|---|---|---|---|")
for cam in ["cam0", "cam1", "cam2", "cam3"]:
    v = [r for r in rows if r["cam"] == cam]
    nm = len(set(r["key"][:3] for r in v))
    part = defaultdict(float)
    for r in v:
        if r["kind"] in ONE:
            part["near"] += r["nx"] - r["nb"]; part["far"] += r["fx"] - r["fb"]
        else:
            part[r["kind"]] += r["nx"] + r["fx"] - r["nb"] - r["fb"]
    tot = sum(part.values())
    print(f"| {cam} | {nm} | {tot / nm:+.4f} | {part['none'] / nm:+.4f} | {part['near'] / nm:+.4f} | "
          f"{part['far'] / nm:+.4f} | {part['mid'] / nm:+.4f} | {part['both'] / nm:+.4f} |")

# The size error (%) split by side kind and end, exactly: each marker's four lines are rebuilt through the
# predicted corners moved along the outward normals by the chosen ends' offsets only (the other ends at
# the prediction), their crossings give the corners, and the perimeter over the predicted one - 1.
def perimeter(c): return sum(math.dist(c[k], c[(k + 1) % 4]) for k in range(4))


def cross(p1, p2, q1, q2):
    d1 = (p2[0] - p1[0], p2[1] - p1[1]); d2 = (q2[0] - q1[0], q2[1] - q1[1])
    den = d1[0] * d2[1] - d1[1] * d2[0]
    t = ((q1[0] - p1[0]) * d2[1] - (q1[1] - p1[1]) * d2[0]) / den
    return (p1[0] + t * d1[0], p1[1] + t * d1[1])


want_of = {}
for c in range(4):
    with open(f"{D}/base_cam{c}.csv") as f:
        for r in csv.DictReader(f):
            want_of[(r["camera"], int(r["frame"]), int(r["id"]))] = [
                (float(r[f"wx{k}"]) + SHIFT, float(r[f"wy{k}"]) + SHIFT) for k in range(4)]


def size_part(mkey, ends):
    """ends: {(side, 0|1): offset px}; the perimeter change (relative) with only those ends moved."""
    w = want_of[mkey]
    cx, cy = sum(p[0] for p in w) / 4, sum(p[1] for p in w) / 4
    lines = []
    for s_ in range(4):
        a, b = w[s_], w[(s_ + 1) % 4]
        L = math.dist(a, b)
        nx, ny = (b[1] - a[1]) / L, -(b[0] - a[0]) / L
        if nx * ((a[0] + b[0]) / 2 - cx) + ny * ((a[1] + b[1]) / 2 - cy) < 0: nx, ny = -nx, -ny
        oa, ob = ends.get((s_, 0), 0.0), ends.get((s_, 1), 0.0)
        lines.append(((a[0] + oa * nx, a[1] + oa * ny), (b[0] + ob * nx, b[1] + ob * ny)))
    corners = [cross(*lines[(k + 3) % 4], *lines[k]) for k in range(4)]
    return perimeter(corners) / perimeter(w) - 1


GROUPS = ["none", "near", "far", "mid", "both"]
print("\n### Size error (%) split by side kind and end (exact perimeter, only that group's ends moved)\n")
print("| camera | variant | size_rel | sum of parts | none | one-end near | one-end far | mid | both |")
print("|---|---|---|---|---|---|---|---|---|")
by_marker = defaultdict(list)
for r in rows: by_marker[r["key"][:3]].append(r)
for cam in ["cam0", "cam1", "cam2", "cam3"]:
    mk = [k for k in by_marker if k[0] == cam]
    res = {}
    for vi, (n_, f_) in enumerate([("nb", "fb"), ("nx", "fx")]):
        part = defaultdict(float)
        for mkey in mk:
            for g in GROUPS:
                ends = {}
                for r in by_marker[mkey]:
                    s_ = r["key"][3]
                    ni, fi = (1, 0) if r["kind"] == "end" else (0, 1)
                    if r["kind"] in ONE:
                        if g == "near": ends[(s_, ni)] = r[n_]
                        if g == "far": ends[(s_, fi)] = r[f_]
                    elif r["kind"] == g:
                        ends[(s_, ni)] = r[n_]; ends[(s_, fi)] = r[f_]
                if ends: part[g] += 100 * size_part(mkey, ends) / len(mk)
        sr = m([100 * base[(mkey + (0,))]["size"] if vi == 0 else 100 * x2[(mkey + (0,))]["size"] for mkey in mk])
        res[vi] = (sr, part)
    for vi, name in [(0, "base"), (1, "`=2`"), (2, "`=2` - base")]:
        if vi < 2:
            sr, part = res[vi]
        else:
            sr = res[1][0] - res[0][0]
            part = {g: res[1][1][g] - res[0][1][g] for g in GROUPS}
        print(f"| {cam} | {name} | {sr:+.3f} | {sum(part.values()):+.3f} | " +
              " | ".join(f"{part[g]:+.3f}" for g in GROUPS) + " |")

# Tilt bias free of the marker's rotation: the clean cluster at the start or at the end of a side (ArUco
# order runs round the marker: a rotation adds +r to end-start on every side) -> (start + end kinds) / 2.
print("\n### Far-end minus near-end offset on one-end sides, rotation removed ((start kind + end kind) / 2), px\n")
print("| camera | base: bias | base: rotation | `=2`: bias | `=2`: rotation | sides start / end |")
print("|---|---|---|---|---|---|")
for cam in ["cam0", "cam1", "cam2", "cam3", None]:
    s_ = [r for r in rows if r["kind"] == "start" and (cam is None or r["cam"] == cam)]
    e_ = [r for r in rows if r["kind"] == "end" and (cam is None or r["cam"] == cam)]
    tb_s, tb_e = m([r["fb"] - r["nb"] for r in s_]), m([r["fb"] - r["nb"] for r in e_])
    tx_s, tx_e = m([r["fx"] - r["nx"] for r in s_]), m([r["fx"] - r["nx"] for r in e_])
    print(f"| {cam or 'all'} | {(tb_s + tb_e) / 2:+.4f} | {(tb_s - tb_e) / 2:+.4f} | {(tx_s + tx_e) / 2:+.4f} | "
          f"{(tx_s - tx_e) / 2:+.4f} | {len(s_)} / {len(e_)} |")
