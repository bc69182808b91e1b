import csv, sys, collections, math
rows = list(csv.DictReader(open(sys.argv[1])))
m = collections.defaultdict(list)
for r in rows:
    if r['fully_visible'] != '1' or r['occluded'] != '0': continue
    m[(r['camera'], r['seq'], r['id'])].append(r)
bands = collections.defaultdict(list)
for k, cs in m.items():
    if len(cs) != 4: continue
    xs = [float(c['x']) - float(c['dx']) for c in cs]; ys = [float(c['y']) - float(c['dy']) for c in cs]
    cx, cy = sum(xs) / 4, sum(ys) / 4
    out = []
    for c, x, y in zip(cs, xs, ys):
        ux, uy = x - cx, y - cy; n = math.hypot(ux, uy)
        out.append((float(c['dx']) * ux + float(c['dy']) * uy) / n)
    v = float(cs[0]['view_deg']); s = float(cs[0]['size_px'])
    band = f"{int(v // 20) * 20:2d}-{int(v // 20) * 20 + 20} deg"
    bands[band].append(sum(out) / 4); bands['all'].append(sum(out) / 4)
    bands[f"size {int(s // 5) * 5}-{int(s // 5) * 5 + 5} px"].append(sum(out) / 4)
for b in sorted(bands): print(f"{b:16s} n={len(bands[b]):5d} mean radial {sum(bands[b]) / len(bands[b]):+.4f} px")
