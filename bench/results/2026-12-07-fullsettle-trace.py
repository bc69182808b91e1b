#!/usr/bin/env python3
"""First differing refinement decision between two MCMT_X_TRACE files (fullsettle-switches.patch).

Usage: 2026-12-07-fullsettle-trace.py A B [min_move_px]. Each refinement of A is paired with one of B of
the same id whose corner 0 lies within 3 px (within 20 lines). For each pair whose corner 0 moved more than
min_move_px (default 0.01), the first decision token that differs. Tokens: ':' crossing pass, '|' model
pass, ' ' next side, 'H' side held as settled, '(' two-surround fit, 's' warm single-surround fit,
Dn/Nn/Kn a fit's end (stop test / iteration cap / no improvement) after n iterations, 'mX' the pass's
corner move X px (ignored here), 'r' contrast reject, 'b' beyond reject, 'g' gamma-hint refit,
'f'/'u'/'h'/'c' one-level refit (faint, unseen, halo, low margin contrast), 'w' wide-tie refit, 'M' mean
of the last two passes, '#' end of a RefineOnce."""
import re
import sys
from collections import Counter

TOK = re.compile(r"[DNK]\d+|.")


def load(path):
    out = []
    for line in open(path):
        v = line.rstrip("\n").split(" ", 4)
        # the pass moves ("m0.0123") are read by eye, not compared
        tokens = re.sub(r"m[0-9.e+-]+", "", v[4]) if len(v) > 4 else ""
        out.append((int(v[0]), int(v[1]), float(v[2]), float(v[3]), tokens))
    return out


def kind(a, b):
    if a is None or b is None:
        return "one path ends (%s / %s)" % (a, b)
    for x, y, name in (("D", "D", "stop test: iterations"), ("N", "N", "cap: iterations")):
        if a[0] == x and b[0] == y:
            return name
    if {a[0], b[0]} == {"D", "N"}:
        return "stop test vs cap"
    if "K" in (a[0], b[0]):
        return "no-improvement end vs other"
    if {a, b} <= {"|", "#", "M"}:
        return "pass count / settle (%s vs %s)" % tuple(sorted((a, b)))
    if "H" in (a, b):
        return "side held (H vs %s)" % (b if a == "H" else a)
    return "%s vs %s" % tuple(sorted((a, b)))


a, b = load(sys.argv[1]), load(sys.argv[2])
limit = float(sys.argv[3]) if len(sys.argv) > 3 else 0.01
# Align: each refinement of A with the nearest unused one of B within 20 lines, same id, corner 0 within 3 px.
used = set()
pairs = []
for i, x in enumerate(a):
    best = None
    for j in range(max(0, i - 20), min(len(b), i + 21)):
        y = b[j]
        if j in used or y[0] != x[0]:
            continue
        d = ((x[2] - y[2]) ** 2 + (x[3] - y[3]) ** 2) ** 0.5
        if d < 3 and (best is None or d < best[0]):
            best = (d, j)
    if best:
        used.add(best[1])
        pairs.append((x, b[best[1]]))
kinds, later = Counter(), Counter()
moved = 0
for x, y in pairs:
    if ((x[2] - y[2]) ** 2 + (x[3] - y[3]) ** 2) ** 0.5 <= limit:
        continue
    moved += 1
    ta, tb = TOK.findall(x[4]), TOK.findall(y[4])
    first = None
    for i in range(max(len(ta), len(tb))):
        p = ta[i] if i < len(ta) else None
        q = tb[i] if i < len(tb) else None
        if p != q:
            k = kind(p, q)
            if first is None:
                first = k
                kinds[k] += 1
            if k.startswith("one path") or k.startswith("pass count") or p in "(s" or q in "(s":
                break  # past here the token lists no longer line up
    if first is None:
        kinds["same decisions"] += 1
    # decisions other than the stop test that differ anywhere in the refinement (token multisets)
    ca, cb = Counter(t[0] if t[0] in "DNK" else t for t in ta), Counter(t[0] if t[0] in "DNK" else t for t in tb)
    for t in set(ca) | set(cb):
        if ca[t] != cb[t] and t not in " :|":
            later[t] += 1
print(f"refinements {len(a)} / {len(b)}, aligned {len(pairs)}, moved > {limit} px: {moved}")
print("first differing decision:")
for k, c in kinds.most_common():
    print(f"  {c:5d}  {k}")
print("refinements whose count of a token differs (token: refinements):",
      ", ".join(f"{t!r}: {c}" for t, c in later.most_common()))
