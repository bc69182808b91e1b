#!/usr/bin/env python3
"""Summarise PMFIT lines (PM_DUMP=1 on the papermargin switch build): the tied fits' margin width q (cells),
the paper read against the fitted code level L1, and the surround, as percentiles. Pure Python."""
import sys


def pct(v, ps=(10, 25, 50, 75, 90)):
    v = sorted(v)
    return " ".join("%.3f" % v[min(len(v) - 1, int(p / 100 * len(v)))] for p in ps)


rows = []
for line in open(sys.argv[1]):
    if not line.startswith("PMFIT"):
        continue
    t = line.split()[1:]
    rows.append({t[i]: float(t[i + 1]) for i in range(0, len(t), 2)})
print("fits", len(rows), "(p10 p25 p50 p75 p90)")
print("q / cell          ", pct([r["q"] for r in rows]))
print("share q < 0.02 c  ", "%.3f" % (sum(r["q"] < 0.02 for r in rows) / len(rows)))
print("(Plin-L1)/(L1-L0) ", pct([(r["plin"] - r["L1"]) / (r["L1"] - r["L0"]) for r in rows if r["L1"] != r["L0"]]))
print("(S2-L0)/(Plin-L0) ", pct([(r["S2"] - r["L0"]) / (r["plin"] - r["L0"]) for r in rows if r["plin"] != r["L0"]]))
print("gamma             ", pct([r["gamma"] for r in rows]))
print("cell px           ", pct([r["cell"] for r in rows]))
