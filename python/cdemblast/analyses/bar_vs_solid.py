"""SPEC 5.1 (examples/single_hole_2d): the bar against the solid explosive model on the same 2D
mesh. A study analysis (docs/study.md, docs/single_hole_2d.md): the study's variants `bar`
and `solid`; writes into the study directory

  * comparison.json: per monitor the peak von Mises stress of each case, their difference
    (bar - solid) / solid * 100 and the time of each peak; the fracture degree at the end of
    the runs (the last row of fracture.csv); the fracture degree and the damaged area at each
    output time; wall time, blocks, steps, explosive work and energy error of each run; and
    max_peak_difference_pct (the largest absolute peak difference over the monitors);
  * comparison.png: the von Mises history of each monitor, bar and solid overlaid;
  * damage_side_by_side.png: damage maps of both cases at each output time (rows) around the
    hole, and damage_side_by_side_full.png: the same over the whole model;

and prints the comparison table.
"""

from __future__ import annotations

import json
import math
import os

import numpy as np
import matplotlib
from matplotlib import patheffects
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from ..plots import plt
from ..vtu import read_vtu
from ..yardsticks import distance_to_segment

CASES = ("bar", "solid")
COLORS = {"bar": "tab:blue", "solid": "tab:red"}
STYLES = {"bar": "-", "solid": "--"}
ZOOM = ((1.0, 3.0), (0.8, 2.0))  # x and y range of the zoomed damage maps (m)
DAMAGED = 0.5  # a block counts as "damaged" in the damaged-area measure from this damage on
DAMAGE_DPI = 100  # the damage grids are large pictures: keep the files small
BAR_EFFECT = [patheffects.withStroke(linewidth=3.4, foreground="black")]
RC = {"font.size": 10, "axes.titlesize": 10.5, "axes.labelsize": 10, "legend.fontsize": 9,
      "xtick.labelsize": 9, "ytick.labelsize": 9, "figure.titlesize": 12,
      "axes.grid": True, "grid.alpha": 0.3, "savefig.dpi": 130}


class Case:
    """One run of the pair, as the comparison reads it."""

    def __init__(self, run):
        self.run = run
        self.dir = run.dir
        self.summary = run.summary
        self.case = run.case
        self.fracture = run.fracture
        self.fields = run.fields
        self.monitors = {n: (m["time"], m["von_mises"]) for n, m in run.monitors.items()}
        if self.fracture is None or not self.monitors:
            raise RuntimeError(f"{run.dir}: fracture.csv or monitors.csv is missing")

    def fracture_at(self, t):
        """The fracture.csv row nearest to time t (dict)."""
        i = int(np.argmin(np.abs(self.fracture["time"] - t)))
        return {k: float(v[i]) for k, v in self.fracture.items() if isinstance(v, np.ndarray)}

    def fracture_end(self):
        return {k: float(v[-1]) for k, v in self.fracture.items() if isinstance(v, np.ndarray)}


def monitor_points(run):
    return {m["name"]: m["point"] for m in run.case.get("monitor", [])}


def hole_axes(run):
    """[(start, end, radius)] of the case's holes (empty when the case is unreadable)."""
    out = []
    for h in run.case.get("hole", []):
        if "collar" in h and "end" in h:
            out.append((np.array(h["collar"], float)[:2], np.array(h["end"], float)[:2],
                        0.5 * float(h.get("diameter", 0.0))))
    return out


def pct(a, b):
    return (a - b) / b * 100.0 if b else float("nan")


def nearest_frame(fields, t):
    """(time, path) of the field output nearest to t, or None when none is within 2 %."""
    best = min(fields, key=lambda f: abs(f[0] - t), default=None)
    if best is None or abs(best[0] - t) > 0.02 * t + 1e-9:
        return None
    return best


class Frame:
    """One field output, in the reference configuration (points - displacement)."""

    def __init__(self, path):
        g = read_vtu(path)
        pts = np.asarray(g.points, float)
        u = g.point_array("displacement")
        self.ref = (pts - u if u is not None else pts)[:, :2]
        self.cur = pts[:, :2]
        off = np.asarray(g.offsets)
        conn = np.asarray(g.connectivity)
        start = np.concatenate([[0], off[:-1]])
        self.cells = [conn[s:e] for s, e in zip(start, off)]
        self.damage = np.asarray(g.cell_array("damage"), float)
        reg = g.cell_array("region")
        self.region = np.zeros(len(self.cells), int) if reg is None else np.asarray(reg, int)
        self.polys = [self.ref[c] for c in self.cells]
        self.area = np.array([0.5 * abs(np.dot(p[:, 0], np.roll(p[:, 1], -1))
                                        - np.dot(np.roll(p[:, 0], -1), p[:, 1]))
                              for p in self.polys])  # shoelace; triangles and quads mixed

    def hole_cells(self):
        """Cells of the hole region(s): every region but the most common one."""
        vals, counts = np.unique(self.region, return_counts=True)
        if len(vals) < 2:
            return np.zeros(len(self.cells), bool)
        return self.region != vals[np.argmax(counts)]


def hole_outline(frame):
    """Boundary edges of the hole region in the reference configuration (list of segments)."""
    mask = frame.hole_cells()
    count, seg = {}, {}
    for i in np.nonzero(mask)[0]:
        p = frame.polys[i]
        for k in range(len(p)):
            a, b = p[k], p[(k + 1) % len(p)]
            key = tuple(sorted((tuple(np.round(a, 7)), tuple(np.round(b, 7)))))
            count[key] = count.get(key, 0) + 1
            seg[key] = (a, b)
    return [seg[k] for k, c in count.items() if c == 1]


def damage_measures(frame):
    """Damage-weighted and damaged (>= DAMAGED) rock area, whole model and zoom window.

    The hole region is left out in both cases (explosive blocks in the solid case, the charge
    region meshed as rock in the bar case), so that both measure the same rock."""
    rock = ~frame.hole_cells()
    c = np.array([p.mean(0) for p in frame.polys])
    inzoom = ((c[:, 0] >= ZOOM[0][0]) & (c[:, 0] <= ZOOM[0][1]) &
              (c[:, 1] >= ZOOM[1][0]) & (c[:, 1] <= ZOOM[1][1]))
    a, d = frame.area, frame.damage
    out = {}
    for tag, sel in (("model", rock), ("zoom", rock & inzoom)):
        out[f"damage_weighted_area_{tag}_m2"] = float(np.sum(a[sel] * d[sel]))
        out[f"damaged_area_{tag}_m2"] = float(np.sum(a[sel & (d >= DAMAGED)]))
        out[f"rock_area_{tag}_m2"] = float(np.sum(a[sel]))
    return out


def compare(runs, out, sets, threads):
    bar, solid = runs["bar"], runs["solid"]
    pts = monitor_points(bar)
    axes = hole_axes(bar)
    res = {"out_dir": os.path.abspath(out), "threads": threads, "set": sets, "monitors": {}}
    for name in bar.summary.get("monitors", {}):
        if name not in solid.summary.get("monitors", {}):
            continue
        b, s = bar.summary["monitors"][name], solid.summary["monitors"][name]
        m = {
            "point": pts.get(name),
            "distance_from_hole_axis_m": (distance_to_segment(pts[name], *axes[0][:2])
                                          if name in pts and axes else None),
            "peak_von_mises_bar_pa": b["peak_von_mises"],
            "peak_von_mises_solid_pa": s["peak_von_mises"],
            "difference_pct": pct(b["peak_von_mises"], s["peak_von_mises"]),
            "ratio_bar_to_solid": b["peak_von_mises"] / s["peak_von_mises"]
            if s["peak_von_mises"] else None,
            "time_of_peak_bar_s": b["time"],
            "time_of_peak_solid_s": s["time"],
        }
        res["monitors"][name] = m
    diffs = [abs(m["difference_pct"]) for m in res["monitors"].values()
             if math.isfinite(m["difference_pct"])]
    res["max_peak_difference_pct"] = max(diffs) if diffs else None

    res["fracture_degree_end"] = {}
    for name, r in runs.items():
        f = r.fracture_end()
        res["fracture_degree_end"][name] = {
            "time_s": f["time"], "degree": f["degree_area"], "tensile": f["tensile_area"],
            "shear": f["shear_area"], "degree_count": f.get("degree_count"),
            "broken_spring_points": f.get("broken"), "spring_points": f.get("total")}
    keys = ("wall_time_s", "blocks", "steps", "dt", "explosive_work", "products_kinetic_energy",
            "explosive_work_to_rock", "energy_error",
            "bar_segments", "explosive_blocks", "collapsed_explosive_blocks", "status")
    res["runs"] = {name: {"run_dir": os.path.abspath(r.dir),
                          **{k: r.summary.get(k) for k in keys if k in r.summary}}
                   for name, r in runs.items()}
    # The explosive work against the energy the charge gave the rock (the work less the products'
    # own kinetic energy: a solid charge's explosive blocks jet out of an open collar, which a
    # bar's products, massless in the dynamics, cannot; docs/single_hole_2d.md section 3).
    for k in ("explosive_work", "explosive_work_to_rock"):
        wb, ws = (res["runs"][n].get(k) for n in CASES)
        res[f"{k}_difference_pct"] = ((wb - ws) / ws * 100.0
                                      if wb is not None and ws else None)
    res["wall_time_s"] = {n: r.summary.get("wall_time_s") for n, r in runs.items()}
    res["blocks"] = {n: r.summary.get("blocks") for n, r in runs.items()}

    # Damage at the output times both runs wrote (t = 0 left out).
    times = sorted({round(t, 12) for t, _ in bar.fields if t > 0})
    frames = []
    res["damage_at_output_times"] = []
    for t in times:
        fb, fs = nearest_frame(bar.fields, t), nearest_frame(solid.fields, t)
        if fb is None or fs is None:
            continue
        fr = {"bar": Frame(fb[1]), "solid": Frame(fs[1])}
        frames.append((t, fr))
        row = {"time_s": t}
        for name, r in runs.items():
            fd = r.fracture_at(t)
            row[name] = {"field_time_s": (fb if name == "bar" else fs)[0],
                         "fracture_degree": fd["degree_area"],
                         "fracture_degree_tensile": fd["tensile_area"],
                         "fracture_degree_shear": fd["shear_area"],
                         **damage_measures(fr[name])}
        res["damage_at_output_times"].append(row)
    return res, frames


def fmt_ms(t):
    return f"{t * 1e3:.3f}"


# The summary's energies (J), printed in MJ/m.
ENERGY_KEYS = ("explosive_work", "products_kinetic_energy", "explosive_work_to_rock")


def table_text(res):
    lines = []
    print = lines.append  # noqa: A001 - the table is built line by line
    print("")
    print(f"SPEC 5.1 single hole: bar against solid ({res['out_dir']})")
    hdr = (f"{'monitor':<8} {'point (m)':<13} {'r (m)':>6} {'peak bar':>10} {'peak solid':>11} "
           f"{'diff %':>7} {'bar/solid':>9} {'t bar':>8} {'t solid':>8}")
    print(hdr)
    print(f"{'':<8} {'':<13} {'':>6} {'(MPa)':>10} {'(MPa)':>11} {'':>7} {'':>9} "
          f"{'(ms)':>8} {'(ms)':>8}")
    for n, m in res["monitors"].items():
        p = m["point"]
        ps = f"({p[0]:g}, {p[1]:g})" if p else "?"
        r = m["distance_from_hole_axis_m"]
        print(f"{n:<8} {ps:<13} {(f'{r:.3f}' if r is not None else '?'):>6} "
              f"{m['peak_von_mises_bar_pa'] / 1e6:>10.1f} "
              f"{m['peak_von_mises_solid_pa'] / 1e6:>11.1f} {m['difference_pct']:>7.1f} "
              f"{m['ratio_bar_to_solid']:>9.2f} {fmt_ms(m['time_of_peak_bar_s']):>8} "
              f"{fmt_ms(m['time_of_peak_solid_s']):>8}")
    mp = res["max_peak_difference_pct"]
    print(f"max |peak difference|: {mp:.1f} %" if mp is not None else "no common monitors")
    print("")
    print(f"{'':<26} {'bar':>12} {'solid':>12}")
    fe = res["fracture_degree_end"]
    te = fe["bar"]["time_s"]
    for k, label in (("degree", "fracture degree"), ("tensile", "  tensile part"),
                     ("shear", "  shear part")):
        print(f"{label + f' at {te * 1e3:.2f} ms':<26} {fe['bar'][k]:>12.4f} "
              f"{fe['solid'][k]:>12.4f}")
    rr = res["runs"]
    for k, label, f in (("wall_time_s", "wall time (s)", "{:.1f}"),
                        ("blocks", "blocks", "{:d}"), ("steps", "steps", "{:d}"),
                        ("explosive_work", "explosive work (MJ/m)", "{:.2f}"),
                        ("products_kinetic_energy", "  products' kinetic (MJ/m)", "{:.2f}"),
                        ("explosive_work_to_rock", "  given to the rock (MJ/m)", "{:.2f}"),
                        ("energy_error", "energy error", "{:.2e}")):
        vals = []
        for n in CASES:
            v = rr[n].get(k)
            if v is None:
                vals.append("-")
            elif k in ENERGY_KEYS:
                vals.append(f.format(v / 1e6))
            else:
                vals.append(f.format(int(v)) if f == "{:d}" else f.format(v))
        print(f"{label:<26} {vals[0]:>12} {vals[1]:>12}")
    for k, label in (("explosive_work", "explosive work"),
                     ("explosive_work_to_rock", "energy given to the rock")):
        d = res.get(f"{k}_difference_pct")
        if d is not None:
            print(f"bar - solid, {label}: {d:+.1f} %")
    if res["damage_at_output_times"]:
        print("")
        print("damage at the output times: fracture degree (whole model) and damaged rock "
              f"area (damage >= {DAMAGED}, hole region left out) in x {ZOOM[0]}, y {ZOOM[1]}")
        print(f"{'t (ms)':>7} {'FD bar':>8} {'FD solid':>9} {'area bar':>10} {'area solid':>11}")
        for row in res["damage_at_output_times"]:
            b, s = row["bar"], row["solid"]
            print(f"{fmt_ms(row['time_s']):>7} {b['fracture_degree']:>8.3f} "
                  f"{s['fracture_degree']:>9.3f} {b['damaged_area_zoom_m2']:>8.3f}m2 "
                  f"{s['damaged_area_zoom_m2']:>9.3f}m2")
    print("")
    return "\n".join(lines)


def plot_histories(runs, res, path):
    names = list(res["monitors"])
    if not names:
        return
    tend = max(float(r.fracture["time"][-1]) for r in runs.values())
    fig, axs = plt.subplots(len(names), 2, figsize=(12, 2.9 * len(names) + 0.6),
                            gridspec_kw={"width_ratios": [1.55, 1]}, squeeze=False)
    tz = min(tend, 1.0e-3)  # the right column: the first millisecond, where the peaks are
    for i, n in enumerate(names):
        m = res["monitors"][n]
        for j, (ax, tmax) in enumerate(zip(axs[i], (tend, tz))):
            for c in CASES:
                t, vm = runs[c].monitors[n]
                ax.plot(t * 1e3, vm / 1e6, STYLES[c], color=COLORS[c], lw=1.3,
                        label=f"{c} model")
                tp, vp = m[f"time_of_peak_{c}_s"], m[f"peak_von_mises_{c}_pa"]
                ax.plot(tp * 1e3, vp / 1e6, "o", color=COLORS[c], ms=5, mfc="white", mew=1.5)
            ax.set_xlim(0, tmax * 1e3)
            ax.set_ylim(bottom=0)
            ax.set_ylabel("von Mises (MPa)")
            if i == len(names) - 1:
                ax.set_xlabel("time (ms)")
            p = m["point"]
            where = f" at ({p[0]:g}, {p[1]:g}) m" if p else ""
            r = m["distance_from_hole_axis_m"]
            dist = f", {r:.2f} m from the hole axis" if r is not None else ""
            if j == 0:
                ax.set_title(f"monitor '{n}'{where}{dist}", loc="left")
                ax.text(0.99, 0.95,
                        f"peak bar {m['peak_von_mises_bar_pa'] / 1e6:.0f} MPa at "
                        f"{m['time_of_peak_bar_s'] * 1e3:.3f} ms\n"
                        f"peak solid {m['peak_von_mises_solid_pa'] / 1e6:.0f} MPa at "
                        f"{m['time_of_peak_solid_s'] * 1e3:.3f} ms\n"
                        f"bar - solid: {m['difference_pct']:+.1f} %",
                        transform=ax.transAxes, ha="right", va="top", fontsize=8.5,
                        bbox=dict(boxstyle="round", fc="white", ec="0.7", alpha=0.9))
            else:
                ax.set_title(f"first {tz * 1e3:g} ms", loc="left")
            if i == 0 and j == 0:
                ax.legend(loc="center right")
    fig.suptitle("SPEC 5.1 single hole: von Mises stress at the monitors, bar vs solid "
                 "explosive model (circles: peaks)")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def draw_damage(ax, frame, solid_case, outline, axes, cmap, norm, lw):
    hole = frame.hole_cells()
    rock = ~hole if solid_case else np.ones(len(frame.cells), bool)
    idx = np.nonzero(rock)[0]
    pc = PolyCollection([frame.polys[i] for i in idx], array=frame.damage[idx], cmap=cmap,
                        norm=norm, edgecolors="0.55", linewidths=lw)
    ax.add_collection(pc)
    if solid_case and hole.any():
        ax.add_collection(PolyCollection([frame.polys[i] for i in np.nonzero(hole)[0]],
                                         facecolors="0.75", edgecolors="0.55", linewidths=lw,
                                         hatch="////"))
    if outline:
        ax.add_collection(LineCollection(outline, colors="tab:blue", linewidths=1.4))
    if not solid_case:
        for a, b, _ in axes:
            ax.plot([a[0], b[0]], [a[1], b[1]], color="white", lw=1.6, solid_capstyle="butt",
                    path_effects=BAR_EFFECT)
    return pc


def save_small(fig, path):
    """Saves a large picture as a 256-colour PNG (a third of the size; pillow comes with
    matplotlib), or as a plain PNG when pillow is missing."""
    try:
        import io
        from PIL import Image
    except ImportError:
        fig.savefig(path, dpi=DAMAGE_DPI)
        return
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DAMAGE_DPI)
    buf.seek(0)
    im = Image.open(buf).convert("RGB")
    none = getattr(Image, "Dither", Image).NONE  # Pillow < 9.1: Image.NONE
    im.quantize(colors=256, dither=none).save(path, optimize=True)


def plot_damage(runs, frames, path, window, title_extra):
    if not frames:
        return
    (x0, x1), (y0, y1) = window
    aspect = (y1 - y0) / (x1 - x0)
    pw = 5.3
    n = len(frames)
    fig, axs = plt.subplots(n, 2, figsize=(2 * pw + 1.3, n * pw * aspect + 1.3), squeeze=False,
                            sharex=True, sharey=True)
    cmap = plt.get_cmap("YlOrRd")
    norm = matplotlib.colors.Normalize(0.0, 1.0)
    axes = hole_axes(runs["bar"])
    outline = hole_outline(frames[0][1]["solid"])
    full = (x1 - x0) >= 3.9
    lw = 0.08 if full else 0.15
    pc = None
    for i, (t, fr) in enumerate(frames):
        for j, c in enumerate(CASES):
            ax = axs[i][j]
            pc = draw_damage(ax, fr[c], c == "solid", outline, axes, cmap, norm, lw)
            ax.set_xlim(x0, x1)
            ax.set_ylim(y0, y1)
            ax.set_aspect("equal")
            ax.grid(False)
            fd = runs[c].fracture_at(t)["degree_area"]
            ax.set_title(f"{c} model, t = {t * 1e3:.3g} ms (fracture degree {fd:.3f})",
                         fontsize=9.5)
            if j == 0:
                ax.set_ylabel("y (m)")
            if i == n - 1:
                ax.set_xlabel("x (m)")
    handles = [Line2D([], [], color="tab:blue", lw=1.4, label="hole (charge region)"),
               Line2D([], [], color="white", lw=1.6, path_effects=BAR_EFFECT,
                      label="bar (bar model)"),
               Patch(facecolor="0.75", edgecolor="0.55", hatch="////",
                     label="explosive blocks (solid model)")]
    h = fig.get_figheight()
    fig.suptitle("SPEC 5.1 single hole: block damage (broken fraction of the interface area), "
                 f"bar (left) vs solid (right){title_extra}\n"
                 "drawn on the undeformed mesh; fracture degree: broken / total spring-point "
                 "area of the whole model", y=1 - 0.08 / h, va="top")
    fig.legend(handles=handles, loc="upper center", ncol=3,
               bbox_to_anchor=(0.5, 1 - 0.55 / h), frameon=False)
    fig.tight_layout(rect=(0, 0, 0.92, 1 - 0.85 / h))
    with plt.rc_context({"axes.grid": False}):
        cax = fig.add_axes((0.93, 0.25, 0.015, 0.5))
        fig.colorbar(pc, cax=cax, label="damage")
    save_small(fig, path)
    plt.close(fig)




def analyse(study, variants, pictures=True, log=print):
    """The study analysis: needs the variants `bar` and `solid`."""
    for c in CASES:
        if c not in variants:
            raise RuntimeError(f"the bar_vs_solid analysis needs a variant named '{c}'")
    runs = {c: Case(variants[c].run) for c in CASES}
    out = study.out
    res, frames = compare(runs, out, getattr(study, "cli_sets", []), getattr(study, "cli_threads", None))
    text = table_text(res)
    log(text)
    files = ["comparison.json"]
    with open(os.path.join(out, "comparison.json"), "w") as f:
        json.dump(res, f, indent=2)
        f.write("\n")
    if pictures:
        with plt.rc_context(RC):
            plot_histories(runs, res, os.path.join(out, "comparison.png"))
            files.append("comparison.png")
            if frames:
                for name, window, extra in (
                        ("damage_side_by_side.png", ZOOM, ", around the hole"),
                        ("damage_side_by_side_full.png", ((0.0, 4.0), (0.0, 2.0)), ", whole model")):
                    plot_damage(runs, frames, os.path.join(out, name), window, extra)
                    files.append(name)
            else:
                log("compare: no field outputs common to both runs: no damage maps")
    for p in files:
        log(f"compare: wrote {os.path.join(out, p)}")
    return {"json_file": "comparison.json", "files": files, "result": res}
