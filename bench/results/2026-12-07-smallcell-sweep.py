#!/usr/bin/env python3
# Issue 15 (helper smallcell): mean fitted edge offset (px, outward +) of diag_side_exact, line at the truth, over ids x sides x
# pixel offsets, per (cell px, blur px, roll deg). Env: EXE, CELLS, BLURS, ROLLS, NIDS, OFFS ("x,y x,y"),
# ALONGPIX (px^2: ALONG = sqrt(blur^2 + ALONGPIX)), RAW (1: each run's edge, for smallcell-pair.py), plus
# diag_side_exact's (PIX, BOX, INK, PAPERL, CROSS, ...) and the model patch's SM_BOXW.
import os, re, subprocess, statistics, sys
exe = os.environ.get('EXE', os.path.join(os.path.dirname(os.path.abspath(__file__)), '../../build/bench/diag_side_exact'))
cells = [float(x) for x in os.environ.get('CELLS', '1.0 1.3 1.6 2.0 2.5 3.0').split()]
blurs = os.environ.get('BLURS', '0.01 0.3 0.6 0.9 1.2').split()
rolls = os.environ.get('ROLLS', '0 22.5 45').split()
offs = [tuple(o.split(',')) for o in os.environ.get('OFFS', '0.3,0.7 0.55,0.1').split()]
ids = range(int(os.environ.get('NIDS', '4')))
print('cell blur roll n mean sd sigma', flush=True)
for c in cells:
  for b in blurs:
    for r in rolls:
      es, sig = [], []
      for i in ids:
        for s in range(4):
          for ox, oy in offs:
            env = dict(os.environ, ROLL=r, OFFX=ox, OFFY=oy)
            if os.environ.get('ALONGPIX'): env['ALONG'] = str((float(b)**2 + float(os.environ['ALONGPIX']))**0.5)
            out = subprocess.run([exe, str(i), str(s), b, str(8 * c)], env=env, capture_output=True, text=True).stdout
            m = re.search(r'e ([-+.\d]+) px \(edge at ([-+.\d]+), tilt ([-+.\d]+)\) sigma ([.\d]+)', out)
            if not m: continue
            es.append(float(m.group(2))); sig.append(float(m.group(4)))
      if es:
        print(f"{c:.2f} {float(b):.2f} {float(r):5.1f} {len(es)} {statistics.mean(es):+.4f} {statistics.pstdev(es):.4f} {statistics.mean(sig):.3f}" + (' RAW ' + ' '.join(f'{e:.5f}' for e in es) if os.environ.get('RAW') else ''), flush=True)
