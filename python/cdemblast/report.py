"""The run report: PNG pictures, a summary.md, an index.html and a report.json of finished
runs (one run, or several overlaid and compared). `scripts/cdem_report.py` and
`cdemblast report` run main(). The page opens with the set-up (a picture of the model and the
inputs that matter: materials, interfaces, explosives, the charge per hole and deck in kg and
its energy, the powder factor, element sizes, time step, wall time) and a box of measured
warnings (checks.py), then the key numbers and the pictures. docs/report.md describes it all.
"""

from __future__ import annotations

import argparse
import html
import json
import math
import os
import sys
import traceback

import numpy as np

from . import checks, yardsticks
from .plots import (MAX_FRAMES, choose_frames, compare_damage, last_frame, load_frames,
                    plot_3d_views, plot_charges, plot_damage_final, plot_energy, plot_field_grid,
                    plot_fracture, plot_fragments_final, plot_grading, plot_monitors, plot_ppv,
                    plt)
from .run import Run, finite, mixed_run_ids, read_toml, unique_labels
from .setup import Setup, plot_setup
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
    ("interfaces", "intact interfaces", "", None, None),
    ("untied_points", "untied spring points (tied mode)", "", None, None),
    ("insertion_energy", "energy of the springs at untying (tied mode)", "J", 1, "{:.4g}"),
]
UNIT_SUFFIX = [("_m3", "m³"), ("_m", "m"), ("_s", "s"), ("_j", "J"), ("_pa", "Pa"), ("_kg", "kg")]
# Plane strain: these are per metre of thickness ("m³/m", "J/m", "kg/m")...
PER_METRE_UNITS = ("m³", "J", "kg")
# ... and these do not exist (a 2D funnel has no extent along y out of the plane).
NOT_IN_2D = ("funnel_ly_m", "funnel_axial_ratio")


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


def describe(key, per_metre=False):
    """(label, unit, scale, format) of a summary key; per_metre: a plane-strain run, whose
    volumes, masses and energies are per metre of thickness."""
    for k, lab, unit, sc, f in KNOWN:
        if k == key:
            break
    else:
        lab, unit, sc, f = key, "", 1, "{:.4g}"
        for suf, u in UNIT_SUFFIX:
            if key.lower().endswith(suf):
                lab, unit = key[: -len(suf)], u
                break
        lab = lab.replace(".", ": ").replace("_", " ")
    if per_metre and unit in PER_METRE_UNITS:
        unit += "/m"
    return lab, unit, sc, f


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
    two_d = [r.per_metre for r in runs]
    for k in keys + rest:
        lab, unit, sc, fm = describe(k, all(two_d))
        if any(two_d) and not all(two_d) and unit in PER_METRE_UNITS:
            unit += " (2D runs: per m)"
        vals = []
        for f, flat2d in zip(flats, two_d):
            if flat2d and k in NOT_IN_2D:
                vals.append("n/a (2D)")
            else:
                vals.append(format_value(f.get(k), sc, fm) if k in f else "–")
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
    "setup.png": "The model as set up (undeformed): blocks coloured by region with the mesh lines, "
                 "the holes with their charge decks and stemming, the monitors, and the boundary "
                 "conditions by type along the sides (free sides dotted). 3D: the vertical section "
                 "through the model centre (holes near it) and the view from above.",
    "monitors.png": "Monitor time histories: von Mises stress, the dominant velocity component and "
                    "the dominant displacement component at each monitor point.",
    "ppv.png": "Peak particle velocity (peak of the velocity magnitude) at the monitors against "
               "the scaled distance R / sqrt(Q), R the distance to the nearest charge deck, Q the "
               "largest charge per delay (8 ms window), with the least-squares fit "
               "PPV = K SD^-beta.",
    "fracture.png": "Fracture degree against time: broken / total spring-point area, split into "
                    "tensile and shear parts (and the count-based ratio).",
    "energy.png": "Energy balance: the stored, input and dissipated energy terms, and the relative "
                  "balance error (log scale). When the explosive work falls after its peak, the "
                  "legend says so: the rock then does work on the products.",
    "charges.png": "The charges' gas (charges.csv): the pressure of every deck against time, and "
                   "the detonation products' mass in the charges, in cracks and vented, summed "
                   "over the decks.",
    "grading.png": "Fragment size grading: cumulative volume percentage passing against the "
                   "characteristic size L_bc, with d40 and d80 marked (and the Kuz-Ram and "
                   "Swebrec curves of the design when one is given).",
    "damage_maps.png": "Damage (broken fraction of each block's interface area) at several output "
                       "times, one colour scale; black lines are the cracks; charge blocks "
                       "hatched grey.",
    "von_mises_maps.png": "von Mises stress at the same output times, one logarithmic colour scale "
                          "for all panels, clipped at the 99th percentile of all drawn values "
                          "(the colour bar's arrows mark the clipping).",
    "damage_final.png": "Damage at the last output time, with the cracks; charge blocks hatched "
                        "grey.",
    "fragments_final.png": "Fragments at the last output time: blocks connected through intact "
                           "spring points share a colour; the largest fragment is grey; the count "
                           "is that of fragments.csv and summary.json (charge blocks hatched, not "
                           "counted).",
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


def fmt(v, f="{:.4g}", scale=1.0, none="–"):
    x = finite(v)
    return none if x is None else f.format(x * scale)


# ----------------------------------------------------------------------------- set-up tables
def setup_tables(st):
    """[(title, header, rows)] of one run's set-up (Setup)."""
    case, run = st.case, st.run
    pm = st.per_metre
    mass_u, en_u, vol_u = ("kg/m", "MJ/m", "m³/m") if pm else ("kg", "MJ", "m³")
    out = []
    rows = []
    for p in st.parts:
        if p["kind"] == "deck":
            rows.append([p["hole"], f"deck {p['deck']}", p["explosive"], p["model"],
                         fmt(p["length_m"]), fmt(p["diameter_m"]), fmt(p["delay_s"], "{:.4g}", 1e3),
                         fmt(p["mass_kg"]), fmt(p["energy_j"], "{:.4g}", 1e-6)])
        else:
            rows.append([p["hole"], "stemming" + (" (rest of the hole)" if p.get("implicit") else ""),
                         "–", p["model"], fmt(p["length_m"]), fmt(p["diameter_m"]), "–", "–", "–"])
    if rows:
        out.append(("Charges, per hole from the bottom up" + (
            " (plane strain: a hole is a slot of its diameter's width; masses and energies "
            "per metre of thickness)" if pm else ""),
            ["hole", "part", "explosive", "model", "length (m)", "diameter (m)", "delay (ms)",
             f"mass ({mass_u})", f"energy ({en_u})"], rows))
    k, kt = st.powder_factor()
    sizes = st.element_sizes()
    s = run.summary
    rows = [
        ["charge in all holes", fmt(st.total_mass), mass_u],
        ["its energy (mass x detonation heat)", fmt(st.total_energy, "{:.4g}", 1e-6), en_u],
        ["rock that counts (no explosive, no damping zone, charge volume taken out)",
         fmt(st.rock_volume()), vol_u],
        ["its density", fmt(st.rock_density()), "kg/m³"],
        ["powder factor" + (" (kg/m of charge over m³/m of rock)" if pm else ""), fmt(k, "{:.3g}"),
         "kg/m³"],
        ["powder factor by mass", fmt(kt, "{:.3g}"), "kg/t"],
        ["blocks", fmt(s.get("blocks"), "{:.0f}"), ""],
        ["element size (largest edge): min / median / max",
         " / ".join(fmt(sizes.get(x), "{:.3g}") for x in ("edge_min_m", "edge_median_m",
                                                          "edge_max_m")), "m"],
        ["one block's characteristic size L_bc (median; the finest fragment the mesh resolves)",
         fmt(sizes.get("block_size_median_m"), "{:.3g}"), "m"],
        ["time step dt", fmt(s.get("dt"), "{:.4g}", 1e6), "µs"],
        ["dt limited by", str(s.get("dt_limit", "–")), ""],
        ["block / spring limits of dt", f"{fmt(s.get('dt_blocks'), '{:.4g}', 1e6)} / "
         f"{fmt(s.get('dt_springs'), '{:.4g}', 1e6)}", "µs"],
        ["steps", fmt(s.get("steps"), "{:.0f}"), ""],
        ["simulated time", fmt(s.get("end_time"), "{:.4g}", 1e3), "ms"],
        ["wall time (threads)", f"{fmt(s.get('wall_time_s'), '{:.3g}')} ({s.get('threads', '–')})", "s"],
    ]
    out.append(("Charge, rock and model", ["quantity", "value", "unit"], rows))
    rows = []
    for m in case.get("material", []):
        E, nu, rho = (finite(m.get(x)) for x in ("youngs_modulus", "poisson_ratio", "density"))
        cp = (math.sqrt(E * (1 - nu) / ((1 + nu) * (1 - 2 * nu) * rho))
              if E and rho and nu is not None and not m.get("explosive") else None)
        rows.append([m.get("name"), ", ".join(m.get("regions", [])),
                     m.get("explosive") or "–", fmt(rho), fmt(E, "{:.4g}", 1e-9) if not m.get("explosive") else "–",
                     fmt(nu) if not m.get("explosive") else "–", fmt(cp, "{:.0f}"),
                     fmt(m.get("damping"))])
    if rows:
        out.append(("Materials", ["material", "regions", "explosive (solid charge)", "density (kg/m³)",
                                  "E (GPa)", "ν", "P-wave speed (m/s)", "damping (1/s)"], rows))
    rows = []
    for itf in case.get("interface", []):
        law = itf.get("law", "mohr_coulomb")
        applies = "default" if itf.get("default") else "; ".join("–".join(p) for p in itf.get("pairs", []))
        rows.append([itf.get("name"), law, applies,
                     fmt(itf.get("tensile_strength"), "{:.4g}", 1e-6) if law != "elastic" else "–",
                     fmt(itf.get("cohesion"), "{:.4g}", 1e-6) if law != "elastic" else "–",
                     fmt(itf.get("friction_angle"), "{:g}"),
                     fmt(itf.get("tensile_fracture_energy")) if law == "fracture_energy" else "–",
                     fmt(itf.get("shear_fracture_energy")) if law == "fracture_energy" else "–",
                     "yes" if itf.get("precracked") else "no"])
    if rows:
        interfaces = case.get("simulation", {}).get("interfaces", "springs")
        out.append((f"Interface laws (intact interfaces: {interfaces})",
                    ["interface", "law", "applies to", "f_t (MPa)", "c (MPa)", "φ (°)",
                     "G_t (J/m²)", "G_s (J/m²)", "pre-cracked"], rows))
    rows = []
    used = {p.get("explosive") for p in st.decks}
    for e in case.get("explosive", []):
        if e.get("name") not in used and not any(m.get("explosive") == e.get("name")
                                                 for m in case.get("material", [])):
            continue
        eos = e.get("eos", "landau")
        q = finite(e.get("detonation_heat")) if eos != "jwl" else None
        rows.append([e.get("name"), eos, fmt(e.get("density")), fmt(e.get("detonation_velocity")),
                     fmt(q, "{:.4g}", 1e-6) if q else fmt(finite(e.get("E0")) and finite(e.get("E0")) / finite(e.get("density")), "{:.4g}", 1e-6) + " (E0/ρ)",
                     f"{fmt(e.get('gamma1'), '{:g}')} / {fmt(e.get('gamma2'), '{:g}')}" if eos != "jwl" else "JWL"])
    if rows:
        out.append(("Explosives", ["explosive", "equation of state", "density (kg/m³)",
                                   "D (m/s)", "energy (MJ/kg)", "γ1 / γ2"], rows))
    rows = []
    from .setup import SIDE_NAMES
    shape = case.get("mesh", {}).get("generate", {}).get("shape")
    drawn = set(SIDE_NAMES.get(shape, {}).values())
    for b in case.get("boundary", []):
        kind = b.get("type")
        val = (fmt(b.get("pressure"), "{:.4g}", 1e-6) + " MPa" if kind == "pressure" else
               str(b.get("velocity")) + " m/s" if kind == "velocity" else "–")
        rows.append([b.get("faces"), kind, val, "yes" if b.get("faces") in drawn else "no"])
    for z in case.get("damping_zone", []):
        rows.append([f"region {z.get('region')}", "damping zone",
                     f"up to {fmt(z.get('max_damping'))} 1/s", "yes (region colour)"])
    if rows:
        out.append(("Boundary conditions (faces without one are free)",
                    ["face set", "type", "value", "in setup.png"], rows))
    return out


def compact_setup_rows(setups):
    """[(quantity, unit, [value per run])] for a comparison."""
    rows = []
    pm = all(st.per_metre for st in setups)
    mass_u = "kg/m" if pm else "kg"
    rows.append(("charge in all holes", mass_u, [fmt(st.total_mass) for st in setups]))
    rows.append(("charge energy", "MJ/m" if pm else "MJ", [fmt(st.total_energy, "{:.4g}", 1e-6) for st in setups]))
    rows.append(("powder factor", "kg/m³", [fmt(st.powder_factor()[0], "{:.3g}") for st in setups]))
    rows.append(("powder factor by mass", "kg/t", [fmt(st.powder_factor()[1], "{:.3g}") for st in setups]))
    rows.append(("element size, median largest edge", "m",
                 [fmt(st.element_sizes().get("edge_median_m"), "{:.3g}") for st in setups]))
    return rows


# ----------------------------------------------------------------------------- documents
def record_warnings(run, warns):
    """Writes the run's warnings (measured here, and its own) into its summary.json as
    `warnings`: a list of {code, message, value, limit}. Read back by the next report, the
    measured ones are not repeated (checks.merge), so the list stays the same. The file is
    replaced atomically; a run without a summary.json is left alone."""
    path = os.path.join(run.dir, "summary.json")
    if not run.summary or not os.path.isfile(path):
        return
    data = dict(run.summary)
    data["warnings"] = [{k: w.get(k) for k in ("code", "message", "value", "limit")} for w in warns]
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(jsonable(data), f, indent=1)
        f.write("\n")
    os.replace(tmp, path)


def warning_lines(per_run, multi):
    """[(run label or None, message)] of every run's warnings."""
    out = []
    for label, warns in per_run:
        for w in warns:
            out.append((label if multi else None, w["message"]))
    return out


def ppv_rows(ppv, multi):
    rows = []
    for label, (pts, fit, q, pm) in ppv.items():
        for p in pts:
            rows.append(([label] if multi else []) + [p["monitor"], fmt(p["ppv_m_s"], "{:.3g}"),
                                                      fmt(p["time_s"], "{:.4g}", 1e3),
                                                      fmt(p["distance_m"], "{:.3g}"),
                                                      fmt(p["scaled_distance"], "{:.3g}")])
    return rows


def write_documents(runs, out_dir, pictures, notes, setups, per_run_warnings, ppv, kuzram):
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
    prow = ppv_rows(ppv, multi)
    pm = all(r.per_metre for r in runs)
    pheader = (["run"] if multi else []) + ["monitor", "PPV (m/s)", "at time (ms)",
                                           "distance to the charge R (m)",
                                           "R / sqrt(Q) (m/(kg/m)^0.5)" if pm else "R / sqrt(Q) (m/kg^0.5)"]
    fits = [(label, fit, q) for label, (pts, fit, q, _pm) in ppv.items() if fit]
    run_lines = []
    for r in runs:
        own = os.path.join(r.dir, "report", "index.html")
        link = os.path.relpath(own, out_dir) if multi and os.path.isfile(own) else None
        run_lines.append((r.label, r.dir, link))
    warns = warning_lines(per_run_warnings, multi)
    if multi:
        set_tables = [("Set-up of each run", ["quantity", "unit"] + [r.label for r in runs],
                       [[q, u] + v for q, u, v in compact_setup_rows(setups)])]
    else:
        set_tables = setup_tables(setups[0])
    kr_rows = []
    if kuzram is not None:
        kj = kuzram.to_json()
        kr_rows = [["powder factor of the design", fmt(kj["powder_factor_kg_m3"], "{:.3g}"), "kg/m³"],
                   ["charge per hole", fmt(kj["charge_per_hole_kg"], "{:.3g}"), "kg"],
                   ["x50 (Kuz-Ram)", fmt(kj["x50_m"], "{:.3g}"), "m"],
                   ["uniformity index n", fmt(kj["uniformity_n"], "{:.3g}"), ""],
                   ["d40 / d80 (Rosin-Rammler)", f"{fmt(kj['rosin_rammler']['d40_m'], '{:.3g}')} / "
                    f"{fmt(kj['rosin_rammler']['d80_m'], '{:.3g}')}", "m"]]
        if kj["swebrec"]:
            kr_rows.append(["d40 / d80 (Swebrec, xmax = " + fmt(kj["xmax_m"], "{:.3g}") + " m)",
                            f"{fmt(kj['swebrec']['d40_m'], '{:.3g}')} / {fmt(kj['swebrec']['d80_m'], '{:.3g}')}", "m"])

    # ---- markdown ----
    md = [f"# {title}", ""]
    for lab, rel, _ in run_lines:
        md.append(f"- run `{lab}`: `{rel}`")
    md.append("")
    md += ["## Warnings", ""]
    if warns:
        md += [f"- **{lab}:** {m}" if lab else f"- {m}" for lab, m in warns]
    else:
        md.append("No warning: none of the checks of docs/report.md fired.")
    md += ["", "## Set-up", ""]
    if "setup.png" in pictures:
        md += ["![setup.png](setup.png)", "", CAPTIONS["setup.png"], ""]
    for t, h, r in set_tables:
        md += [f"**{t}**", "", md_table(h, r), ""]
    md += ["## Key numbers", "", md_table(header, table_rows), ""]
    if mrows:
        md += ["## Monitors", "", md_table(mheader, mrows), ""]
    if prow:
        md += ["**Peak particle velocity**", "", md_table(pheader, prow), ""]
        for label, fit, q in fits:
            md.append(f"- {label}: PPV = {fit['K']:.3g} (R/√Q)^-{fit['beta']:.3g} m/s, R² {fit['r2']:.3f}, "
                      f"Q = {q:.3g} {'kg/m' if pm else 'kg'} per delay")
        md.append("")
    if kr_rows:
        md += ["## Kuz-Ram yardstick of the design", "", md_table(["quantity", "value", "unit"], kr_rows), ""]
    md += ["## Pictures", ""]
    for p in pictures:
        if p == "setup.png":
            continue
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
        ".warnings{border:2px solid #c00;background:#fff4f4;padding:0.5em 1em;margin:1em 0}"
        ".warnings h2{color:#a00;margin:0.2em 0}.ok{border:2px solid #3a3;background:#f4fff4;"
        "padding:0.5em 1em}code{background:#f5f5f5}</style>",
        "</head><body>", f"<h1>{e(title)}</h1>", "<ul>"]
    for lab, rel, own in run_lines:
        link = f" (<a href=\"{e(own)}\">its own report</a>)" if own else ""
        parts.append(f"<li>run <b>{e(lab)}</b>: <code>{e(rel)}</code>{link}</li>")
    parts.append("</ul>")
    if warns:
        parts += ["<div class=\"warnings\" id=\"warnings\"><h2>Warnings</h2><ul>"]
        parts += [f"<li>{('<b>' + e(lab) + ':</b> ') if lab else ''}{e(m)}</li>" for lab, m in warns]
        parts += ["</ul></div>"]
    else:
        parts.append("<p class=\"ok\" id=\"warnings\">No warning: none of the checks fired.</p>")
    parts.append("<h2 id=\"setup\">Set-up</h2>")
    if "setup.png" in pictures:
        parts.append(f"<figure><img src=\"setup.png\" alt=\"setup.png\"><figcaption>"
                     f"{e(CAPTIONS['setup.png'])}</figcaption></figure>")
    for t, h, r in set_tables:
        parts += [f"<h3>{e(t)}</h3>", html_table(h, r)]
    parts += ["<h2>Key numbers</h2>", html_table(header, table_rows)]
    if mrows:
        parts += ["<h2>Monitors</h2>", html_table(mheader, mrows)]
    if prow:
        parts += ["<h3>Peak particle velocity</h3>", html_table(pheader, prow)]
        for label, fit, q in fits:
            parts.append(f"<p>{e(label)}: PPV = {fit['K']:.3g} (R/√Q)<sup>-{fit['beta']:.3g}</sup> m/s, "
                         f"R² {fit['r2']:.3f}, Q = {q:.3g} {'kg/m' if pm else 'kg'} per delay</p>")
    if kr_rows:
        parts += ["<h2>Kuz-Ram yardstick of the design</h2>",
                  html_table(["quantity", "value", "unit"], kr_rows)]
    parts.append("<h2>Pictures</h2>")
    for p in pictures:
        if p == "setup.png":
            continue
        parts.append(f"<figure><img src=\"{e(p)}\" alt=\"{e(p)}\"><figcaption>{e(CAPTIONS.get(p, p))}"
                     "</figcaption></figure>")
    if notes:
        parts += ["<h2>Notes</h2>", "<ul>"] + [f"<li>{e(n)}</li>" for n in notes] + ["</ul>"]
    parts.append("</body></html>")
    with open(os.path.join(out_dir, "index.html"), "w") as f:
        f.write("\n".join(parts) + "\n")


def jsonable(v):
    """numpy values and arrays as plain JSON; non-finite numbers as null."""
    if isinstance(v, dict):
        return {str(k): jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [jsonable(x) for x in v]
    if isinstance(v, np.ndarray):
        return jsonable(v.tolist())
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return float(v) if math.isfinite(v) else None
    return v


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



def field_pictures(run, out_dir, written, notes, args, failures, charge=None):
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
                 "damage_maps.png", written, charge)
    failures.run("von_mises_maps.png", notes, plot_field_grid, run, frames, "von_mises", out_dir,
                 "von_mises_maps.png", written, charge)
    failures.run("damage_final.png", notes, plot_damage_final, run, last, out_dir, "damage_final.png",
                 written, None, None, charge)
    failures.run("fragments_final.png", notes, plot_fragments_final, run, last, out_dir, written,
                 charge)
    if last.dim == 3:
        failures.run("3D views", notes, plot_3d_views, run, last, out_dir, written)
    if not run.cracks:
        notes.append("no crack output (cracks.pvd): cracks not drawn.")
    return last


def read_design(path):
    """The [design] table of a TOML file (a study file or a design file), for Kuz-Ram."""
    d = read_toml(path)
    if not d:
        raise ValueError(f"{path}: cannot read it as TOML")
    return d.get("design", d)


def kuzram_of(design, setup):
    """A yardsticks.KuzRam for a design; charge_per_hole, hole_diameter and charge_length default
    to the case's (the largest deck of all holes, its hole's diameter and charged length)."""
    d = dict(design or {})
    if not d:
        return None
    decks = setup.decks if setup is not None else []
    if decks:
        per_hole = {}
        for p in decks:
            per_hole.setdefault(p["hole"], []).append(p)
        big = max(per_hole.values(), key=lambda ps: sum(p["mass_kg"] or 0 for p in ps))
        d.setdefault("charge_per_hole", sum(p["mass_kg"] or 0 for p in big))
        d.setdefault("hole_diameter", big[0]["diameter_m"])
        d.setdefault("charge_length", sum(p["length_m"] for p in big))
    return yardsticks.KuzRam(d)


def ppv_of(run, setup):
    """(points, fit, charge per delay, per metre) of a run's monitors."""
    if setup is None or not setup.decks:
        return [], None, None, run.per_metre
    pts, q = yardsticks.monitor_ppv(run, setup.decks)
    pts = [p for p in pts if p["scaled_distance"]]
    fit = yardsticks.fit_ppv([p["scaled_distance"] for p in pts], [p["ppv_m_s"] for p in pts])
    return pts, fit, q, run.per_metre


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
    ap.add_argument("--design", metavar="TOML",
                    help="a TOML file with a [design] table (docs/study.md): draw the Kuz-Ram / "
                         "Swebrec curves of that design beside the grading")
    args = ap.parse_args(argv)
    if args.frames < 1:
        ap.error("--frames must be at least 1")
    if not math.isfinite(args.magnify):
        ap.error("--magnify must be a finite number")

    for d in args.runs:
        if not os.path.isdir(d):
            print(f"cdem_report: '{d}' is not a directory", file=sys.stderr)
            return 2
    for d in args.runs:
        mixed = mixed_run_ids(d)
        if mixed:
            print(f"cdem_report: '{d}': {mixed}; rerun it into a clean directory "
                  "(cdemblast run ... --overwrite)", file=sys.stderr)
            return 2
    try:
        runs = unique_labels([Run(d) for d in args.runs])
    except VtuError as ex:
        print(f"cdem_report: {ex}", file=sys.stderr)
        return 2
    design = None
    if args.design:
        try:
            design = read_design(args.design)
        except ValueError as ex:
            print(f"cdem_report: {ex}", file=sys.stderr)
            return 2
    multi = len(runs) > 1
    out_dir = args.out or os.path.join(runs[0].dir, "report_compare" if multi else "report")
    os.makedirs(out_dir, exist_ok=True)
    # Remove pictures of an earlier report so index.html never shows stale ones.
    for name in list(CAPTIONS) + ["summary.md", "index.html", "report.json"]:
        p = os.path.join(out_dir, name)
        if os.path.isfile(p):
            os.remove(p)

    written, notes = [], []
    failures = Failures()
    setups, per_run_warnings, numbers, ppv = [], [], {}, {}
    for r in runs:
        if not r.monitors:
            r.notes.append("no monitor data (monitors.csv).")
        if r.fracture is None:
            r.notes.append("no fracture history (fracture.csv).")
        if r.energy is None:
            r.notes.append("no energy history (energy.csv).")
        st = failures.run(f"set-up of {r.label}", r.notes, Setup, r)
        setups.append(st)
        warns, nums = (failures.run(f"checks of {r.label}", r.notes, checks.measure, r, st)
                       if st is not None else None) or (checks.merge([], r.summary.get("warnings")), {})
        per_run_warnings.append((r.label, warns))
        numbers[r.label] = nums
        if st is not None:
            r.notes.extend(st.notes)
            ppv[r.label] = failures.run(f"PPV of {r.label}", r.notes, ppv_of, r, st) or ([], None, None, r.per_metre)
    kuzram = None
    if design is not None:
        kuzram = failures.run("Kuz-Ram of the design", notes, kuzram_of, design, setups[0])
    if not multi and setups[0] is not None:
        failures.run("setup.png", notes, plot_setup, setups[0], out_dir, written)
    failures.run("monitors.png", notes, plot_monitors, runs, out_dir, written)
    failures.run("ppv.png", notes, plot_ppv, [(lab, pts, fit, pm) for lab, (pts, fit, _q, pm) in ppv.items()],
                 out_dir, written)
    failures.run("fracture.png", notes, plot_fracture, runs, out_dir, written)
    failures.run("energy.png", notes, plot_energy, runs, out_dir, written)
    failures.run("charges.png", notes, plot_charges, runs, out_dir, written)
    failures.run("grading.png", notes, plot_grading, runs, out_dir, written, notes, kuzram)
    if multi:
        failures.run("damage_final_compare.png", notes, compare_damage, runs, out_dir, written, notes, args)
    else:
        charge = setups[0].charge_cell if setups[0] is not None and setups[0].measures is not None else None
        failures.run("field pictures", runs[0].notes, field_pictures, runs[0], out_dir, written,
                     runs[0].notes, args, failures, charge)
    for r in runs:  # per-run notes, named by their run when there are several
        notes.extend(f"{r.label}: {n}" if multi else n for n in r.notes)
    order = list(CAPTIONS)
    pictures = sorted(dict.fromkeys(written), key=lambda p: order.index(p) if p in order else 99)
    write_documents(runs, out_dir, pictures, notes, setups, per_run_warnings, ppv, kuzram)
    for r, (_lab, w) in zip(runs, per_run_warnings):
        failures.run(f"warnings into {r.label}'s summary.json", notes, record_warnings, r, w)
    report = {
        "runs": [{"label": r.label, "dir": r.dir, "summary": r.summary,
                  "setup": st.to_json() if st is not None else None,
                  "checks": numbers.get(r.label, {}),
                  "warnings": w,
                  "ppv": {"points": ppv.get(r.label, ([], None))[0],
                          "fit": ppv.get(r.label, ([], None))[1],
                          "charge_per_delay": (ppv.get(r.label) or [None] * 4)[2]}}
                 for r, st, (_lab, w) in zip(runs, setups, per_run_warnings)],
        "warnings": [dict(w, run=lab) for lab, ws in per_run_warnings for w in ws],
        "kuz_ram": kuzram.to_json() if kuzram is not None else None,
        "pictures": pictures,
        "notes": notes,
    }
    with open(os.path.join(out_dir, "report.json"), "w") as f:
        json.dump(jsonable(report), f, indent=1)
        f.write("\n")
    print(f"cdem_report: {len(pictures)} pictures, summary.md, index.html and report.json in {out_dir}")
    return 1 if failures.count else 0
