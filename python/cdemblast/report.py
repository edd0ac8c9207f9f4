"""The run report: PNG pictures, a summary.md and an index.html of finished runs (one run, or
several overlaid and compared). `scripts/cdem_report.py` and `cdemblast report` run main().
docs/report.md describes the pages and every picture.
"""

from __future__ import annotations

import argparse
import html
import math
import os
import sys
import traceback

import numpy as np

from .plots import (MAX_FRAMES, choose_frames, compare_damage, last_frame, load_frames,
                    plot_3d_views, plot_damage_final, plot_energy, plot_field_grid,
                    plot_fracture, plot_fragments_final, plot_grading, plot_monitors, plt)
from .run import Run, unique_labels
from .vtu import VtuError

# ----------------------------------------------------------------------------- summary tables
KNOWN = [
    # key, label, unit, scale, format. Rows appear in this order: run state, blasting
    # quality, energy, model, performance; keys not listed follow (nested ones as "a: b").
    ("status", "status", "", None, None),
    ("diagnosis", "diagnosis", "", None, None),
    ("end_time", "simulated time", "ms", 1e3, "{:.4g}"),
    ("fracture_degree", "fracture degree (area)", "%", 100, "{:.2f}"),
    ("fracture_degree_tensile", "fracture degree, tensile", "%", 100, "{:.2f}"),
    ("fracture_degree_shear", "fracture degree, shear", "%", 100, "{:.2f}"),
    ("fracture_degree_count", "fracture degree (count)", "%", 100, "{:.2f}"),
    ("fragments", "fragments", "", None, None),
    ("d40_m", "d40 (40 % passing)", "m", 1, "{:.4g}"),
    ("d80_m", "d80 (80 % passing)", "m", 1, "{:.4g}"),
    ("d10_90", "d10, d20, ..., d90", "m", 1, "{:.3g}"),  # the nine d_x keys in one row
] + [
    ("main_fragment_volume", "main rock mass volume", "m³", 1, "{:.4g}"),
    ("funnel_depth_m", "funnel depth", "m", 1, "{:.4g}"),
    ("funnel_lx_m", "funnel extent l_x", "m", 1, "{:.4g}"),
    ("funnel_ly_m", "funnel extent l_y", "m", 1, "{:.4g}"),
    ("funnel_axial_ratio", "funnel axial ratio e = l_y / l_x", "", 1, "{:.3g}"),
    ("footage_m", "footage", "m", 1, "{:.4g}"),
    ("funnel_broken_volume", "funnel broken volume", "m³", 1, "{:.4g}"),
    ("energy_error", "energy balance error (relative)", "", 1, "{:.2e}"),
    ("kinetic_energy", "kinetic energy at the end", "J", 1, "{:.4g}"),
    ("explosive_work", "explosive work", "J", 1, "{:.4g}"),
    ("blocks", "blocks", "", None, None),
    ("nodes", "nodes", "", None, None),
    ("spring_points", "spring points", "", None, None),
    ("bar_segments", "bar segments", "", None, None),
    ("explosive_blocks", "explosive blocks", "", None, None),
    ("collapsed_explosive_blocks", "collapsed explosive blocks", "", None, None),
    ("steps", "time steps", "", None, None),
    ("dt", "time step", "µs", 1e6, "{:.4g}"),
    ("dt_limit", "time step limited by", "", None, None),
    ("dt_blocks", "block limit of the time step", "µs", 1e6, "{:.4g}"),
    ("dt_springs", "spring limit of the time step", "µs", 1e6, "{:.4g}"),
    ("field_outputs", "field outputs", "", None, None),
    ("threads", "threads", "", None, None),
    ("wall_time_s", "wall time", "s", 1, "{:.3g}"),
    ("loop_time_s", "time-loop wall time", "s", 1, "{:.3g}"),
    ("block_steps_per_s", "throughput", "block-steps/s", 1, "{:.3g}"),
    ("spring_steps_per_s", "spring throughput", "spring-steps/s", 1, "{:.3g}"),
]
UNIT_SUFFIX = [("_m3", "m³"), ("_m", "m"), ("_s", "s"), ("_j", "J"), ("_pa", "Pa"), ("_kg", "kg")]


def flatten(d, prefix=""):
    """Scalar entries of a summary (nested dicts as 'a.b'), monitors left out."""
    out = {}
    for k, v in d.items():
        key = prefix + k
        if k == "monitors" and not prefix:
            continue
        if isinstance(v, dict):
            out.update(flatten(v, key + "."))
        elif isinstance(v, (int, float, str, bool)) or v is None:
            out[key] = v
        elif isinstance(v, list) and len(v) <= 6 and all(isinstance(x, (int, float)) for x in v):
            out[key] = v
    return out


def describe(key):
    """(label, unit, scale, format) of a summary key."""
    for k, lab, unit, sc, f in KNOWN:
        if k == key:
            return lab, unit, sc, f
    lab, unit = key, ""
    for suf, u in UNIT_SUFFIX:
        if key.lower().endswith(suf):
            lab, unit = key[: -len(suf)], u
            break
    lab = lab.replace(".", ": ").replace("_", " ")
    return lab, unit, 1, "{:.4g}"


def format_value(v, sc, f):
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int) and (sc in (None, 1)) and (f in (None, "{:.4g}")):
        return f"{v:,}".replace(",", " ")
    if isinstance(v, (int, float)):
        if not math.isfinite(v):
            return "–"
        x = v * (sc or 1)
        return (f or "{:.4g}").format(x)
    if isinstance(v, list):
        return ", ".join(format_value(x, sc, f) if x is not None else "–" for x in v)
    return str(v)


def summary_rows(runs):
    """[(label, unit, [value per run])] in a fixed order: known keys first, then the rest."""
    flats = [flatten(r.summary) for r in runs]
    dkeys = [f"d{x}_m" for x in range(10, 100, 10)]
    for f in flats:  # d10..d90 make one row (d40 and d80 keep their own rows too)
        if sum(k in f for k in dkeys) >= 3:
            f["d10_90"] = [f.get(k) for k in dkeys]
            for k in dkeys:
                if k not in ("d40_m", "d80_m"):
                    f.pop(k, None)
    keys = [k for k, *_ in KNOWN if any(k in f for f in flats)]
    rest = []
    for f in flats:
        for k in f:
            if k not in keys and k not in rest and k != "title":
                rest.append(k)
    quality = [k for k in rest if k.startswith(("funnel", "grading", "fragment", "footage"))]
    rest = [k for k in rest if k not in quality]
    known = [k for k, *_ in KNOWN]
    last_quality = known.index("funnel_broken_volume")
    pos = sum(1 for k in keys if known.index(k) <= last_quality)
    keys = keys[:pos] + quality + keys[pos:]
    rows = []
    for k in keys + rest:
        lab, unit, sc, fm = describe(k)
        vals = [format_value(f.get(k), sc, fm) if k in f else "–" for f in flats]
        if k == "diagnosis" and all(v in ("", "–") for v in vals):
            continue
        rows.append((lab, unit, vals))
    return rows


def monitor_rows(runs):
    rows = []
    for r in runs:
        mons = r.summary.get("monitors")
        if isinstance(mons, dict):
            for n, m in mons.items():
                if isinstance(m, dict):
                    pv = m.get("peak_von_mises")
                    t = m.get("time")
                    rows.append((r.label, n, format_value(pv, 1e-6, "{:.3g}"),
                                 format_value(t, 1e3, "{:.4g}")))
        elif r.monitors:  # no summary: from the CSV
            for n, m in r.monitors.items():
                if "von_mises" in m and m["von_mises"].size:
                    i = int(np.nanargmax(m["von_mises"]))
                    rows.append((r.label, n, f"{m['von_mises'][i] * 1e-6:.3g}", f"{m['time'][i] * 1e3:.4g}"))
    return rows


CAPTIONS = {
    "monitors.png": "Monitor time histories: von Mises stress, the dominant velocity component and "
                    "the dominant displacement component at each monitor point.",
    "fracture.png": "Fracture degree against time: broken / total spring-point area, split into "
                    "tensile and shear parts (and the count-based ratio).",
    "energy.png": "Energy balance: the stored, input and dissipated energy terms, and the relative "
                  "balance error (log scale).",
    "grading.png": "Fragment size grading: cumulative volume percentage passing against the "
                   "characteristic size L_bc, with d40 and d80 marked.",
    "damage_maps.png": "Damage (broken fraction of each block's interface area) at several output "
                       "times; black lines are the cracks.",
    "von_mises_maps.png": "von Mises stress at the same output times (each picture has its own "
                          "colour scale, clipped at its 97th percentile, so that a few blocks loaded by a charge do not hide the rock).",
    "damage_final.png": "Damage at the last output time, with the cracks.",
    "fragments_final.png": "Fragments at the last output time: blocks connected through intact "
                           "spring points share a colour; the largest fragment is grey.",
    "top_view.png": "View of the free surface (the faces looking up, 'up' being the case's "
                    "analysis.up, +z by default): damage and displacement along up.",
    "section.png": "Section through the model centre containing the up direction, free surface "
                   "on top: damage with crack traces, and "
                   "displacement magnitude (colour scale clipped at its 98th percentile).",
    "damage_final_compare.png": "Damage at the last output time of each run, side by side.",
}


def md_table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join(" --- " for _ in header) + "|"]
    for r in rows:
        lines.append("| " + " | ".join(str(c).replace("|", "\\|") for c in r) + " |")
    return "\n".join(lines)


def html_table(header, rows):
    h = "".join(f"<th>{html.escape(str(c))}</th>" for c in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><thead><tr>{h}</tr></thead><tbody>{body}</tbody></table>"


def write_documents(runs, out_dir, pictures, notes):
    multi = len(runs) > 1
    title = ("Comparison: " + ", ".join(r.label for r in runs)) if multi else f"Run report: {runs[0].label}"
    rows = summary_rows(runs)
    if multi:
        header = ["quantity", "unit"] + [r.label for r in runs]
        table_rows = [[lab, unit] + vals for lab, unit, vals in rows]
    else:
        header = ["quantity", "value", "unit"]
        table_rows = [[lab, vals[0], unit] for lab, unit, vals in rows]
    mrows = monitor_rows(runs)
    mheader = (["run"] if multi else []) + ["monitor", "peak von Mises (MPa)", "at time (ms)"]
    mrows = [list(r) if multi else list(r[1:]) for r in mrows]
    run_lines = []
    for r in runs:
        rel = r.dir
        own = os.path.join(r.dir, "report", "index.html")
        link = os.path.relpath(own, out_dir) if multi and os.path.isfile(own) else None
        run_lines.append((r.label, rel, link))
    warn = [f"{r.label}: status '{r.summary.get('status')}'"
            + (f" ({r.summary.get('diagnosis')})" if r.summary.get("diagnosis") else "")
            for r in runs if r.summary.get("status") not in (None, "finished")]

    # ---- markdown ----
    md = [f"# {title}", ""]
    for lab, rel, _ in run_lines:
        md.append(f"- run `{lab}`: `{rel}`")
    md.append("")
    for w in warn:
        md.append(f"**Warning:** {w}")
    if warn:
        md.append("")
    md += ["## Key numbers", "", md_table(header, table_rows), ""]
    if mrows:
        md += ["## Monitors", "", md_table(mheader, mrows), ""]
    md += ["## Pictures", ""]
    for p in pictures:
        md += [f"### {p}", "", CAPTIONS.get(p, ""), "", f"![{p}]({p})", ""]
    if notes:
        md += ["## Notes", ""] + [f"- {n}" for n in notes] + [""]
    with open(os.path.join(out_dir, "summary.md"), "w") as f:
        f.write("\n".join(md))

    # ---- html ----
    e = html.escape
    parts = [
        "<!DOCTYPE html>", "<html lang=\"en\"><head><meta charset=\"utf-8\">",
        f"<title>{e(title)}</title>",
        "<style>body{font-family:sans-serif;max-width:1200px;margin:1em auto;padding:0 1em;color:#222}"
        "table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #ccc;padding:3px 8px;"
        "text-align:left}th{background:#f0f0f0}td:nth-child(n+2){font-variant-numeric:tabular-nums}"
        "img{max-width:100%;border:1px solid #ddd}figure{margin:1.5em 0}"
        ".warn{color:#a00;font-weight:bold}code{background:#f5f5f5}</style>",
        "</head><body>", f"<h1>{e(title)}</h1>", "<ul>"]
    for lab, rel, own in run_lines:
        link = f" (<a href=\"{e(own)}\">its own report</a>)" if own else ""
        parts.append(f"<li>run <b>{e(lab)}</b>: <code>{e(rel)}</code>{link}</li>")
    parts.append("</ul>")
    for w in warn:
        parts.append(f"<p class=\"warn\">Warning: {e(w)}</p>")
    parts += ["<h2>Key numbers</h2>", html_table(header, table_rows)]
    if mrows:
        parts += ["<h2>Monitors</h2>", html_table(mheader, mrows)]
    parts.append("<h2>Pictures</h2>")
    for p in pictures:
        parts.append(f"<figure><img src=\"{e(p)}\" alt=\"{e(p)}\"><figcaption>{e(CAPTIONS.get(p, p))}"
                     "</figcaption></figure>")
    if notes:
        parts += ["<h2>Notes</h2>", "<ul>"] + [f"<li>{e(n)}</li>" for n in notes] + ["</ul>"]
    parts.append("</body></html>")
    with open(os.path.join(out_dir, "index.html"), "w") as f:
        f.write("\n".join(parts) + "\n")


# ----------------------------------------------------------------------------- main
class Failures:
    """Collects failures of single pictures so one bad picture does not stop the report."""

    def __init__(self):
        self.count = 0

    def run(self, what, notes, fn, *args):
        try:
            return fn(*args)
        except Exception as ex:  # report and carry on
            self.count += 1
            plt.close("all")
            notes.append(f"{what} failed: {type(ex).__name__}: {ex}")
            print(f"cdem_report: {what} failed:", file=sys.stderr)
            traceback.print_exc()
            return None


def field_pictures(run, out_dir, written, notes, args, failures):
    if not run.fields:
        notes.append("no field output (fields.pvd): no field pictures.")
        return None
    frames = load_frames(run, choose_frames(run.fields, args.frames), args.magnify, notes)
    last = last_frame(run, args.magnify, [])
    if not frames or last is None:
        notes.append("no readable field output: no field pictures.")
        return None
    if last.time > frames[-1].time:
        frames = (frames + [last])[-args.frames:]
    failures.run("damage_maps.png", notes, plot_field_grid, run, frames, "damage", out_dir,
                 "damage_maps.png", written)
    failures.run("von_mises_maps.png", notes, plot_field_grid, run, frames, "von_mises", out_dir,
                 "von_mises_maps.png", written)
    failures.run("damage_final.png", notes, plot_damage_final, run, last, out_dir, "damage_final.png",
                 written)
    failures.run("fragments_final.png", notes, plot_fragments_final, run, last, out_dir, written)
    if last.dim == 3:
        failures.run("3D views", notes, plot_3d_views, run, last, out_dir, written)
    if not run.cracks:
        notes.append("no crack output (cracks.pvd): cracks not drawn.")
    return last


def main(argv=None):
    ap = argparse.ArgumentParser(
        prog="cdem_report.py",
        description="Pictures and a summary of finished cdemblast runs (several runs: overlaid "
                    "and compared).")
    ap.add_argument("runs", nargs="+", metavar="RUN", help="run directory (cdemblast run --out)")
    ap.add_argument("--out", metavar="OUTDIR",
                    help="output directory (default RUN/report; several runs: FIRST_RUN/report_compare)")
    ap.add_argument("--frames", type=int, default=MAX_FRAMES, metavar="N",
                    help=f"at most N output times in the map grids (default {MAX_FRAMES})")
    ap.add_argument("--magnify", type=float, default=1.0, metavar="M",
                    help="draw displacements magnified M times (default 1: the true deformed shape; "
                         "0: the undeformed mesh)")
    args = ap.parse_args(argv)
    if args.frames < 1:
        ap.error("--frames must be at least 1")
    if not math.isfinite(args.magnify):
        ap.error("--magnify must be a finite number")

    for d in args.runs:
        if not os.path.isdir(d):
            print(f"cdem_report: '{d}' is not a directory", file=sys.stderr)
            return 2
    try:
        runs = unique_labels([Run(d) for d in args.runs])
    except VtuError as ex:
        print(f"cdem_report: {ex}", file=sys.stderr)
        return 2
    multi = len(runs) > 1
    out_dir = args.out or os.path.join(runs[0].dir, "report_compare" if multi else "report")
    os.makedirs(out_dir, exist_ok=True)
    # Remove pictures of an earlier report so index.html never shows stale ones.
    for name in list(CAPTIONS) + ["summary.md", "index.html"]:
        p = os.path.join(out_dir, name)
        if os.path.isfile(p):
            os.remove(p)

    written, notes = [], []
    failures = Failures()
    for r in runs:
        if not r.monitors:
            r.notes.append("no monitor data (monitors.csv).")
        if r.fracture is None:
            r.notes.append("no fracture history (fracture.csv).")
        if r.energy is None:
            r.notes.append("no energy history (energy.csv).")
    failures.run("monitors.png", notes, plot_monitors, runs, out_dir, written)
    failures.run("fracture.png", notes, plot_fracture, runs, out_dir, written)
    failures.run("energy.png", notes, plot_energy, runs, out_dir, written)
    failures.run("grading.png", notes, plot_grading, runs, out_dir, written, notes)
    if multi:
        failures.run("damage_final_compare.png", notes, compare_damage, runs, out_dir, written, notes, args)
    else:
        failures.run("field pictures", runs[0].notes, field_pictures, runs[0], out_dir, written,
                     runs[0].notes, args, failures)
    for r in runs:  # per-run notes, named by their run when there are several
        notes.extend(f"{r.label}: {n}" if multi else n for n in r.notes)
    order = list(CAPTIONS)
    pictures = sorted(dict.fromkeys(written), key=lambda p: order.index(p) if p in order else 99)
    write_documents(runs, out_dir, pictures, notes)
    print(f"cdem_report: {len(pictures)} pictures, summary.md and index.html in {out_dir}")
    return 1 if failures.count else 0


