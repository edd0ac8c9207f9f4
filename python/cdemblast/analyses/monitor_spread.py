"""SPEC 5.1's monitor comparison made robust to where a monitor happens to sit (issue 13).

SPEC 5.1 compares the bar and the solid explosive model by the peak von Mises stress at three
points. By the time the stress wave reaches the middle point the rock there has cracked, and a
point's peak is the stress its one block still carries: it depends on the crack pattern next
to it. The model is symmetric about the hole's axis, so the point's mirror image on the other
side of the hole sees the same loading; the difference between the two, in one run, measures
that dependence.

This analysis puts monitors on both sides of the hole at each of the case's monitor distances
and at several depths, runs both cases, and reports per point the two peaks and their ratio,
per distance the spread of the ratio and the ratio of the mean peaks, and per point the
left/right ratio of each model (the scatter of a point value within one run).

Used by examples/single_hole_2d/monitor_spread (a thin command).
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess

from ..plots import plt
from ..run import Run

CASES = ("bar", "solid")


def with_monitors(case_text, points):
    """The case's TOML text with [[monitor]] tables appended for `points` ({name: (x, y)})."""
    lines = [case_text.rstrip("\n"), "", "# added by monitor_spread"]
    for name, (x, y) in points.items():
        lines += ["[[monitor]]", f'name = "{name}"', f"point = [{x:.6g}, {y:.6g}]"]
    return "\n".join(lines) + "\n"


def spread_points(axis_x, distances, depths):
    """{name: (x, y)}: for each distance d (name, metres) the points axis_x -/+ d at each depth
    y; names '<distance name>_<L|R>_<y in mm>'."""
    pts = {}
    for dname, d in distances.items():
        for side, sgn in (("L", -1.0), ("R", 1.0)):
            for y in depths:
                pts[f"{dname}_{side}_{round(1000 * y)}"] = (axis_x + sgn * d, y)
    return pts


def run_cases(binary, cases, points, out, threads=None, sets=(), log=print):
    """Writes each case with the points added into out/<name>/case.toml and runs it there."""
    dirs = {}
    for name, path in cases.items():
        d = os.path.join(out, name)
        os.makedirs(d, exist_ok=True)
        with open(path) as f:
            text = with_monitors(f.read(), points)
        case = os.path.join(d, "case.toml")
        with open(case, "w") as f:
            f.write(text)
        cmd = [binary, "run", case, "--out", os.path.join(d, "run"), "--overwrite", "-q"]
        if threads is not None:
            cmd += ["--threads", str(threads)]
        for s in sets:
            cmd += ["--set", s]
        log(f"monitor_spread: running {name} ...")
        rc = subprocess.run(cmd).returncode
        if rc != 0:
            raise RuntimeError(f"the {name} run failed (exit code {rc}): {' '.join(cmd)}")
        dirs[name] = os.path.join(d, "run")
    return dirs


def peaks(run_dir):
    """{monitor: (peak von Mises in Pa, time of the peak in s)}: the run's own peaks, as
    summary.json holds them (the same figures bar_vs_solid compares)."""
    return {name: (float(m["peak_von_mises"]), float(m["time"]))
            for name, m in Run(run_dir).summary.get("monitors", {}).items()
            if m.get("peak_von_mises") is not None}


def analyse(run_dirs, points, distances):
    """The comparison as a dict (see the module's doc)."""
    pk = {c: peaks(run_dirs[c]) for c in CASES}
    rows = []
    for name, (x, y) in points.items():
        dname, side, _ = name.rsplit("_", 2)
        b, s = pk["bar"].get(name), pk["solid"].get(name)
        if b is None or s is None or not s[0] > 0:
            continue
        rows.append({"point": name, "distance": dname, "side": side, "x": x, "y": y,
                     "peak_bar_MPa": b[0] / 1e6, "peak_solid_MPa": s[0] / 1e6,
                     "ratio": b[0] / s[0], "t_bar_ms": b[1] * 1e3, "t_solid_ms": s[1] * 1e3})
    by_dist = {}
    for dname, d in distances.items():
        rs = [r for r in rows if r["distance"] == dname]
        if not rs:
            continue
        ratios = [r["ratio"] for r in rs]
        bars = [r["peak_bar_MPa"] for r in rs]
        solids = [r["peak_solid_MPa"] for r in rs]
        # the same point's mirror in the same run (left / right), per model
        mirror = {c: [] for c in CASES}
        for r in rs:
            if r["side"] != "L":
                continue
            twin = next((q for q in rs if q["side"] == "R" and abs(q["y"] - r["y"]) < 1e-9), None)
            if twin:
                mirror["bar"].append(r["peak_bar_MPa"] / twin["peak_bar_MPa"])
                mirror["solid"].append(r["peak_solid_MPa"] / twin["peak_solid_MPa"])
        by_dist[dname] = {
            "distance_m": d,
            "points": len(rs),
            "ratio_median": statistics.median(ratios),
            "ratio_min": min(ratios),
            "ratio_max": max(ratios),
            "points_within_20pct": sum(1 for q in ratios if abs(q - 1) <= 0.2),
            "mean_peak_bar_MPa": statistics.mean(bars),
            "mean_peak_solid_MPa": statistics.mean(solids),
            "ratio_of_means": statistics.mean(bars) / statistics.mean(solids),
            "peak_bar_range_MPa": [min(bars), max(bars)],
            "peak_solid_range_MPa": [min(solids), max(solids)],
            "left_over_right_bar": [min(mirror["bar"], default=None), max(mirror["bar"], default=None)],
            "left_over_right_solid": [min(mirror["solid"], default=None),
                                      max(mirror["solid"], default=None)],
        }
    return {"points": rows, "by_distance": by_dist}


def table(result):
    """The per-distance summary as printable text."""
    out = ["distance  points  bar/solid median (min-max)  within 20 %  mean bar / mean solid  "
           "left/right bar  left/right solid"]
    for dname, d in result["by_distance"].items():
        lb, ls = d["left_over_right_bar"], d["left_over_right_solid"]
        fmt = lambda p: "n/a" if p[0] is None else f"{p[0]:.2f}-{p[1]:.2f}"  # noqa: E731
        out.append(f"{dname:8s} {d['distance_m']:5.2f} m {d['points']:3d}    "
                   f"{d['ratio_median']:.2f} ({d['ratio_min']:.2f}-{d['ratio_max']:.2f})"
                   f"            {d['points_within_20pct']:2d}/{d['points']:<2d}          "
                   f"{d['ratio_of_means']:.2f}                {fmt(lb)}       {fmt(ls)}")
    return "\n".join(out)


def plot(result, path, shipped=()):
    """Peak bar against peak solid per point (one colour per distance), the 1:1 line and the
    20 % band; the case's own monitors (`shipped`, point names) circled."""
    fig, ax = plt.subplots(figsize=(6.4, 6.0))
    hi = 0.0
    for dname in result["by_distance"]:
        rs = [r for r in result["points"] if r["distance"] == dname]
        xs = [r["peak_solid_MPa"] for r in rs]
        ys = [r["peak_bar_MPa"] for r in rs]
        hi = max([hi] + xs + ys)
        ax.scatter(xs, ys, s=28, label=f"{dname} ({result['by_distance'][dname]['distance_m']:g} m)")
        for r in rs:
            if r["point"] in shipped:
                ax.scatter([r["peak_solid_MPa"]], [r["peak_bar_MPa"]], s=160, facecolors="none",
                           edgecolors="black", linewidths=1.2)
    top = 1.1 * hi
    ax.plot([0, top], [0, top], color="black", lw=1, label="bar = solid")
    ax.fill_between([0, top], [0, 0.8 * top], [0, 1.2 * top], color="0.85", zorder=0,
                    label="within 20 %")
    ax.set_xlim(0, top)
    ax.set_ylim(0, top)
    ax.set_xlabel("peak von Mises, solid model (MPa)")
    ax.set_ylabel("peak von Mises, bar model (MPa)")
    ax.set_title("SPEC 5.1: peak von Mises at points on both sides of the hole\n"
                 "(circled: the case's own monitors)", fontsize=10)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_json(result, path):
    with open(path, "w") as f:
        json.dump(result, f, indent=1)
