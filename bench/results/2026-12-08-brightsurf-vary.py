#!/usr/bin/env python3
"""diag_side_exact's fixed point on a bright surface under blur, one scene change at a time (issue 15, helper
brightsurf): 12 ids x 4 sides, cells 1.7 px (SIDE_PX 13.6), the print's linear levels ink 25 / paper 225 /
surface 218 (0.855 / 0.882 of the paper), its face ending 3 cells beyond the edge on a background of 102.
Three modes: the detector's first model pass (ALONG0 0.8 px) and 6 warm passes; the first pass at the true
blur; and the first with 2026-12-08-brightsurf-trace.patch's MCMT_BS_UNSEEN_NOT_STICKY=1 (needs the patch).
  python3 2026-12-08-brightsurf-vary.py [BUILD_DIR (default build)]"""
import subprocess, os, re, sys
B = os.path.join(sys.argv[1] if len(sys.argv) > 1 else 'build', 'bench', 'diag_side_exact')
def run(env, blur, side_px=13.6, ids=range(12)):
    es, singles, L1s, S1s = [], 0, [], []
    for i in ids:
        for k in range(4):
            e = dict(os.environ, **{a: str(b) for a, b in env.items()})
            out = subprocess.run([B, str(i), str(k), str(blur), str(side_px)], env=e, capture_output=True, text=True).stdout.split('\n')[0]
            m = re.search(r'e ([-+][\d.]+) px.*L0 ([-\d.]+) L1 ([-\d.]+) S1 ([-\d.]+) S2 ([-\d.]+) q ([-\d.]+) single (\d)', out)
            if not m: continue
            es.append(float(m.group(1))); singles += int(m.group(7)); L1s.append(float(m.group(3))); S1s.append(float(m.group(4)))
    n = len(es)
    return '%+.4f px | %.0f %% single | L1 %.0f | S1 %.0f | n %d' % (sum(es) / n, 100 * singles / n, sum(L1s) / n, sum(S1s) / n, n)
base = dict(INK=25, PAPERL=225, SURFACE=218, EXT=3, BG=102, MARGIN=1)
cases = [('base (surface 218, face end 3 c, BG 102, margin 1 c)', {}, 1.05),
         ('blur 0.6', {}, 0.6),
         ('surface 178.6 (0.70)', dict(SURFACE=178.6), 1.05),
         ('surface 127.6 (0.5)', dict(SURFACE=127.6), 1.05),
         ('face end out of reach (EXT 10)', dict(EXT=10), 1.05),
         ('face end 4 c (EXT 4)', dict(EXT=4), 1.05),
         ('BG 200 (bright beyond)', dict(BG=200), 1.05),
         ('BG 25 (black beyond)', dict(BG=25), 1.05),
         ('margin 0.5 c', dict(MARGIN=0.5), 1.05),
         ('margin 2 c', dict(MARGIN=2), 1.05)]
MODES = [('main: first pass 0.8 px along, 6 passes', dict(ALONG0=0.8, PASSES=6)),
         ('first pass at the true blur, 6 passes', dict(PASSES=6)),
         ('unseen not sticky, first pass 0.8, 6 passes', dict(ALONG0=0.8, PASSES=6, MCMT_BS_UNSEEN_NOT_STICKY=1))]
for mode, menv in MODES:
    for name, ch, blur in cases:
        env = dict(base, **ch, **menv)
        print('| %s | %s | %s |' % (mode, name, run(env, blur)))
