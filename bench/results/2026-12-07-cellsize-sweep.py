#!/usr/bin/env python3
# Issue 15 (helper cellsize): mean fitted edge offset (px, outward +) of diag_side_exact over ids 0-3, sides 0-3,
# rolls and two pixel offsets, per cell size (CELLS, px). Pass diag_side_exact's options in the environment, e.g.
#   INK=25 PAPERL=225 PIX=1 BOX=8 python3 2026-12-07-cellsize-sweep.py   (B: blur px, default 0.01: none)
import os, re, subprocess, sys, statistics
exe = os.environ.get('EXE', os.path.join(os.path.dirname(os.path.abspath(__file__)), '../../build/bench/diag_side_exact'))
cells = [float(x) for x in os.environ.get('CELLS', '1.3 1.6 1.9 2.2 2.5').split()]
blur = os.environ.get('B', '0.01')
rolls = os.environ.get('ROLLS', '0 17 33 61').split()
offs = [('0.3', '0.7'), ('0.55', '0.1')]
ids = range(int(os.environ.get('NIDS', '4')))
for c in cells:
    es, sig, lines, tilts = [], [], [], []
    for i in ids:
        for s in range(4):
            for r in rolls:
                for ox, oy in offs:
                    env = dict(os.environ, ROLL=r, OFFX=ox, OFFY=oy)
                    out = subprocess.run([exe, str(i), str(s), blur, str(8 * c)], env=env, capture_output=True, text=True).stdout
                    m = re.search(r'e ([-+.\d]+) px \(edge at ([-+.\d]+), tilt ([-+.\d]+)\) sigma ([.\d]+)', out)
                    if not m: continue
                    es.append(float(m.group(2))); tilts.append(float(m.group(3))); sig.append(float(m.group(4)))
                if os.environ.get('PIX', '0') == '0': break
    print(f"cell {c:.2f} px: n {len(es)} edge mean {statistics.mean(es):+.4f} (sd {statistics.pstdev(es):.4f}) "
          f"sigma {statistics.mean(sig):.3f} |tilt| {statistics.mean(abs(t) for t in tilts):.3f}", flush=True)
