#!/usr/bin/env python3
# The tracker's poses in the map's own frames (rig = the reference camera's, object = the reference
# marker's: the frames the published covariance is of), against an mcmt-sim ground truth; and the map's
# camera centres against the mapper's 1-sigma (report.json). mcmt-eval instead aligns the rig on every
# camera centre and the object on every corner (Horn), which takes out part of the map's error.
#   2026-12-07-mapcov-frames.py GROUND_TRUTH.yaml MAP.yaml POSES.csv [REPORT.json]
# Needs numpy and PyYAML (Debian: python3-numpy, python3-yaml).
import csv
import json
import sys

import numpy as np
import yaml


def rotation(w, x, y, z):
    n = np.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def pose(d):
    m = np.eye(4)
    m[:3, :3] = rotation(*d['rotation_wxyz'])
    m[:3, 3] = d['translation']
    return m


gt = yaml.safe_load(open(sys.argv[1]))
mp = yaml.safe_load(open(sys.argv[2]))
rows = list(csv.DictReader(open(sys.argv[3])))
a = pose(gt['cameras'][mp['reference_camera']]['rig_from_cam'])  # world_from_rig
markers = gt['markers']
b = pose(markers[mp['reference_marker']]['object_from_marker'])  # body_from_object
frames = {f['seq']: f for f in gt['frames']}
beyond_p = beyond_r = 0
errors, sigmas = [], []
for r in rows:
    e = np.eye(4)
    e[:3, :3] = rotation(float(r['qw']), float(r['qx']), float(r['qy']), float(r['qz']))
    e[:3, 3] = [float(r['tx']), float(r['ty']), float(r['tz'])]
    est = a @ e @ np.linalg.inv(b)
    g = pose(frames[int(r['seq'])]['rig_from_object'])
    t = np.linalg.norm(est[:3, 3] - g[:3, 3])
    angle = np.arccos(np.clip((np.trace(est[:3, :3] @ g[:3, :3].T) - 1) / 2, -1, 1))
    sp, sr = float(r['sigma_position_m']), float(r['sigma_rotation_rad'])
    beyond_p += t > 3 * sp
    beyond_r += angle > 3 * sr
    errors.append(t)
    sigmas.append(sp)
n = len(rows)
print(f"map frames: position error mean {1e3 * np.mean(errors):.3f} mm (max {1e3 * np.max(errors):.3f}), "
      f"sigma median {1e3 * np.median(sigmas):.3f} mm; beyond 3 sigma: position {100 * beyond_p / n:.1f} %, "
      f"rotation {100 * beyond_r / n:.1f} %")
if len(sys.argv) > 4:
    sigma = {c['name']: c.get('sigma_position_mm') for c in json.load(open(sys.argv[4]))['diagnostics']['cameras']}
    a_inv = np.linalg.inv(a)
    nees, axes = 0.0, 0
    for c in mp['cameras']:
        d = 1e3 * (pose(c['rig_from_cam'])[:3, 3] - (a_inv @ pose(gt['cameras'][c['name']]['rig_from_cam']))[:3, 3])
        if sigma[c['name']]:
            nees += float(np.sum((d / np.array(sigma[c['name']])) ** 2))
            axes += 3
        print(f"  {c['name']}: centre error {np.round(d, 3)} mm, mapper's sigma {sigma[c['name']]}")
    print(f"camera centres: squared error / variance per axis {nees / max(axes, 1):.2f} (1 for a right covariance)")
