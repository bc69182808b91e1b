#!/usr/bin/python3
"""mcmt-report OUTDIR: writes OUTDIR/report.html, a calibration report a person can read.

One self-contained page (every image inlined as a data: URI, no script, no external resource) that opens
in any browser without a server. It reads what mcmt-mapper wrote into OUTDIR: map.yaml, trajectory.csv,
report.json (with its "diagnostics": per-camera verdicts, predicted RMS, coverage, pose covariance) and
residuals.csv (every corner of every observation, inlier or rejected with the reason), and draws with
Debian's python3-matplotlib. The rig picture comes from mcmt-viz --snapshot (headless EGL) when it runs.
"""
import argparse
import base64
import csv
import html
import io
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

# Filled in by CMake when the script is copied into the build tree (report/CMakeLists.txt).
VERSION = "@PROJECT_VERSION@"

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402

PROGRAM = "mcmt-report"
VERDICT_COLOURS = {"good": "#1a7f37", "fair": "#b58900", "poor": "#cf222e"}


class ReportError(Exception):
    pass


# ---- inputs ------------------------------------------------------------------------------------------

def read_structured(path, parse, kind, errors):
    """A JSON or YAML file; errors name the file."""
    try:
        with open(path) as f:
            return parse(f)
    except OSError as e:
        raise ReportError(f"{path}: cannot read: {e.strerror}")
    except errors as e:
        raise ReportError(f"{path}: not valid {kind}: {str(e).splitlines()[0]}")


def read_json(path):
    return read_structured(path, json.load, "JSON", json.JSONDecodeError)


def read_map(path):
    return read_structured(path, yaml.safe_load, "YAML", yaml.YAMLError)


def read_csv(path, required):
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        raise ReportError(f"{path}: cannot read: {e.strerror}")
    if rows and not set(required) <= set(rows[0].keys()):
        missing = sorted(set(required) - set(rows[0].keys()))
        raise ReportError(f"{path}: missing columns {', '.join(missing)}")
    return rows


def residual_arrays(rows):
    """residuals.csv rows -> dict of numpy arrays (one entry per corner)."""
    def col(name, kind=float):
        out = []
        for r in rows:
            v = r[name]
            out.append(kind(v) if v != "" else float("nan"))
        return np.array(out)

    return {
        "utime": col("utime", int), "camera": np.array([r["camera"] for r in rows]),
        "id": col("id", int), "x": col("x"), "y": col("y"), "dx": col("dx"), "dy": col("dy"),
        "inlier": np.array([r["status"] == "inlier" for r in rows], dtype=bool),
        "reason": np.array([r["reason"] for r in rows]),
    }


def load(outdir):
    paths = {k: os.path.join(outdir, f) for k, f in
             [("map", "map.yaml"), ("report", "report.json"), ("trajectory", "trajectory.csv"),
              ("residuals", "residuals.csv")]}
    for key, p in paths.items():
        if not os.path.exists(p):
            raise ReportError(f"{p}: missing (run mcmt-mapper --out {outdir} first)")
    report = read_json(paths["report"])
    if "diagnostics" not in report:
        raise ReportError(f"{paths['report']}: diagnostics: missing (written by an older mcmt-mapper)")
    trajectory = read_csv(paths["trajectory"], ["utime", "tx", "ty", "tz", "rms_px"])
    residuals = read_csv(paths["residuals"], ["utime", "camera", "id", "x", "y", "dx", "dy", "status"])
    return {"map": read_map(paths["map"]), "report": report, "trajectory": trajectory,
            "res": residual_arrays(residuals), "paths": paths}


# ---- figures -----------------------------------------------------------------------------------------

def png_uri(fig):
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=80, bbox_inches="tight")
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def file_uri(path):
    with open(path, "rb") as f:
        return "data:image/png;base64," + base64.b64encode(f.read()).decode("ascii")


def camera_sizes(m):
    return {c["name"]: (c["intrinsics"]["width"], c["intrinsics"]["height"]) for c in m["cameras"]}


def histogram_figure(res, cam):
    sel = res["camera"] == cam
    err = np.hypot(res["dx"][sel], res["dy"][sel])
    inl = res["inlier"][sel]
    fig, ax = plt.subplots(figsize=(4.2, 3))
    finite = np.isfinite(err)
    top = max(1.0, np.percentile(err[finite], 99.5)) if finite.any() else 1.0
    bins = np.linspace(0, top, 40)
    ax.hist(np.clip(err[finite & inl], 0, top), bins=bins, color="#4477aa", label="inliers")
    if (finite & ~inl).any():
        ax.hist(np.clip(err[finite & ~inl], 0, top), bins=bins, color="#cc6677", alpha=0.8, label="rejected")
    ax.set_xlabel("corner residual |projected - observed| (px)")
    ax.set_ylabel("corners")
    ax.set_title(f"{cam}: residuals")
    ax.legend(fontsize=8)
    return png_uri(fig)


def image_axes(ax, size, title):
    w, h = size
    ax.set_xlim(0, w)
    ax.set_ylim(h, 0)
    ax.set_aspect("equal")
    ax.set_title(title)
    ax.set_xlabel("x (px)")
    ax.set_ylabel("y (px)")


def vectors_figure(res, cam, size):
    sel = (res["camera"] == cam) & res["inlier"] & np.isfinite(res["dx"])
    fig, ax = plt.subplots(figsize=(4.6, 3.8))
    x, y, dx, dy = res["x"][sel], res["y"][sel], res["dx"][sel], res["dy"][sel]
    if len(x) > 4000:  # an even subset keeps the picture readable
        keep = np.linspace(0, len(x) - 1, 4000).astype(int)
        x, y, dx, dy = x[keep], y[keep], dx[keep], dy[keep]
    mag = np.hypot(dx, dy)
    scale_px = max(np.percentile(mag, 90), 1e-6) if len(mag) else 1.0
    gain = 0.04 * size[0] / scale_px  # the 90th percentile residual drawn 4% of the image wide
    ax.quiver(x, y, dx * gain, dy * gain, mag, angles="xy", scale_units="xy", scale=1, cmap="viridis",
              width=0.003)
    image_axes(ax, size, f"{cam}: residual vectors (x{gain:.0f})")
    return png_uri(fig)


def coverage_figure(res, cam, size):
    sel = (res["camera"] == cam) & res["inlier"]
    fig, ax = plt.subplots(figsize=(4.6, 3.8))
    w, h = size
    nx = 32
    ny = max(1, round(nx * h / w))
    counts, _, _ = np.histogram2d(res["x"][sel], res["y"][sel], bins=[nx, ny], range=[[0, w], [0, h]])
    shown = np.ma.masked_equal(counts.T, 0)
    im = ax.imshow(shown, extent=[0, w, h, 0], cmap="magma_r", interpolation="nearest")
    ax.set_facecolor("#e8e8e8")
    fig.colorbar(im, ax=ax, label="inlier corners")
    image_axes(ax, size, f"{cam}: where markers were seen (grey: never)")
    return png_uri(fig)


def markers_figure(m):
    markers = m.get("markers") or []
    fig, ax = plt.subplots(figsize=(max(4, 0.25 * len(markers) + 2), 3))
    ids = [str(k["id"]) for k in markers]
    ax.bar(ids, [k.get("rms_px", 0) for k in markers], color="#4477aa")
    ax.set_xlabel("marker id")
    ax.set_ylabel("rms (px)")
    ax.set_title("reprojection rms per marker")
    if len(ids) > 30:
        ax.tick_params(axis="x", labelrotation=90, labelsize=6)
    return png_uri(fig)


def marker_square(pose, side):
    r = np.array(pose["rotation_matrix"], dtype=float).reshape(3, 3)
    t = np.array(pose["translation"], dtype=float)
    h = side / 2
    corners = np.array([[-h, h, 0], [h, h, 0], [h, -h, 0], [-h, -h, 0], [-h, h, 0]])
    return corners @ r.T + t


def layout_figure(m):
    fig = plt.figure(figsize=(5.5, 4.5))
    ax = fig.add_subplot(projection="3d")
    pts = []
    for k in m.get("markers") or []:
        sq = marker_square(k["object_from_marker"], k["size"])
        ax.plot(sq[:, 0], sq[:, 1], sq[:, 2], color="#222222", linewidth=1)
        ax.text(*sq[:4].mean(axis=0), str(k["id"]), fontsize=7, color="#aa3377")
        pts.append(sq)
    if pts:
        allp = np.vstack(pts)
        centre, half = allp.mean(axis=0), max(np.ptp(allp, axis=0).max() / 2, 1e-3)
        for set_lim, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre):
            set_lim(c - half, c + half)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    ax.set_title("marker layout (object frame = reference marker)")
    return png_uri(fig)


def trajectory_figure(rows):
    t0 = int(rows[0]["utime"]) if rows else 0
    t = np.array([(int(r["utime"]) - t0) * 1e-6 for r in rows])
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 4.6), sharex=True)
    for key, colour in (("tx", "#cc3311"), ("ty", "#009988"), ("tz", "#0077bb")):
        a1.plot(t, [float(r[key]) for r in rows], color=colour, linewidth=1, label=key[1])
    a1.set_ylabel("rig_from_object\nposition (m)")
    a1.legend(fontsize=8, ncol=3)
    a2.plot(t, [float(r["rms_px"]) for r in rows], color="#333333", linewidth=0.8)
    a2.set_ylabel("frame rms (px)")
    a2.set_xlabel("time since the first frame (s)")
    a1.set_title("the object's trajectory and each frame's reprojection rms")
    return png_uri(fig)


def uncertainty_figure(cams):
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(8, 3))
    names = [c["name"] for c in cams]
    pos = [np.linalg.norm(c.get("sigma_position_mm", [0, 0, 0])) for c in cams]
    rot = [np.linalg.norm(c.get("sigma_rotation_deg", [0, 0, 0])) for c in cams]
    a1.bar(names, pos, color="#4477aa")
    a1.set_ylabel("1-sigma position (mm)")
    a2.bar(names, rot, color="#ee7733")
    a2.set_ylabel("1-sigma rotation (deg)")
    for a in (a1, a2):
        a.tick_params(axis="x", labelrotation=45)
    fig.suptitle("camera pose uncertainty from the bundle adjustment (reference camera: 0 by definition)")
    return png_uri(fig)


def rig_picture(outdir, viz):
    """mcmt-viz --snapshot of the map and trajectory; (data URI or None, note)."""
    if not viz:
        return None, "mcmt-viz not found next to mcmt-report nor on PATH"
    tmp = tempfile.mkdtemp(prefix="mcmt_report_")
    try:
        png = os.path.join(tmp, "rig.png")
        cmd = [viz, "--map", os.path.join(outdir, "map.yaml"), "--trajectory",
               os.path.join(outdir, "trajectory.csv"), "--snapshot", png]
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=120)
        if p.returncode != 0 or not os.path.exists(png):
            lines = p.stdout.strip().splitlines()
            return None, "mcmt-viz failed: " + (lines[-1] if lines else f"exit {p.returncode}")
        return file_uri(png), ""
    except (OSError, subprocess.TimeoutExpired) as e:
        return None, f"mcmt-viz failed: {e}"
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


# ---- page --------------------------------------------------------------------------------------------

CSS = """
body { font-family: sans-serif; margin: 2em auto; max-width: 1200px; color: #222; }
h1 { margin-bottom: 0.2em; } h2 { border-bottom: 1px solid #ccc; padding-bottom: 0.2em; margin-top: 1.6em; }
table { border-collapse: collapse; font-size: 0.9em; } td, th { border: 1px solid #ddd; padding: 0.3em 0.6em; }
th { background: #f4f4f4; text-align: left; } td.num { text-align: right; font-variant-numeric: tabular-nums; }
.verdict { color: white; font-weight: bold; padding: 0.1em 0.5em; border-radius: 0.3em; }
.figs { display: flex; flex-wrap: wrap; gap: 0.5em; align-items: flex-start; } .figs img { max-width: 100%; }
.note { color: #666; font-size: 0.9em; } .camera { margin-top: 1.2em; }
"""


def esc(x):
    return html.escape(str(x))


def fmt(v, digits=3):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return f"{v:.{digits}f}" if isinstance(v, float) else str(v)


def badge(verdict):
    colour = VERDICT_COLOURS.get(verdict, "#666")
    return f'<span class="verdict" style="background:{colour}">{esc(verdict)}</span>'


def img(uri, alt):
    return f'<img src="{uri}" alt="{esc(alt)}">'


def table(header, rows, numeric=()):
    out = ["<table><tr>" + "".join(f"<th>{esc(h)}</th>" for h in header) + "</tr>"]
    for r in rows:
        cells = []
        for i, v in enumerate(r):
            cls = ' class="num"' if i in numeric else ""
            cells.append(f"<td{cls}>{v}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    return "\n".join(out) + "</table>"


def summary_section(d):
    r, m = d["report"], d["map"]
    diag = r["diagnostics"]
    items = [
        ("cameras", len(m.get("cameras") or [])), ("markers", len(m.get("markers") or [])),
        ("frames used", f"{r.get('frames_used')} of {r.get('frames_assembled')} assembled"),
        ("observations used", f"{r.get('observations_used')} of {r.get('observations_total')}"),
        ("rms", f"{fmt(r.get('initial_rms_px'))} px after initialisation -> {fmt(r.get('final_rms_px'))} px "
                f"after bundle adjustment"),
        ("residual sigma", f"{fmt(diag.get('residual_sigma_px'))} px per coordinate"),
        ("solver", f"{r.get('iterations')} iterations in {r.get('solves')} solves ({esc(r.get('termination'))}), "
                   f"{fmt(r.get('seconds', {}).get('total'), 2)} s"),
        ("references", f"camera {esc(m.get('reference_camera'))} (rig frame), marker "
                       f"{esc(m.get('reference_marker'))} (object frame)"),
    ]
    rows = [(esc(k), esc(v) if not isinstance(v, str) else v) for k, v in items]
    return "<h2>Summary</h2>" + table(["", ""], rows)


def verdict_table(cams, diag):
    rows = []
    for c in cams:
        share = c["rejected"] / c["observations"] if c["observations"] else 0.0
        sp = c.get("sigma_position_mm")
        sr = c.get("sigma_rotation_deg")
        rows.append((esc(c["name"]) + (" (reference)" if c.get("reference") else ""), badge(c["verdict"]),
                     fmt(c["rms_px"]), fmt(c["predicted_rms_px"]), c["observations"], c["inliers"],
                     fmt(100 * share, 1), fmt(100 * c["coverage"], 0), fmt(c["median_side_px"], 1),
                     fmt(float(np.linalg.norm(sp)), 2) if sp else "-", fmt(float(np.linalg.norm(sr)), 3) if sr else "-",
                     esc(c["reason"])))
    head = ["camera", "verdict", "rms (px)", "predicted (px)", "observations", "inliers", "rejected (%)",
            "coverage (%)", "marker side (px)", "pose 1-sigma (mm)", "(deg)", "why"]
    u = diag.get("rules", {})
    cells = u.get("coverage_cells", 8)
    note = (f'<p class="note">Predicted rms = sqrt(2 &middot; {diag["corner_noise_px"]}&sup2; + '
            f'({diag["print_tolerance"]} &middot; marker side / 2)&sup2;): corner noise of '
            f'{diag["corner_noise_px"]} px per coordinate plus a {100 * diag["print_tolerance"]:.1f}% error of the '
            f'printed size. good: rms within {u.get("fair_rms_ratio")}x of it, at most '
            f'{100 * u.get("fair_rejected", 0):.0f}% rejected, markers seen in at least '
            f'{100 * u.get("fair_coverage", 0):.0f}% of the image ({cells}x{cells} cells), at least '
            f'{u.get("fair_observations")} observations; poor: beyond {u.get("poor_rms_ratio")}x, '
            f'{100 * u.get("poor_rejected", 0):.0f}%, {100 * u.get("poor_coverage", 0):.0f}%, '
            f'{u.get("poor_observations")}.</p>')
    return "<h2>Cameras</h2>" + table(head, rows, numeric=range(2, 11)) + note


def camera_sections(d):
    sizes = camera_sizes(d["map"])
    out = ["<h2>Per camera: residuals and coverage</h2>",
           '<p class="note">Residual = projected - observed corner, at the final estimates. The coverage map '
           'shows where in the image markers were seen: wave the object through the grey parts next time.</p>']
    for c in d["report"]["diagnostics"]["cameras"]:
        name = c["name"]
        if name not in sizes:
            continue
        figs = [histogram_figure(d["res"], name), vectors_figure(d["res"], name, sizes[name]),
                coverage_figure(d["res"], name, sizes[name])]
        out.append(f'<div class="camera"><h3>{esc(name)} {badge(c["verdict"])}</h3>'
                   f'<p>{esc(c["reason"])}</p><div class="figs">'
                   + "".join(img(u, f"{name} figure") for u in figs) + "</div></div>")
    return "\n".join(out)


def marker_section(d):
    m = d["map"]
    rows = [(k["id"], fmt(k["size"], 4), k.get("observations"), fmt(k.get("rms_px")), fmt(k.get("max_px")))
            for k in m.get("markers") or []]
    return ("<h2>Markers</h2><div class='figs'>" + img(markers_figure(m), "rms per marker") + "</div>"
            + table(["id", "size (m)", "observations", "rms (px)", "max (px)"], rows, numeric=range(0, 5)))


def uncertainty_section(d):
    cams = d["report"]["diagnostics"]["cameras"]
    rows = []
    for c in cams:
        if "sigma_position_mm" in c:
            rows.append((esc(c["name"]), *[fmt(v, 3) for v in c["sigma_position_mm"]],
                         *[fmt(v, 4) for v in c["sigma_rotation_deg"]], ""))
        else:
            rows.append((esc(c["name"]), "-", "-", "-", "-", "-", "-", esc(c.get("covariance_note", ""))))
    head = ["camera", "x (mm)", "y (mm)", "z (mm)", "rx (deg)", "ry (deg)", "rz (deg)", "note"]
    return ("<h2>Camera pose uncertainty</h2><div class='figs'>" + img(uncertainty_figure(cams), "uncertainty")
            + "</div>" + table(head, rows, numeric=range(1, 7))
            + '<p class="note">1-sigma of each camera pose from the bundle adjustment\'s covariance at the '
              'solution (inlier observations, residual variance as measured); position of the camera centre '
              'in the rig frame, rotation about the camera\'s axes.</p>')


def rejection_section(d):
    r, res = d["report"], d["res"]
    out = ["<h2>What was rejected, and why</h2>"]
    if r.get("rejected_markers"):
        out.append(table(["marker", "observations", "reason"],
                         [(m["id"], m["observations"], esc(m["reason"])) for m in r["rejected_markers"]]))
    else:
        out.append("<p>No marker was rejected.</p>")
    rejected = ~res["inlier"]
    groups = {}
    err = np.hypot(res["dx"], res["dy"])
    for cam, reason, e in zip(res["camera"][rejected], res["reason"][rejected], err[rejected]):
        kind = re.sub(r"\(rms [^ ]+ px > ", "(rms > ", reason)  # one row per kind, not per value
        groups.setdefault((cam, kind), []).append(e)
    rows = []
    for (cam, kind), errors in sorted(groups.items()):
        e = np.array(errors)
        e = e[np.isfinite(e)]
        rows.append((esc(cam), len(errors) // 4, esc(kind), fmt(float(np.median(e)), 2) if len(e) else "-"))
    out.append(table(["camera", "observations", "reason", "median corner residual (px)"], rows, numeric=(1, 3))
               if rows else "<p>No observation was rejected.</p>")
    for key, text in (("duplicates", "detections dropped: the same id twice in one image"),
                      ("ignored_ids", "detections of ids outside markers.ids"),
                      ("weak_frames", "frames seen by one camera only (pose decided by continuity)")):
        if r.get(key):
            out.append(f"<p>{esc(r[key])} {esc(text)}.</p>")
    for w in r.get("warnings") or []:
        out.append(f'<p class="note">warning: {esc(w)}</p>')
    return "\n".join(out)


def page(d, outdir, viz):
    rig_uri, rig_note = rig_picture(outdir, viz)
    rig = img(rig_uri, "the mapped rig") if rig_uri else f'<p class="note">{esc(rig_note)}</p>'
    diag = d["report"]["diagnostics"]
    parts = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
        f"<title>mcmt calibration report: {esc(os.path.abspath(outdir))}</title><style>{CSS}</style></head><body>",
        f"<h1>mcmt calibration report</h1><p class='note'>{esc(os.path.abspath(outdir))}</p>",
        summary_section(d), verdict_table(diag["cameras"], diag),
        "<h2>The rig</h2><div class='figs'>" + rig + img(layout_figure(d["map"]), "marker layout") + "</div>",
        camera_sections(d), marker_section(d),
        "<h2>Trajectory</h2><div class='figs'>" + img(trajectory_figure(d["trajectory"]), "trajectory") + "</div>",
        uncertainty_section(d), rejection_section(d), "</body></html>\n",
    ]
    return "\n".join(parts)


def find_viz():
    here = os.path.join(os.path.dirname(os.path.realpath(__file__)), "mcmt-viz")
    return here if os.access(here, os.X_OK) else shutil.which("mcmt-viz")


def main(argv):
    ap = argparse.ArgumentParser(prog=PROGRAM, description="Writes OUTDIR/report.html: a self-contained "
                                 "calibration report (verdicts, residuals, coverage, uncertainty) of a mapper "
                                 "output folder.")
    ap.add_argument("--version", action="version", version=PROGRAM + " " + VERSION)
    ap.add_argument("outdir", help="the folder mcmt-mapper --out wrote")
    ap.add_argument("--viz", help="mcmt-viz to draw the rig picture with (default: beside mcmt-report, or PATH)")
    ap.add_argument("--no-rig-picture", action="store_true", help="do not run mcmt-viz")
    args = ap.parse_args(argv)
    try:
        d = load(args.outdir)
        viz = None if args.no_rig_picture else (args.viz or find_viz())
        text = page(d, args.outdir, viz)
        out = os.path.join(args.outdir, "report.html")
        tmp = f"{out}.tmp.{os.getpid()}"
        with open(tmp, "w") as f:
            f.write(text)
        os.replace(tmp, out)
    except ReportError as e:
        print(f"{PROGRAM}: error: {e}", file=sys.stderr)
        return 1
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
