#!/usr/bin/env python3
"""tilttruth: every model-pass ray's mid-level crossing against the chessboard-predicted side.
Input: DIR/{base,x2}_camN.csv (diag_charuco) and DIR/{base,x2}_camN.rays (MCMT_X_RAY_DUMP). Each side of
each final marker takes the last dumped model pass whose ends lie within TOL px of its final corners.
usage: 2026-12-08-tilttruth-rays.py DIR [variant base|x2]"""
import csv, math, sys
from collections import defaultdict

D = sys.argv[1]
VARIANTS = sys.argv[2:] or ["base", "x2"]
SHIFT, TOL, MAXVIEW, CELLS = -0.5, 0.05, 55.0, 6


def m(v): return sum(v) / len(v) if v else float("nan")


def load(v, cam):
    sides = {}  # (frame, id, side) -> dict
    with open(f"{D}/{v}_{cam}.csv") as f:
        for r in csv.DictReader(f):
            if float(r["view_deg"]) > MAXVIEW: continue
            g = [(float(r[f"gx{k}"]), float(r[f"gy{k}"])) for k in range(4)]
            w = [(float(r[f"wx{k}"]) + SHIFT, float(r[f"wy{k}"]) + SHIFT) for k in range(4)]
            for s in range(4):
                sides[(int(r["frame"]), int(r["id"]), s)] = dict(g=(g[s], g[(s + 1) % 4]), w=(w[s], w[(s + 1) % 4]),
                                                               wc=w, L=float(r["side_px"]), clean=r[f"side{s}_clean"])
    bucket = defaultdict(list)
    for k, d in sides.items():
        bucket[(int(d["g"][0][0]), int(d["g"][0][1]))].append(k)
    with open(f"{D}/{v}_{cam}.rays") as f:
        for line in f:
            t = line.split()
            ox, oy = float(t[1]), float(t[2])  # the refinement region's origin: its ideal px are shifted
            t = t[3:]
            ax, ay, bx, by = map(float, t[1:5])
            ax, ay, bx, by = ax + ox, ay + oy, bx + ox, by + oy
            hit = None
            for dx in (-1, 0, 1):
                for dy in (-1, 0, 1):
                    for k in bucket.get((int(ax) + dx, int(ay) + dy), []):
                        (gax, gay), (gbx, gby) = sides[k]["g"]
                        if abs(gax - ax) < TOL and abs(gay - ay) < TOL and abs(gbx - bx) < TOL and abs(gby - by) < TOL:
                            hit = k
            if hit is None: continue
            ri = t.index("R"); ki = t.index("K")
            rays = []
            for tok in t[ri + 1:ki]:
                i, c, x, y = tok.split(":")
                rays.append((int(i), int(c), float(x) + ox, float(y) + oy))
            sides[hit]["rays"] = rays
            sides[hit]["use_clean"] = int(t[6])
            kn = (float(t[ki + 2]), float(t[ki + 3]))
            sides[hit]["K"] = (int(t[ki + 1]), kn[0], kn[1], float(t[ki + 4]) + kn[0] * ox + kn[1] * oy)
            fn = (float(t[ki + 6]), float(t[ki + 7]))
            sides[hit]["F"] = (fn[0], fn[1], float(t[ki + 8]) + fn[0] * ox + fn[1] * oy)
    return {k: d for k, d in sides.items() if "rays" in d}


def frame_of(d):
    """The truth side's outward normal and tangent, and its start (ideal px)."""
    (ax, ay), (bx, by) = d["w"]
    wc = d["wc"]
    cx, cy = sum(p[0] for p in wc) / 4, sum(p[1] for p in wc) / 4
    L = math.hypot(bx - ax, by - ay)
    tx, ty = (bx - ax) / L, (by - ay) / L
    nx, ny = ty, -tx
    if nx * ((ax + bx) / 2 - cx) + ny * ((ay + by) / 2 - cy) < 0: nx, ny = -nx, -ny
    return (ax, ay), (nx, ny), (tx, ty), L


def line_end_offsets(line, d):
    """A line n.x = c's outward offsets at the truth side's two ends (along the truth normal)."""
    (ax, ay), (nx, ny), (tx, ty), L = frame_of(d)
    lnx, lny, c = line
    out = []
    for (px, py) in [(ax, ay), (ax + L * tx, ay + L * ty)]:
        # the point p + u n on the line: lnx (px + u nx) + lny (py + u ny) = c
        den = lnx * nx + lny * ny
        out.append((c - lnx * px - lny * py) / den)
    return out


def kind(clean):
    ts = [(i + 0.5) / len(clean) for i, ch in enumerate(clean) if ch == "1"]
    if len(ts) < 4: return "none", ts
    if max(ts) < 0.5: return "start", ts
    if min(ts) > 0.5: return "end", ts
    if min(ts) < 1 / 3 and max(ts) > 2 / 3: return "both", ts
    return "mid", ts


for v in VARIANTS:
    print(f"\n## {v}\n")
    # A: per-ray crossing offsets (outward, from the truth side), relative to the same side's clean rays'
    # mean, by distance from the clean cluster's end (cells), one-end sides.
    prof = defaultdict(lambda: defaultdict(list))
    lines_tab = defaultdict(lambda: defaultdict(list))
    arch = defaultdict(lambda: defaultdict(list))
    for cam in ["cam0", "cam1", "cam2", "cam3"]:
        S = load(v, cam)
        for k, d in S.items():
            kd, ts = kind(d["clean"])
            (ax, ay), (nx, ny), (tx, ty), L = frame_of(d)
            offs = []
            for (i, c, x, y) in d["rays"]:
                u = ((x - ax) * tx + (y - ay) * ty) / L  # 0..1 along the truth side
                o = (x - ax) * nx + (y - ay) * ny
                offs.append((i, c, u, o))
            clean_o = [o for (i, c, u, o) in offs if c]
            if kd in ("start", "end") and len(clean_o) >= 2:
                cm = m(clean_o)
                for (i, c, u, o) in offs:
                    dist = u if kd == "start" else 1 - u  # from the clean end
                    b = min(CELLS - 1, int(dist * CELLS))
                    prof[(cam, "clean" if c else "unclean")][b].append(o - cm)
                    prof[("all", "clean" if c else "unclean")][b].append(o - cm)
                    prof[("all", "abs")][b].append(o)
            # C: every side (any kind): each ray's crossing minus the mean of the side's crossings, by cell
            # (from the side's start corner) and clean flag: the crossings' profile along the side.
            if len(offs) >= 12:
                om = m([o for (i, c, u, o) in offs])
                for (i, c, u, o) in offs:
                    b = min(CELLS - 1, max(0, int(u * CELLS)))
                    arch[(cam, "clean" if c else "unclean")][b].append(o - om)
                    arch[("all", "clean" if c else "unclean")][b].append(o - om)
                    arch[("all", "any")][b].append(o - om)
            # B: crossing line (K) and final line (F) against the truth, at the near / far ends.
            if kd in ("start", "end") and d["K"][0]:
                ka, kb = line_end_offsets(d["K"][1:], d)
                fa, fb = line_end_offsets(d["F"], d)
                g = d["g"]
                if kd == "end": ka, kb, fa, fb = kb, ka, fb, fa
                for cc in (cam, "all"):
                    lines_tab[cc]["K near"].append(ka); lines_tab[cc]["K far"].append(kb)
                    lines_tab[cc]["F near"].append(fa); lines_tab[cc]["F far"].append(fb)
                    lines_tab[cc]["K far-near " + kd].append(kb - ka)
                    lines_tab[cc]["F far-near " + kd].append(fb - fa)
    print("### One-end sides: each ray's crossing (outward px from the truth side) minus the side's clean "
          "crossings' mean, by distance from the clean end (cell 0 = the corner's)\n")
    print("| camera | rays | " + " | ".join(f"cell {b}" for b in range(CELLS)) + " |")
    print("|---|---|" + "---|" * CELLS)
    for key in sorted(prof):
        row = prof[key]
        print(f"| {key[0]} | {key[1]} | " + " | ".join(
            f"{m(row[b]):+.3f} ({len(row[b])})" if row[b] else "" for b in range(CELLS)) + " |")
    print("\n### Every side: each ray's crossing minus its side's mean crossing (px, outward), by cell from "
          "the side's start corner\n")
    print("| camera | rays | " + " | ".join(f"cell {b}" for b in range(CELLS)) + " |")
    print("|---|---|" + "---|" * CELLS)
    for key in sorted(arch):
        row = arch[key]
        print(f"| {key[0]} | {key[1]} | " + " | ".join(
            f"{m(row[b]):+.3f} ({len(row[b])})" if row[b] else "" for b in range(CELLS)) + " |")
    print("\n### One-end sides: the crossing line (K) and the final line (F) against the truth at the near "
          "(clean) and far ends, px; far-near by kind (start / end: their mean removes the marker's rotation)\n")
    print("| camera | sides | K near | K far | F near | F far | K far-near (start, end, bias) | F far-near (start, end, bias) |")
    print("|---|---|---|---|---|---|---|---|")
    for cc in ["cam0", "cam1", "cam2", "cam3", "all"]:
        t = lines_tab[cc]
        ks, ke = m(t["K far-near start"]), m(t["K far-near end"])
        fs, fe = m(t["F far-near start"]), m(t["F far-near end"])
        print(f"| {cc} | {len(t['K near'])} | {m(t['K near']):+.4f} | {m(t['K far']):+.4f} | {m(t['F near']):+.4f} | "
              f"{m(t['F far']):+.4f} | {ks:+.4f}, {ke:+.4f}, **{(ks + ke) / 2:+.4f}** | "
              f"{fs:+.4f}, {fe:+.4f}, **{(fs + fe) / 2:+.4f}** |")
