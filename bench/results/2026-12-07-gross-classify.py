#!/usr/bin/env python3
"""Gross corners of bench_accuracy 8, classified, and refinement-choice policies scored offline (issue 15, gross).

  2026-12-07-gross-classify.py TRUTH TRACE DUMP [policy ...]

TRUTH: `build/bench/diag_id123 --truth 8`. TRACE: GROSS_TRACE=file of a bench_accuracy run built with
2026-12-07-gross-trace.patch (one line per RefineCorners call: id, sharp frame (sm), candidate and its code
mismatches, the first refinement (smoothed on sharp frames), `alt` = the unsmoothed refinement from the
candidate (sharp frames), `sp` = cornerSubPix from the candidate, id123's retry, each with its mismatches).
DUMP: the same run's MCMT_CORNER_DUMP (the matrix only): trace lines are kept where they give the dump's
corners (the small-marker band's are left out). Policies (which refinement a marker keeps): main (as
11dbc98), w0 (this branch: a sharp frame's refinement reading worse than its candidate -> unsmoothed if
that reads better), v0 (... no worse), c<N> (allowance candidate + N instead of + cells; d<N>: so, and a marker neither reads within is dropped), b<X> (unsmoothed
where the candidate's thinnest cells are < X px), a<X> (unsmoothed where an edge moved > X cell from the
candidate), best (the fewer mismatches of smoothed / unsmoothed: needs both on every marker), oracle
(the one nearest the truth of smoothed / unsmoothed / cornerSubPix)."""
import math, sys
from collections import defaultdict, Counter
CELLS = 8
truth_path, trace_path, dump_path = sys.argv[1], sys.argv[2], sys.argv[3]
truths = defaultdict(list)
for line in open(truth_path):
    f = line.split()
    if len(f) < 15: continue
    c, s, g, i, mid = map(int, f[:5])
    pts = [(float(f[7 + 2 * k]), float(f[8 + 2 * k])) for k in range(4)]
    truths[mid].append(dict(c=c, s=s, g=g, i=i, side=float(f[5]), view=float(f[6]), pts=pts))

def parse(line):
    f = line.split()
    d = dict(id=int(f[1]), sm=int(f[3]), ref=int(f[5]), kept=int(f[7]), deconv=int(f[9]), candmis=int(f[11]))
    k = 12
    while k < len(f):
        w = f[k]
        if w in ("cand", "first", "alt", "sp", "retry"):
            m = int(f[k + 1]); p = [(float(f[k + 2 + 2 * j]), float(f[k + 3 + 2 * j])) for j in range(4)]
            d[w] = (m, p); k += 10
        elif w in ("altkept", "firstok", "slid"):
            d[w] = int(f[k + 1]); k += 2
        elif w == "subpix":
            d["subpix"] = 1; k += 1
        else:
            raise ValueError(w)
    return d

def centre(p): return (sum(q[0] for q in p) / 4, sum(q[1] for q in p) / 4)
def err(p, t): return [math.hypot(p[k][0] - t[k][0], p[k][1] - t[k][1]) for k in range(4)]
def side_off(p, t):
    """signed outward offset of p's side k (mean of its two corners) from t's side k line, px"""
    cx, cy = centre(t); out = []
    for k in range(4):
        a, b = t[k], t[(k + 1) % 4]
        nx, ny = b[1] - a[1], -(b[0] - a[0]); L = math.hypot(nx, ny); nx /= L; ny /= L
        if (a[0] - cx) * nx + (a[1] - cy) * ny < 0: nx, ny = -nx, -ny
        o = [((p[j][0] - a[0]) * nx + (p[j][1] - a[1]) * ny) for j in (k, (k + 1) % 4)]
        out.append(sum(o) / 2)
    return out
def depth(t):
    """cell depth across side k: distance of opposite side's midpoint to side k's line / cells"""
    out = []
    for k in range(4):
        a, b = t[k], t[(k + 1) % 4]; c, d = t[(k + 2) % 4], t[(k + 3) % 4]
        mx, my = (c[0] + d[0]) / 2, (c[1] + d[1]) / 2
        nx, ny = b[1] - a[1], -(b[0] - a[0]); L = math.hypot(nx, ny)
        out.append(abs((mx - a[0]) * nx + (my - a[1]) * ny) / L / CELLS)
    return out

def outcome(d, pol):
    allow = CELLS
    if pol.startswith("c") or pol.startswith("d"):  # tighter allowance c<N> (d<N>: drop, not cornerSubPix)
        allow = int(pol[1:])
    first_ok = d.get("first") is not None and d["first"][0] <= d["candmis"] + allow
    if pol == "main": first_ok = d["firstok"] == 1
    if pol.startswith("b") and pol[1:2].isdigit() and d["sm"]:  # no smoothing where a side's cells < X px (on candidate)
        thr = float(pol[1:])
        if min(depth(d["cand"][1])) < thr:
            if "alt" in d and d["alt"][0] <= d["candmis"] + allow: return "alt", d["alt"][1]
            return ("sp", d["sp"][1]) if d.get("subpix") or not d.get("slid") else ("drop", None)
    if pol == "best" and first_ok and "alt" in d and d["alt"][0] < d["first"][0]: return "alt", d["alt"][1]
    if pol.startswith("a") and pol[1:2].isdigit() and first_ok and d["sm"]:  # an edge moved > X cell from the candidate: alt
        thr = float(pol[1:]); cand = d["cand"][1]
        dep = depth(cand); mv = side_off(d["first"][1], cand)
        if any(abs(mv[k]) > thr * dep[k] for k in range(4)):
            if "alt" in d and d["alt"][0] <= d["candmis"] + allow: return "alt", d["alt"][1]
            return "sp", d["sp"][1]
    if pol.startswith("w") and first_ok and d["sm"] and d["first"][0] > d["candmis"] + int(pol[1:] or 0):
        # the smoothed refinement reads worse than the candidate: the unsmoothed one if it reads better
        if "alt" in d and d["alt"][0] < d["first"][0]: return "alt", d["alt"][1]
    if pol.startswith("v") and first_ok and d["sm"] and d["first"][0] > d["candmis"] + int(pol[1:] or 0):
        # ... or no worse
        if "alt" in d and d["alt"][0] <= d["first"][0]: return "alt", d["alt"][1]
    if pol == "oracle":
        opts = [(n, d[n][1]) for n in ("first", "alt", "sp") if n in d]
        return min(opts, key=lambda o: max(err(o[1], d["t"]["pts"])))
    if first_ok: return "first", d["first"][1]
    if d["sm"] and not d.get("slid"):
        if pol == "main":
            if "retry" in d and d["retry"][0] <= d["candmis"] + allow: return "retry", d["retry"][1]
        elif "alt" in d and d["alt"][0] <= d["candmis"] + allow: return "alt", d["alt"][1]
    if d.get("slid") or (pol.startswith("d") and not first_ok): return "drop", None
    return "sp", d["sp"][1]


# Trace lines of the matrix: those giving the dump's corners in order (a dropped marker between two of them too).
dump = [l.split() for l in open(dump_path)]
recs = []
j = 0
prev_matrix = False
for line in open(trace_path):
    if not line.startswith("M "): continue
    d = parse(line)
    how, p = outcome(d, "main")
    if p is None:
        matrix = prev_matrix
    else:
        matrix = False
        if j < len(dump):
            f = dump[j]; q = [float(x) for x in f[1:9]]; pp = [c for xy in p for c in xy]
            matrix = int(f[0]) == d["id"] and max(abs(a - b) for a, b in zip(q, pp)) < 0.002
        if matrix: j += 1
        prev_matrix = matrix
    if not matrix: continue
    cx, cy = centre(d["cand"][1]); best, bd = None, 8.0
    for t in truths[d["id"]]:
        tx, ty = centre(t["pts"]); dd = math.hypot(tx - cx, ty - cy)
        if dd < bd: best, bd = t, dd
    if best is None: continue
    d["t"] = best; recs.append(d)
print("trace lines of the matrix: %d (dump %d of %d)" % (len(recs), j, len(dump)))

pols = sys.argv[4:] or ["main"]
for pol in pols:
    gross = Counter(); gm = 0; found = 0; drops = 0; bandg = Counter(); paths = Counter(); gpaths = Counter()
    for d in recs:
        t = d["t"]; how, p = outcome(d, pol)
        paths[how] += 1
        paths["changed vs main"] += p != outcome(d, "main")[1]
        if p is None: drops += 1; continue
        found += 1
        e = err(p, t["pts"]); n = sum(x > 0.5 for x in e)
        if n: gm += 1; gross[t["c"]] += n; bandg[t["g"]] += n; gpaths[how] += 1
    print("%-6s corners>0.5 %d on %d markers, found %d, dropped %d; per cond %s; per angle band %s; paths %s; gross paths %s" %
          (pol, sum(gross.values()), gm, found, drops, dict(sorted(gross.items())), dict(sorted(bandg.items())), dict(paths), dict(gpaths)))


NAMES = ["plain","no margin","black tool","wood","two-cell white","shading","blur 1.2","defocus","motion","gamma","shot noise","webcam","hard","inverted","dark grey"]
def side_parts(p, T, k):
    a, b = T[k], T[(k + 1) % 4]; cx, cy = centre(T)
    nx, ny = b[1] - a[1], -(b[0] - a[0]); L = math.hypot(nx, ny); nx /= L; ny /= L
    if (a[0] - cx) * nx + (a[1] - cy) * ny < 0: nx, ny = -nx, -ny
    o = [((p[j][0] - a[0]) * nx + (p[j][1] - a[1]) * ny) for j in (k, (k + 1) % 4)]
    return L, (o[0] + o[1]) / 2, (o[1] - o[0]) / 2
def angle(T, k):
    a = T[(k - 1) % 4]; b = T[(k + 1) % 4]; c = T[k]
    v1 = (a[0] - c[0], a[1] - c[1]); v2 = (b[0] - c[0], b[1] - c[1])
    return math.degrees(math.acos((v1[0] * v2[0] + v1[1] * v2[1]) / math.hypot(*v1) / math.hypot(*v2)))
rows = []
for d in recs:
    t = d["t"]; how, p = outcome(d, "main")
    if p is None: continue
    T = t["pts"]; e = err(p, T)
    if max(e) > 5: continue
    sp = [side_parts(p, T, k) for k in range(4)]
    r = dict(c=t["c"], g=t["g"], view=t["view"], size=t["side"], mind=min(depth(T)), sm=d["sm"], how=how,
             gross=max(e) > 0.5, n=sum(x > 0.5 for x in e),
             A=any(abs(s[1]) + abs(s[2]) > 0.6 for s in sp),
             worse=("first" in d and how == "first" and d["first"][0] > d["candmis"]),
             cand=max(err(d["cand"][1], T)), res=max(e),
             acute=sum(1 for k in range(4) if e[k] > 0.5 and (angle(T, k) < 45 or angle(T, k) > 120)))
    rows.append(r)
def table(title, key, order=None):
    C = Counter(); G = Counter(); N = Counter(); A = Counter()
    for r in rows:
        k = key(r); C[k] += 1
        if r["gross"]: G[k] += 1; N[k] += r["n"]; A[k] += r["A"]
    print("\n| %s | markers | gross markers | gross corners | of them type A (a side > 0.6 px off) |" % title)
    print("|---|---:|---:|---:|---:|")
    for k in (order or sorted(C)):
        if C[k]: print("| %s | %d | %d (%.1f %%) | %d | %d |" % (k, C[k], G[k], 100 * G[k] / C[k], N[k], A[k]))
table("view angle band", lambda r: ["0-40 deg", "40-60 deg", "60-75 deg"][r["g"]])
table("view angle (truth)", lambda r: "%02d-%02d deg" % (r["view"] // 15 * 15, r["view"] // 15 * 15 + 15))
table("thinnest side's cell depth (truth)", lambda r: "< 1.0 px" if r["mind"] < 1.0 else "1.0-1.3 px" if r["mind"] < 1.3 else "1.3-2 px" if r["mind"] < 2 else "2-3 px" if r["mind"] < 3 else ">= 3 px")
table("condition", lambda r: "%2d %s" % (r["c"], NAMES[r["c"]]))
table("frame (sm: refined on the smoothed region first)", lambda r: "sharp (smoothed)" if r["sm"] else "blurred (unsmoothed)")
table("path of the result", lambda r: r["how"])
table("candidate's worst corner", lambda r: "< 0.5 px" if r["cand"] < 0.5 else "0.5-1 px" if r["cand"] < 1 else "1-2 px" if r["cand"] < 2 else ">= 2 px")
g = [r for r in rows if r["gross"]]
print("\ngross markers %d (corners %d): type A %d, type B %d; result worse than candidate %d; code reads worse than candidate %d;"
      " gross corners at corner angles < 45 or > 120 deg: %d" % (len(g), sum(r["n"] for r in g), sum(r["A"] for r in g), sum(not r["A"] for r in g),
      sum(r["res"] > r["cand"] for r in g), sum(r["worse"] for r in g), sum(r["acute"] for r in g)))
