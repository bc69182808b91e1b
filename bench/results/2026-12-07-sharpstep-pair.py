#!/usr/bin/env python3
"""Pairs two diag_side_bias SIDES dumps (the same renders: same SEED, sizes, images) side by side.

usage: 2026-12-07-sharpstep-pair.py BASE.sides OTHER.sides
Prints per band of the marker's extent across the side (px): the mean offset of each (px, outward +) and
their paired difference OTHER - BASE with its standard error, over the sides both refined.
"""
import math
import sys


def load(path):
    sides = {}
    for line in open(path):
        marker, side, extent, offset = line.split()
        sides[(int(marker), int(side))] = (float(extent), float(offset))
    return sides


def main():
    base, other = load(sys.argv[1]), load(sys.argv[2])
    bands = [(0, 8), (8, 10), (10, 12), (12, 14), (14, 16), (16, 20), (20, 30), (30, 1e9)]
    out = []
    for lo, hi in bands:
        keys = [k for k in base if k in other and lo <= base[k][0] < hi]
        if not keys:
            continue
        d = [other[k][1] - base[k][1] for k in keys]
        mean = sum(d) / len(d)
        sd = math.sqrt(sum((x - mean) ** 2 for x in d) / max(1, len(d) - 1))
        b = sum(base[k][1] for k in keys) / len(keys)
        o = sum(other[k][1] for k in keys) / len(keys)
        out.append(f"{lo:g}-{hi:g} px: {b:+.4f} -> {o:+.4f}, paired {mean:+.4f} (se {sd / math.sqrt(len(d)):.4f}, n {len(d)})")
    print("; ".join(out))


if __name__ == "__main__":
    main()
