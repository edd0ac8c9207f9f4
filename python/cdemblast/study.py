"""Studies: a base case and its variants (as --set overrides), run with `cdemblast run` and
compared on one page (docs/study.md).

    cdemblast study FILE [--out DIR] [--threads N] [--no-run]
    /usr/bin/python3 scripts/cdem_study.py FILE [--out DIR] [--threads N] [--no-run] [--bin B]

Running: every variant into DIR/<name> with `cdemblast run`, skipping (resuming) a variant
whose directory already holds a finished summary.json for the same resolved case (its
case.resolved.toml has every key the variant asks for, with the same value). When an override
of simulation.end_time ends a run before some of the case's output times, those are dropped
(with a notice). Wall and CPU times of the runs made go to DIR/timings.json.

Comparing: DIR/index.html (the pictures, the tables and a recommendation table that states its
criteria), DIR/study.json (every number) and the PNGs: vertical displacement fields at chosen
times (3D: top view and vertical section; 2D: the model), monitor histories, fracture degree
over time (total, and per region when fracture.csv has degree_area_<region> columns), grading
curves with d40/d80 (and the Kuz-Ram / Swebrec curves of a [design]), the funnel, fly-rock
(maximum vertical displacement from the fields, fragment launch speeds), the energy budget.
"""

from __future__ import annotations

import argparse
import html
import json
import math
import os
import resource
import subprocess
import sys
import textwrap
import time

import numpy as np

from . import plots
from .geometry import block_measures
from .plots import (load_frames, plot_energy, plot_fracture, plot_grading,
                    plot_monitors, plot_ppv, plt, save)
from .report import Failures, html_table, jsonable, kuzram_of, ppv_of
from .run import Run, finite, read_toml, tomllib
from .setup import Setup

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))


class StudyError(Exception):
    """A study file or a command line that cannot be used (exit code 2)."""


# ----------------------------------------------------------------------------- the study file
def parse_value(text):
    """A --set VALUE as TOML (numbers, booleans, arrays, quoted strings)."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except Exception as e:  # tomllib.TOMLDecodeError
        raise StudyError(f"--set value '{text}' is not TOML ({e})") from None


def apply_set(case, key, value):
    """Applies one dotted-path override (docs/case_reference.md 5.2) to a case dict."""
    parts = key.split(".")
    node = case
    for i, p in enumerate(parts):
        last = i == len(parts) - 1
        if isinstance(node, list):
            try:
                k = int(p)
            except ValueError:
                raise StudyError(f"--set {key}: '{p}' must be an index") from None
            if not 0 <= k < len(node):
                raise StudyError(f"--set {key}: index {k} beyond the array")
            if last:
                node[k] = value
            else:
                node = node[k]
            continue
        if last:
            node[p] = value
        else:
            node = node.setdefault(p, {})
    return case


def split_set(s):
    k, sep, v = s.partition("=")
    if not sep or not k.strip():
        raise StudyError(f"--set '{s}' is not KEY=VALUE")
    return k.strip(), v.strip()


def same_value(want, got, tol=1e-12):
    """Does the resolved value `got` hold the requested `want` (numbers to a relative
    tolerance, points padded with zeros, tables as subsets)?"""
    if isinstance(want, bool) or isinstance(got, bool):
        return isinstance(want, bool) and isinstance(got, bool) and want == got
    if isinstance(want, (int, float)) and isinstance(got, (int, float)):
        return abs(want - got) <= tol * max(1.0, abs(want), abs(got))
    if isinstance(want, dict):
        return isinstance(got, dict) and all(k in got and same_value(v, got[k]) for k, v in want.items())
    if isinstance(want, list):
        if not isinstance(got, list):
            return False
        if want and all(isinstance(x, (int, float)) for x in want) and len(got) > len(want):
            return (all(same_value(a, b) for a, b in zip(want, got))
                    and all(isinstance(x, (int, float)) and x == 0 for x in got[len(want):]))
        return len(want) == len(got) and all(same_value(a, b) for a, b in zip(want, got))
    return want == got


class Variant:
    def __init__(self, table, study):
        self.name = table.get("name")
        if not self.name or not isinstance(self.name, str) or "/" in self.name:
            raise StudyError(f"{study.path}: every [[variant]] needs a name (a directory name)")
        self.label = table.get("label") or self.name
        case = table.get("case") or study.base
        if not case:
            raise StudyError(f"{study.path}: variant '{self.name}' has no case and [study] no base")
        self.case = os.path.normpath(os.path.join(study.root, case))
        sets = table.get("set", [])
        if isinstance(sets, str) or not all(isinstance(s, str) for s in sets):
            raise StudyError(f"{study.path}: variant '{self.name}': set must be a list of "
                             "\"KEY=VALUE\" strings")
        self.sets = list(study.sets) + list(sets)
        self.repeat = int(table.get("repeat", 1))
        self.optional = bool(table.get("optional", False))
        self.dir = os.path.join(study.out, self.name)
        self.run = None
        self.resumed = False

    def requested_case(self):
        """The case file with this variant's overrides applied (no defaults)."""
        case = read_toml(self.case)
        if not case:
            raise StudyError(f"{self.case}: the case file is missing or not TOML")
        for s in self.sets + self.extra_sets():
            k, v = split_set(s)
            apply_set(case, k, parse_value(v))
        return case

    def extra_sets(self):
        """Output times past an overridden end time are dropped (else the case is refused)."""
        keys = {split_set(s)[0] for s in self.sets}
        if "simulation.end_time" not in keys or "simulation.output_times" in keys:
            return []
        end = None
        for s in self.sets:
            k, v = split_set(s)
            if k == "simulation.end_time":
                end = finite(parse_value(v))
        case = read_toml(self.case)
        times = case.get("simulation", {}).get("output_times", [])
        if end is None or not times:
            return []
        kept = [t for t in times if t <= end * (1 + 1e-12)]
        if len(kept) == len(times):
            return []
        return ["simulation.output_times=[" + ",".join(repr(float(t)) for t in kept) + "]"]

    def is_done(self):
        """A finished summary.json and a resolved case that holds every requested key."""
        s = read_json(os.path.join(self.dir, "summary.json"))
        if not s or s.get("status") != "finished":
            return False
        resolved = read_toml(os.path.join(self.dir, "case.resolved.toml"))
        want = self.requested_case()
        want.pop("title", None)
        mesh = want.get("mesh", {})
        if "file" in mesh:  # paths are resolved against the case's directory: compare names
            got = resolved.get("mesh", {}).get("file", "")
            if os.path.basename(str(got)) != os.path.basename(str(mesh["file"])):
                return False
            mesh = dict(mesh)
            mesh.pop("file")
            want["mesh"] = mesh
        return bool(resolved) and same_value(want, resolved)


def read_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


class Study:
    """A study file, parsed and checked (docs/study.md)."""

    def __init__(self, path, out=None, sets=()):
        self.path = os.path.abspath(path)
        if tomllib is None:
            raise StudyError("studies need Python >= 3.11 (tomllib)")
        try:
            with open(self.path, "rb") as f:
                data = tomllib.load(f)
        except OSError as e:
            raise StudyError(f"{path}: cannot read ({e.strerror})") from None
        except tomllib.TOMLDecodeError as e:
            raise StudyError(f"{path}: not valid TOML ({e})") from None
        self.data = data
        self.root = os.path.dirname(self.path)
        st = data.get("study", {})
        known = {"study", "variant", "compare", "design", "recommend", "analysis"}
        unknown = [k for k in data if k not in known]
        if unknown:
            raise StudyError(f"{path}: unknown table(s) {', '.join(unknown)} (known: "
                             f"{', '.join(sorted(known))})")
        self.title = st.get("title") or os.path.splitext(os.path.basename(path))[0]
        self.base = st.get("base")
        self.sets = st.get("set", [])
        if isinstance(self.sets, str) or not all(isinstance(s, str) for s in self.sets):
            raise StudyError(f"{path}: [study] set must be a list of \"KEY=VALUE\" strings")
        self.sets = list(self.sets) + list(sets)  # the command line's --set: every variant
        self.cli_sets, self.cli_threads = list(sets), None
        self.out = os.path.abspath(out or st.get("out") or os.path.join(
            "runs", os.path.splitext(os.path.basename(path))[0]))
        self.threads = st.get("threads")
        self.analyses = st.get("analyses", [])
        self.variants = [Variant(v, self) for v in data.get("variant", [])]
        if not self.variants:
            raise StudyError(f"{path}: no [[variant]]")
        names = [v.name for v in self.variants]
        if len(set(names)) != len(names):
            raise StudyError(f"{path}: variant names must be unique")
        self.compare = data.get("compare", {})
        self.design = data.get("design")
        self.recommend = data.get("recommend", {})
        if not isinstance(self.recommend, dict):
            raise StudyError(f"{path}: [recommend] must be a table")
        bad = [k for k in self.recommend if k not in ("tolerance", "speed_quantile", "rise_quantile")]
        if bad:
            raise StudyError(f"{path}: [recommend] unknown key(s) {', '.join(bad)} (known: "
                             "tolerance, speed_quantile, rise_quantile)")
        self.analysis = data.get("analysis", {})
        for v in self.variants:
            if not os.path.isfile(v.case):
                raise StudyError(f"{path}: variant '{v.name}': case file {v.case} not found")

    def variant(self, name):
        for v in self.variants:
            if v.name == name:
                return v
        raise StudyError(f"no variant '{name}' in {self.path}")


# ----------------------------------------------------------------------------- running
def find_binary(arg=None):
    for b in (arg, os.environ.get("CDEM_BIN"), os.path.join(REPO, "build", "bin", "cdemblast")):
        if b:
            if not (os.path.isfile(b) and os.access(b, os.X_OK)):
                raise StudyError(f"cdemblast binary '{b}' not found or not executable (build it, "
                                 "or give --bin or $CDEM_BIN)")
            return b
    return None


def run_variant(binary, v, threads=None, extra=(), repeats=None, verbose=False, log=print):
    """Runs one variant (repeats times into the same directory); returns {"wall_s": [...],
    "cpu_s": [...]} (wall from summary.json, CPU = user + system of the cdemblast process)."""
    sets = v.sets + v.extra_sets() + list(extra)
    for s in v.extra_sets():
        log(f"study: {v.name}: the end time drops output times: {s}")
    # An interrupted run (SIGINT, SIGTERM: its checkpoint and an "interrupted" summary) or a
    # killed one (checkpoints, no summary) is continued; anything else in the directory is
    # replaced (--overwrite: the run directory is cleared first).
    summary = read_json(os.path.join(v.dir, "summary.json"))
    ckpts = os.path.join(v.dir, "checkpoints")
    interrupted = (os.path.isdir(ckpts) and any(n.endswith(".cdemckpt") for n in os.listdir(ckpts))
                   and (summary is None
                        or (isinstance(summary, dict) and summary.get("status") == "interrupted")))
    opts = []
    if not verbose:
        opts.append("-q")
    if threads is not None:
        opts += ["--threads", str(threads)]
    for s in sets:
        opts += ["--set", s]
    n = repeats or v.repeat
    timing = {"wall_s": [], "cpu_s": []}
    os.makedirs(v.dir, exist_ok=True)
    for k in range(n):
        more = f" (run {k + 1} of {n})" if n > 1 else ""
        if k == 0 and interrupted and n == 1:
            cmd = [binary, "run", v.case, "--restart", v.dir] + opts
            log(f"study: continuing the interrupted {v.name} run from its checkpoint ...")
        else:
            cmd = [binary, "run", v.case, "--out", v.dir, "--overwrite"] + opts
            log(f"study: running {v.name}{more} ...")
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.monotonic()
        rc = subprocess.run(cmd).returncode
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        if rc != 0:
            raise RuntimeError(f"the {v.name} run failed (exit code {rc}): {' '.join(cmd)}")
        cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
        wall = (read_json(os.path.join(v.dir, "summary.json")) or {}).get(
            "wall_time_s", time.monotonic() - t0)
        timing["wall_s"].append(wall)
        timing["cpu_s"].append(cpu)
        log(f"study: {v.name} done in {wall:.1f} s ({cpu:.1f} s CPU)")
    return timing


def run_study(study, binary, threads=None, only=None, extra_sets=None, repeats=None,
              verbose=False, resume=True, include_optional=(), log=print, resume_only=False):
    """Runs the variants that need it; returns the updated timings (DIR/timings.json)."""
    os.makedirs(study.out, exist_ok=True)
    tpath = os.path.join(study.out, "timings.json")
    timings = read_json(tpath) or {}
    threads = threads if threads is not None else study.threads
    for v in study.variants:
        if only and v.name not in only:
            continue
        if v.optional and v.name not in include_optional and not (only and v.name in only):
            continue
        v.sets = v.sets + list((extra_sets or {}).get(v.name, []))
        if resume and (not only or resume_only) and v.is_done():
            v.resumed = True
            log(f"study: {v.name}: finished run found in {v.dir} (same resolved case): not rerun")
            continue
        t = run_variant(binary, v, threads, (), (repeats or {}).get(v.name), verbose, log)
        timings = read_json(tpath) or {}  # (re-read: other processes may run other variants)
        timings[v.name] = t
        with open(tpath, "w") as f:
            json.dump(timings, f, indent=1)
    return timings


# ----------------------------------------------------------------------------- measures
def up_vector(run):
    return run.up


def vertical(frame, run):
    """Displacement along `up` at every node (m)."""
    return frame.u @ up_vector(run)


def launch_speeds(run, frame, setup):
    """(speeds (m/s), vertical speeds, volumes, source) of the fragments of a field output,
    the main rock mass (id 0) and the charge left out: from fragments.csv's vx, vy, vz when it
    has them, else the volume-weighted mean of the VTU velocity over each fragment_id."""
    tab = run.fragments_at(frame.path)
    up = up_vector(run)
    if tab is not None and all(isinstance(tab.get(c), np.ndarray) for c in ("id", "vx", "vy", "vz")):
        v = np.stack([tab["vx"], tab["vy"], tab["vz"]], 1)
        keep = tab["id"] != 0
        vol = tab["volume"][keep] if isinstance(tab.get("volume"), np.ndarray) else np.ones(keep.sum())
        return np.linalg.norm(v[keep], axis=1), (v[keep] @ up), vol, "fragments.csv"
    fid = frame.cell("fragment_id")
    vel = frame.grid.point_array("velocity")
    if fid is None or vel is None:
        return None, None, None, None
    fid = np.asarray(fid).astype(np.int64)
    meas = block_measures(frame.X, frame.grid)
    cell_v = np.zeros((frame.grid.ncells, 3))
    from .geometry import cell_node_lists
    for ids, nodes in cell_node_lists(frame.grid):
        cell_v[ids] = vel[nodes].mean(1)
    keep = fid > 0
    if setup is not None and setup.measures is not None:
        keep &= ~setup.charge_cell
    ids = np.unique(fid[keep])
    vol = np.array([meas["volume"][fid == i].sum() for i in ids])
    mv = np.array([(cell_v[fid == i] * meas["volume"][fid == i, None]).sum(0) for i in ids])
    mv = mv / np.maximum(vol, 1e-300)[:, None] if ids.size else np.zeros((0, 3))
    return np.linalg.norm(mv, axis=1), mv @ up, vol, "VTU velocity per fragment_id"


def in_funnel(points, funnel, up):
    """Mask of the points (reference positions) inside a design funnel: a box {lo, hi} or a
    cylinder {center (on the free surface), radius, depth (along -up)}."""
    shape = funnel.get("shape", "box")
    if shape == "box":
        lo = np.zeros(3)
        hi = np.zeros(3)
        lo[:len(funnel["lo"])] = funnel["lo"]
        hi[:len(funnel["hi"])] = funnel["hi"]
        if len(funnel["lo"]) == 2:
            lo[2], hi[2] = -np.inf, np.inf
        return np.all((points >= lo) & (points <= hi), axis=1)
    if shape == "cylinder":
        c = np.zeros(3)
        c[:len(funnel["center"])] = funnel["center"]
        d = points - c
        along = -(d @ up)  # depth below the centre
        radial = np.linalg.norm(d + np.outer(along, up), axis=1)
        return (along >= -1e-9) & (along <= funnel["depth"]) & (radial <= funnel["radius"])
    raise StudyError(f"design funnel shape '{shape}': expected box or cylinder")


def passing_sizes(sizes, volumes, pcts=(10, 20, 30, 40, 50, 60, 70, 80, 90)):
    """{f"d{p}_m"} of a volume-weighted grading (linear interpolation of the cumulative
    volume passing against the size, as grading.csv)."""
    if sizes.size == 0:
        return {f"d{p}_m": None for p in pcts}, np.zeros(0), np.zeros(0)
    o = np.argsort(sizes)
    s, v = sizes[o], volumes[o]
    cum = 100.0 * np.cumsum(v) / v.sum()
    return {f"d{p}_m": float(np.interp(p, cum, s)) for p in pcts}, s, cum


def weighted_quantile(values, weights, q):
    """The smallest value v with a share of at least q of the total weight at or below it
    (None without data): the volume-weighted quantile the fly-rock criteria use."""
    v = np.asarray(values, float).ravel()
    w = np.asarray(weights, float).ravel()
    ok = np.isfinite(v) & np.isfinite(w) & (w > 0)
    if not ok.any():
        return None
    o = np.argsort(v[ok], kind="stable")
    v, w = v[ok][o], w[ok][o]
    c = np.cumsum(w)
    i = int(np.searchsorted(c, q * c[-1], side="left"))
    return float(v[min(i, v.size - 1)])


def fly_rock_quantiles(study):
    """([recommend] speed_quantile, rise_quantile): defaults 0.95 and 0.99, each in (0, 1]."""
    rec = study.recommend if study is not None else {}
    out = []
    for key, default in (("speed_quantile", 0.95), ("rise_quantile", 0.99)):
        q = rec.get(key, default)
        if isinstance(q, bool) or not isinstance(q, (int, float)) or not (0 < q <= 1):
            raise StudyError(f"{study.path}: [recommend] {key} = {q!r}: expected a number in "
                             "(0, 1] (the share of the volume at or below the value)")
        out.append(float(q))
    return tuple(out)


def measure_variant(v, study, notes):
    """Every number the comparison needs of one variant (a dict; see docs/study.md)."""
    run, st = v.run, v.setup
    s = run.summary
    out = {"name": v.name, "label": v.label, "dir": run.dir, "status": s.get("status"),
           "resumed": v.resumed, "wall_time_s": s.get("wall_time_s"), "blocks": s.get("blocks"),
           "steps": s.get("steps"), "dt": s.get("dt"), "dimension": run.dim}
    out["fracture_degree"] = {k: s.get(f"fracture_degree{suf}") for k, suf in
                              (("total", ""), ("tensile", "_tensile"), ("shear", "_shear"),
                               ("count", "_count"))}
    fr = run.fracture
    regions = {}
    if fr is not None:
        for c, val in fr.items():
            if c.startswith("degree_area_") and isinstance(val, np.ndarray) and val.size:
                regions[c[len("degree_area_"):]] = float(val[-1])
    out["fracture_degree"]["by_region"] = regions or None
    if isinstance(s.get("fracture_degree_regions"), dict):
        out["fracture_degree"]["by_region_summary"] = s["fracture_degree_regions"]
    out["grading"] = {f"d{p}_m": s.get(f"d{p}_m") for p in range(10, 100, 10)}
    out["fragments"] = s.get("fragments")
    two_d = run.dim == 2
    out["funnel"] = {"depth_m": s.get("funnel_depth_m"), "l_x_m": s.get("funnel_lx_m"),
                     "l_y_m": None if two_d else s.get("funnel_ly_m"),
                     "axial_ratio": None if two_d else s.get("funnel_axial_ratio"),
                     "footage_m": s.get("footage_m"), "broken_volume": s.get("funnel_broken_volume"),
                     "not_in_2d": ["l_y_m", "axial_ratio"] if two_d else []}
    if run.energy is not None:
        e = run.energy
        out["energy"] = {k: float(e[k][-1]) for k in ("kinetic", "block_strain", "spring_strain",
                                                       "external_work", "gravity_work",
                                                       "explosive_work", "damping", "fracture",
                                                       "initial", "insertion", "products_kinetic",
                                                       "balance", "error")
                         if k in e}
        out["energy"]["time_s"] = float(e["time"][-1])
        out["energy"]["per_metre"] = two_d
    # Fly-rock: per output the fragments' speeds and the rock's rise (displacement along up),
    # each as its largest value and as the robust quantile the recommendation uses: the value
    # exceeded by a share 1 - q of the moving fragments' volume (speed) or of the rock's volume
    # (rise), so that a few tiny, numerically ejected fragments do not decide.
    qs, qr = fly_rock_quantiles(study)
    fly = {"max_vertical_displacement_m": None, "time_s": None, "max_displacement_m": None,
           "speed_quantile": qs, "rise_quantile": qr}
    speeds_all, speeds_q, rises_q = [], [], []
    last = None
    ref_vol = None
    from .geometry import cell_node_lists
    for i in range(len(run.fields)):
        frs = load_frames(run, [i], 1.0, notes)
        if not frs:
            continue
        f = frs[0]
        last = f
        uz_all = vertical(f, run)
        rock_node = np.ones(uz_all.size, bool)
        rock_cell = np.ones(f.grid.ncells, bool)
        charge = (st is not None and st.measures is not None
                  and st.charge_cell.size == f.grid.ncells)
        if charge:
            rock_cell = ~st.charge_cell  # the charge's own blocks are not fly-rock
        # per rock block the rise of its nodes' mean (weighted by the block's reference volume,
        # the same at every output)
        cell_uz = np.full(f.grid.ncells, np.nan)
        for ids, nodes in cell_node_lists(f.grid):
            cell_uz[ids] = uz_all[nodes].mean(1)
            if charge:
                rock_node[nodes[st.charge_cell[ids]].ravel()] = False
        if ref_vol is None or ref_vol.size != f.grid.ncells:
            ref_vol = block_measures(f.X, f.grid)["volume"]
        vol = ref_vol
        uz = uz_all[rock_node]
        if uz.size and (fly["max_vertical_displacement_m"] is None
                        or uz.max() > fly["max_vertical_displacement_m"]):
            fly["max_vertical_displacement_m"] = float(uz.max())
            fly["time_s"] = f.time
        r = weighted_quantile(cell_uz[rock_cell], vol[rock_cell], qr)
        if r is not None:
            rises_q.append((f.time, r))
        mag = float(np.linalg.norm(f.u, axis=1).max()) if f.u.size else None
        if mag is not None and (fly["max_displacement_m"] is None or mag > fly["max_displacement_m"]):
            fly["max_displacement_m"] = mag
        sp, _vz, fvol, src = launch_speeds(run, f, st)
        if sp is not None and sp.size:
            speeds_all.append((f.time, float(sp.max())))
            speeds_q.append((f.time, weighted_quantile(sp, fvol, qs)))
    if last is not None:
        sp, vz, vol, src = launch_speeds(run, last, st)
        if sp is not None:
            fly["launch_speed_source"] = src
            fly["fragments_moving"] = int(sp.size)
            fly["launch_speeds_m_s"] = [float(x) for x in np.sort(sp)] if sp.size <= 5000 else None
            fly["max_launch_speed_m_s"] = float(sp.max()) if sp.size else 0.0
            fly["p90_launch_speed_m_s"] = float(np.percentile(sp, 90)) if sp.size else 0.0
            fly["median_launch_speed_m_s"] = float(np.median(sp)) if sp.size else 0.0
            fly["max_upward_speed_m_s"] = float(vz.max()) if vz.size else 0.0
    fly["max_launch_speed_by_output"] = speeds_all
    fly["quantile_launch_speed_by_output"] = speeds_q
    fly["quantile_rise_by_output"] = rises_q
    if speeds_all:
        fly["max_launch_speed_any_output_m_s"] = max(x for _, x in speeds_all)
    fly["quantile_launch_speed_m_s"] = max((x for _, x in speeds_q), default=None)
    fly["quantile_rise_m"] = max((x for _, x in rises_q), default=None)
    out["fly_rock"] = fly
    # Monitors: peak displacement along up.
    mons = {}
    up = up_vector(run)
    for n, m in run.monitors.items():
        comps = [m.get(c, np.zeros_like(m["time"])) for c in ("ux", "uy", "uz")]
        uu = comps[0] * up[0] + comps[1] * up[1] + comps[2] * up[2]
        i = int(np.nanargmax(np.abs(uu))) if uu.size else 0
        mons[n] = {"peak_vertical_displacement_m": float(uu[i]) if uu.size else None,
                   "time_s": float(m["time"][i]) if uu.size else None,
                   "final_vertical_displacement_m": float(uu[-1]) if uu.size else None}
    out["monitors"] = mons
    # The design funnel: damage and grading of what lies inside it.
    funnel = (study.design or {}).get("funnel")
    out["design_funnel"] = None
    if funnel and last is not None and st is not None and st.measures is not None:
        meas = st.measures
        inside = in_funnel(meas["centroid"], funnel, up) & ~st.charge_cell & ~st.damping_cell
        dmg = np.asarray(last.cell("damage"), float)
        vol = meas["volume"]
        rec = {"blocks": int(inside.sum())}
        if inside.any():
            rec["fracture_degree"] = float(np.sum(dmg[inside] * vol[inside]) / np.sum(vol[inside]))
            outside = ~inside & ~st.charge_cell & ~st.damping_cell
            rec["damaged_volume_outside"] = float(np.sum(dmg[outside] * vol[outside]))
            fid = last.cell("fragment_id")
            tab = run.fragments_at(last.path)
            if fid is not None and tab is not None:
                fid = np.asarray(fid).astype(np.int64)
                ids = tab["id"].astype(np.int64)
                cen = np.array([np.average(meas["centroid"][fid == i], axis=0,
                                           weights=vol[fid == i]) if np.any(fid == i)
                                else np.full(3, np.nan) for i in ids])
                sel = (ids != 0) & in_funnel(cen, funnel, up)
                ds, _s, _c = passing_sizes(tab["l_bc"][sel], tab["volume"][sel])
                rec["fragments"] = int(sel.sum())
                rec.update(ds)
        out["design_funnel"] = rec
    out["ppv"] = None
    if st is not None:
        pts, fit, q, _pm = ppv_of(run, st)
        out["ppv"] = {"points": pts, "fit": fit, "charge_per_delay": q}
        k, kt = st.powder_factor()
        out["setup"] = {"charge_mass_kg": st.total_mass, "charge_energy_j": st.total_energy,
                        "powder_factor_kg_m3": k, "powder_factor_kg_t": kt,
                        "per_metre": st.per_metre}
    return out


# ----------------------------------------------------------------------------- recommendation
def pick(values, larger_better, tol, names):
    """Lexicographic choice: `values` is a list of criteria, each {name: value or None}; the
    best on the first criterion wins, ties (within the relative tolerance) go to the next.
    Returns (winner, the criterion that decided, candidates left after each criterion)."""
    cands = [n for n in names if values[0].get(n) is not None]
    trail = []
    decided = None
    for ci, crit in enumerate(values):
        vals = {n: crit.get(n) for n in cands if crit.get(n) is not None}
        if not vals:
            trail.append(list(cands))
            continue
        best = max(vals.values()) if larger_better[ci] else min(vals.values())
        scale = max(abs(best), 1e-300)
        cands = [n for n in vals if abs(vals[n] - best) <= tol * scale]
        trail.append(list(cands))
        if len(cands) == 1:
            decided = ci
            break
    winner = cands[0] if len(cands) == 1 else None
    return winner, decided, trail


def recommend(measures, study):
    """The recommendation table: for each goal its criteria (in order), every variant's value,
    the winner and what decided."""
    tol = float(study.recommend.get("tolerance", 0.05))
    names = [m["name"] for m in measures]
    by = {m["name"]: m for m in measures}
    funnel = (study.design or {}).get("funnel")

    def fly(key):
        return {n: finite(by[n]["fly_rock"].get(key)) for n in names}

    def in_design(key, whole):
        if funnel:
            return {n: finite((by[n]["design_funnel"] or {}).get(key)) for n in names}
        return {n: whole(by[n]) for n in names}

    def region_fd(m):
        reg = m["fracture_degree"].get("by_region")
        if reg:
            rock = [k for k in reg if not k.startswith("ring")]
            main = [k for k in rock if k in ("rock",)] or rock
            if main:
                return finite(reg[main[0]])
        return finite(m["fracture_degree"].get("total"))

    where = ("inside the design funnel ([design.funnel])" if funnel
             else "over the rock (per-region fracture degree of the main region when fracture.csv "
                  "has it, else the whole model; no design funnel given)")
    goals = []
    qs, qr = fly_rock_quantiles(study)
    c1 = [(f"fragment launch speed exceeded by {100 * (1 - qs):g} % of the moving fragments' volume, "
           "largest over the outputs (m/s), lower is better",
           fly("quantile_launch_speed_m_s"), False),
          (f"rise (displacement along up) exceeded by {100 * (1 - qr):g} % of the rock's volume, "
           "largest over the outputs (m), lower is better",
           fly("quantile_rise_m"), False)]
    c2 = [(f"fracture degree {where}, higher is better",
           in_design("fracture_degree", region_fd), True),
          (f"d80 {where} (m), lower is better",
           in_design("d80_m", lambda m: finite(m["grading"].get("d80_m"))), False),
          (f"d40 {where} (m), lower is better",
           in_design("d40_m", lambda m: finite(m["grading"].get("d40_m"))), False)]
    for goal, crits in (("limits fly-rock", c1), ("breaks the rock best", c2)):
        winner, decided, trail = pick([c[1] for c in crits], [c[2] for c in crits], tol, names)
        tied = trail[-1] if trail and winner is None else []
        goals.append({
            "goal": goal,
            "criteria": [{"criterion": c[0], "values": c[1], "larger_is_better": c[2]}
                         for c in crits],
            "rule": (f"the best variant on the first criterion; variants within {100 * tol:g} % "
                     "of the best go on to the next criterion"),
            "winner": winner,
            "tied": tied,
            "decided_by": crits[decided][0] if decided is not None else
            (f"no clear winner: {', '.join(tied)} are within {100 * tol:g} % on every criterion"
             if len(tied) > 1 else "no data"),
        })
    most = fly("quantile_launch_speed_m_s")
    known = {n: x for n, x in most.items() if x is not None}
    extra = {"most_fly_rock": max(known, key=known.get) if known else None}
    return {"tolerance": tol, "goals": goals, **extra}


# ----------------------------------------------------------------------------- pictures
def choose_times(run, times):
    """Field outputs nearest to the asked times (all outputs after 0 when none asked: the last)."""
    if not run.fields:
        return []
    ts = np.array([t for t, _ in run.fields])
    if not times:
        return [len(ts) - 1]
    out = []
    for t in times:
        i = int(np.argmin(np.abs(ts - t)))
        if i not in out:
            out.append(i)
    return out


def charge_cells(v, frame):
    """The variant's charge-cell mask for a field output (None when its set-up has none or the
    output's cells differ)."""
    if v.setup is None or v.setup.measures is None or v.setup.charge_cell.size != frame.grid.ncells:
        return None
    return v.setup.charge_cell


def variant_key(variants, width=110):
    """The variants' long labels, one line each (wrapped at `width`), for a figure whose panels
    are titled by the short names: panel titles of 40-80 characters ran into each other."""
    lines = []
    for v in variants:
        text = v.label if v.label.startswith(v.name) else f"{v.name}: {v.label}"
        lines += textwrap.wrap(text, width, subsequent_indent="    ") or [v.name]
    return "\n".join(lines)


def panel_grid(nr, nc, aspect):
    """A figure of nr x nc map panels (rows: variants, columns: times) with a shared colour bar."""
    w, h = plots.figsize_for(nc, nr, aspect, 3.4, False, True, 2)
    return plt.subplots(nr, nc, squeeze=False, constrained_layout=True, figsize=(max(w, 7.5), h))


def plot_vertical(variants, times, out_dir, written, notes):
    """Vertical displacement (along up) at the chosen times, one shared diverging colour scale
    over every panel (clipped at the 99th percentile of |u_up|, arrows on the colour bar).
    3D: vertical_displacement_top.png (the free surface seen from above) and
    vertical_displacement_section.png; 2D: vertical_displacement.png (the model)."""
    from matplotlib import colors as mcolors
    from matplotlib.collections import PolyCollection
    rows = []
    for v in variants:
        idx = choose_times(v.run, times)
        frames = load_frames(v.run, idx, 1.0, notes)
        rows.append((v, frames))
    if not any(fr for _, fr in rows):
        return []
    dim = variants[0].run.dim
    kinds = ["model"] if dim == 2 else ["top", "section"]
    names = []
    for kind in kinds:
        panels = []
        for v, frames in rows:
            row = []
            for f in frames:
                charge = charge_cells(v, f)
                if kind == "top":
                    top = f.top_faces()
                    if top is None:
                        continue
                    verts, ids, un = top
                    row.append((f, [(verts, np.arange(len(ids)))], un * 1e3, (f.h1, f.h2),
                                charge[ids] if charge is not None else None))
                else:
                    view = f.view()
                    uz = vertical(f, v.run)
                    cell = np.zeros(f.grid.ncells)
                    from .geometry import cell_node_lists
                    for ids, nodes in cell_node_lists(f.grid):
                        cell[ids] = uz[nodes].mean(1)
                    row.append((f, view.polys, cell * 1e3, view.idx, charge))
            panels.append((v, row))
        vals = [np.concatenate([val[ids][~ch[ids]] if ch is not None else val[ids]
                                for _, ids in polys]) for _, row in panels
                for _f, polys, val, _i, ch in row if polys]
        if not vals:
            continue
        allv = np.abs(np.concatenate(vals))
        top = float(np.percentile(allv, 99)) or float(allv.max()) or 1.0
        vmax = float(allv.max())
        norm = mcolors.Normalize(-top, top)
        nr = len(panels)
        nc = max(len(r) for _, r in panels)
        f0, p0, _v0, i0, _c0 = next(x for _, r in panels for x in r)
        box = plots.view_box([p for _, r in panels for _f, p, _v, _i, _c in r], f0, i0)
        fig, axes = panel_grid(nr, nc, plots.box_aspect(box))
        m, handle = None, None
        for r, (v, row) in enumerate(panels):
            for c in range(nc):
                ax = axes[r, c]
                if c >= len(row):
                    ax.set_visible(False)
                    continue
                f, polys, val, idx, ch = row[c]
                for verts, ids in polys:
                    m = PolyCollection(verts, array=val[ids], cmap="RdBu_r", norm=norm,
                                       edgecolors="face", linewidths=0.1)
                    ax.add_collection(m)
                hc = plots.draw_charge(ax, polys, ch)
                if hc is not None and handle is None:
                    handle, handle_ax = hc, ax
                flip = kind == "section" and f.s < 0
                plots.set_limits(ax, box, f"{'xyz'[idx[0]]} (m)", f"{'xyz'[idx[1]]} (m)", flip)
                ax.set_title(f"{v.name}, {plots.fmt_time(f.time)}", fontsize=9)
        if m is not None:
            cb = plots.colorbar(fig, m, ax=axes.ravel().tolist(), shrink=0.8,
                                extend="both" if vmax > top else "neither")
            cb.set_label(f"displacement along up (mm)\nclipped at ±{top:.3g} (99th percentile "
                         f"of |u|; max {vmax:.3g})")
        if handle is not None:
            handle_ax.legend(handles=[handle], loc="lower left", fontsize=7, framealpha=0.85)
        what = {"model": "the model (plane strain)", "top": "the free surface (faces looking up)",
                "section": "vertical section through the model centre"}[kind]
        fig.suptitle(f"Displacement along up: {what}; one colour scale for all panels\n"
                     f"{variant_key([v for v, _ in panels])}", fontsize=10)
        name = {"model": "vertical_displacement.png", "top": "vertical_displacement_top.png",
                "section": "vertical_displacement_section.png"}[kind]
        names.append(save(fig, out_dir, name, written))
    if dim == 2:
        notes.append("2D study: no top view (the model is its own vertical section).")
    return names


def plot_damage(variants, times, out_dir, written, notes):
    """Damage (the broken share of each block's interface area) and the cracks at the chosen
    times: damage.png, rows the variants, columns the times (3D: the vertical section)."""
    rows = [(v, load_frames(v.run, choose_times(v.run, times), 1.0, notes)) for v in variants]
    rows = [(v, frames) for v, frames in rows if frames]
    if not rows:
        return None
    # one box for every panel (each frame's own made the panels' scales differ with the
    # fragments in flight)
    f0 = rows[0][1][0]
    idx = f0.view().idx
    box = plots.view_box([f.view().polys for _, frames in rows for f in frames], f0, idx)
    fig, axes = panel_grid(len(rows), max(len(frames) for _, frames in rows), plots.box_aspect(box))
    m = None
    for r, (v, frames) in enumerate(rows):
        for c in range(axes.shape[1]):
            ax = axes[r, c]
            if c >= len(frames):
                ax.set_visible(False)
                continue
            f = frames[c]
            charge = charge_cells(v, f)
            got = plots.plot_damage_final(v.run, f, out_dir, None, written, ax=ax, fig=fig,
                                          charge=charge, box=box)
            m = m if m is not None else got
            ax.set_title(f"{v.name}, {plots.fmt_time(f.time)}", fontsize=9)
    if m is not None:
        cb = plots.colorbar(fig, m, ax=axes.ravel().tolist(), shrink=0.8)
        cb.set_label("damage (broken fraction of interface area)")
    fig.suptitle("Damage at the chosen output times (rows: variants); black lines: cracks\n"
                 f"{variant_key([v for v, _ in rows])}", fontsize=10)
    return save(fig, out_dir, "damage.png", written)


def plot_monitor_vertical(variants, out_dir, written):
    """Displacement along up at each monitor, the variants overlaid."""
    runs = [v.run for v in variants if v.run.monitors]
    if not runs:
        return None
    names = list(dict.fromkeys(n for r in runs for n in r.monitors))
    nc = min(3, len(names))
    nr = math.ceil(len(names) / nc)
    fig, axes = plt.subplots(nr, nc, squeeze=False, figsize=(4.6 * nc, 3.2 * nr + 0.6),
                             constrained_layout=True, sharex=True)
    colors = plots.run_colors(len(variants))
    tmax = max(float(m["time"].max()) for r in runs for m in r.monitors.values())
    tf, tu = plots.time_scale(tmax)
    for k, n in enumerate(names):
        ax = axes.ravel()[k]
        for i, v in enumerate(variants):
            m = v.run.monitors.get(n)
            if m is None:
                continue
            up = up_vector(v.run)
            uu = sum(m.get(c, 0) * up[j] for j, c in enumerate(("ux", "uy", "uz")))
            ax.plot(m["time"] * tf, uu * 1e3, color=colors[i], lw=1.3, label=v.label)
        ax.set_title(f"monitor {n}", fontsize=10)
        ax.set_ylabel("displacement along up (mm)")
        ax.set_xlabel(f"time ({tu})")
    for ax in axes.ravel()[len(names):]:
        ax.set_visible(False)
    axes.ravel()[0].legend(fontsize=8)
    fig.suptitle("Vertical displacement (along up) at the monitors")
    return save(fig, out_dir, "monitors_vertical.png", written)


def plot_fracture_regions(variants, out_dir, written, notes):
    """fracture_regions.png: the fracture degree of each region over time (fracture.csv columns
    degree_area_<region>), variants overlaid; skipped with a note when no run has them."""
    cols = []
    for v in variants:
        fr = v.run.fracture or {}
        cols += [c for c in fr if c.startswith("degree_area_") and c not in cols]
    if not cols:
        notes.append("fracture.csv has no per-region columns (degree_area_<region>): the fracture "
                     "degree is compared in total only.")
        return None
    fig, axes = plt.subplots(1, len(cols), squeeze=False, figsize=(4.8 * len(cols), 4.2),
                             constrained_layout=True, sharey=True)
    colors = plots.run_colors(len(variants))
    for ax, c in zip(axes[0], cols):
        for i, v in enumerate(variants):
            fr = v.run.fracture
            if fr is None or c not in fr:
                continue
            tf, tu = plots.time_scale(float(fr["time"].max()))
            ax.plot(fr["time"] * tf, fr[c] * 100, color=colors[i], lw=1.5,
                    label=f"{v.label}: {100 * fr[c][-1]:.1f} %")
            ax.set_xlabel(f"time ({tu})")
        ax.set_title(f"region {c[len('degree_area_'):]}")
        # (below the axes: inside, the long labels covered the curves and the axis label)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16))
    axes[0, 0].set_ylabel("fracture degree (%)")
    fig.suptitle(textwrap.fill("Fracture degree per region (broken / total spring-point area of "
                               "the region)", max(40, int(12 * 4.8 * len(cols)))), fontsize=11)
    return save(fig, out_dir, "fracture_regions.png", written)


def plot_launch_speeds(measures, out_dir, written):
    """launch_speeds.png: the distribution (share of fragments with at most a speed) of the
    fragments' speeds at the last output, per variant, and the largest speed at each output."""
    have = [m for m in measures if m["fly_rock"].get("launch_speeds_m_s")]
    if not have:
        return None
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 6.2), constrained_layout=True)
    colors = plots.run_colors(len(measures))
    for i, m in enumerate(measures):
        sp = m["fly_rock"].get("launch_speeds_m_s")
        if sp:
            x = np.sort(sp)
            a1.step(x, 100 * np.arange(1, x.size + 1) / x.size, where="post", color=colors[i],
                    lw=1.5, label=f"{m['label']}: {x.size} fragments, max {x[-1]:.3g} m/s")
        by = m["fly_rock"].get("max_launch_speed_by_output") or []
        if by:
            t = np.array([b[0] for b in by])
            tf, tu = plots.time_scale(float(t.max()))
            a2.plot(t * tf, [b[1] for b in by], "o-", color=colors[i], ms=4,
                    label=f"{m['label']}: largest")
            a2.set_xlabel(f"time ({tu})")
        qb = m["fly_rock"].get("quantile_launch_speed_by_output") or []
        if qb:
            t = np.array([b[0] for b in qb])
            tf, _ = plots.time_scale(float(t.max()))
            q = m["fly_rock"].get("speed_quantile", 0.95)
            a2.plot(t * tf, [b[1] for b in qb], "s--", color=colors[i], ms=3,
                    label=f"{m['label']}: {100 * q:g} % of the fragments' volume below")
    a1.set_xlabel("fragment speed (m/s)")
    a1.set_ylabel("fragments at or below the speed (%)")
    a1.set_title("Fragment speeds at the last output (main rock mass left out)", fontsize=10)
    a1.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14))
    a2.set_ylabel("fragment speed (m/s)")
    a2.set_yscale("log")
    a2.set_title("Fragment speed at each output: the largest and the criterion's quantile", fontsize=10)
    a2.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14))
    return save(fig, out_dir, "launch_speeds.png", written)


def plot_energy_budget(measures, out_dir, written):
    """energy_budget.png: the energy terms at the end of each run as bars."""
    have = [m for m in measures if m.get("energy")]
    if not have:
        return None
    terms = [("explosive_work", "explosive work (in)"), ("kinetic", "kinetic"),
             ("block_strain", "block strain"), ("spring_strain", "spring strain"),
             ("damping", "damping + absorbed"), ("fracture", "fracture dissipation"),
             ("insertion", "opened points at insertion (in)")]
    terms = [t for t in terms if any(abs(m["energy"].get(t[0], 0)) > 0 for m in have)]
    vmax = max(abs(m["energy"].get(k, 0)) for m in have for k, _ in terms) or 1.0
    sc, unit = plots.energy_scale(vmax)
    if all(m["energy"].get("per_metre") for m in have):
        unit += "/m"
    fig, ax = plt.subplots(figsize=(max(7, 1.3 * len(terms) * len(have) / 2 + 4), 4.8),
                           constrained_layout=True)
    w = 0.8 / len(have)
    colors = plots.run_colors(len(have))
    x = np.arange(len(terms))
    for i, m in enumerate(have):
        ax.bar(x + (i - (len(have) - 1) / 2) * w, [m["energy"].get(k, 0) * sc for k, _ in terms],
               w, color=colors[i], label=f"{m['label']} (t = {m['energy']['time_s'] * 1e3:.3g} ms, "
                                         f"error {m['energy'].get('error', float('nan')):.1e})")
    ax.set_xticks(x, [lab for _, lab in terms], rotation=20, ha="right")
    ax.set_ylabel(f"energy ({unit})")
    ax.set_title("Energy budget at the end of each run")
    ax.legend(fontsize=8)
    return save(fig, out_dir, "energy_budget.png", written)


# ----------------------------------------------------------------------------- the page
CAPTIONS = {
    "vertical_displacement.png": "Displacement along the free-surface normal `up` at the chosen "
                                 "output times (rows: variants), one colour scale.",
    "vertical_displacement_top.png": "Displacement along `up` of the faces looking up (the free "
                                     "surface seen from above), one colour scale for all panels.",
    "vertical_displacement_section.png": "Displacement along `up` in the vertical section through "
                                         "the model centre, one colour scale for all panels.",
    "damage.png": "Damage (broken share of each block's interface area) and cracks at the chosen "
                  "output times (rows: variants; 3D: the vertical section).",
    "monitors.png": "Monitor histories (von Mises stress, dominant velocity and displacement "
                    "components), line style per variant.",
    "monitors_vertical.png": "Displacement along `up` at each monitor, the variants overlaid.",
    "fracture.png": "Fracture degree over time: total, tensile and shear parts.",
    "fracture_regions.png": "Fracture degree of each region over time (fracture.csv "
                            "degree_area_<region>).",
    "grading.png": "Grading curves with d40 and d80 (and the Kuz-Ram / Swebrec curves of the "
                   "design, dashed and dotted).",
    "launch_speeds.png": "Fly-rock: distribution of the fragments' speeds at the last output and "
                         "the largest speed at each output.",
    "energy.png": "Energy terms over time, the variants overlaid.",
    "energy_budget.png": "Energy budget at the end of each run.",
    "ppv.png": "Peak particle velocity at the monitors against the scaled distance, with the "
               "fitted K and beta of each variant.",
}


def fmtv(v, f="{:.4g}", scale=1.0):
    x = finite(v)
    return "–" if x is None else f.format(x * scale)


def pick_label(goal, measures):
    lab = {m["name"]: m["label"] for m in measures}
    if goal["winner"]:
        return lab[goal["winner"]]
    if len(goal.get("tied", [])) > 1:
        return "tie: " + ", ".join(lab[n] for n in goal["tied"])
    return "–"


def tables(measures, rec, study):
    """[(title, header, rows)] of the comparison."""
    labels = [m["label"] for m in measures]
    two_d = all(m["dimension"] == 2 for m in measures)
    vol_u = "m³/m" if two_d else "m³"
    out = []
    rows = []
    for g in rec["goals"]:
        for i, c in enumerate(g["criteria"]):
            rows.append([g["goal"] if i == 0 else "", c["criterion"]]
                        + [fmtv(c["values"].get(m["name"])) for m in measures]
                        + ([pick_label(g, measures)] if i == 0 else [""]))
        rows.append(["", "rule: " + g["rule"] + "; decided by: " + g["decided_by"]]
                    + [""] * len(measures) + [""])
    out.append(("Recommendation", ["goal", "criterion (in order)"] + labels + ["pick"], rows))
    rows = [
        ["status", ""] + [str(m["status"]) + (" (resumed)" if m["resumed"] else "") for m in measures],
        ["charge", "kg/m" if two_d else "kg"] + [fmtv((m.get("setup") or {}).get("charge_mass_kg")) for m in measures],
        ["powder factor", "kg/m³"] + [fmtv((m.get("setup") or {}).get("powder_factor_kg_m3"), "{:.3g}") for m in measures],
        ["fracture degree (total)", "%"] + [fmtv(m["fracture_degree"]["total"], "{:.2f}", 100) for m in measures],
        ["  tensile / shear", "%"] + [f"{fmtv(m['fracture_degree']['tensile'], '{:.2f}', 100)} / "
                                      f"{fmtv(m['fracture_degree']['shear'], '{:.2f}', 100)}" for m in measures],
    ]
    regs = sorted({k for m in measures for k in (m["fracture_degree"].get("by_region") or {})})
    for r in regs:
        rows.append([f"  region {r}", "%"] + [fmtv((m["fracture_degree"].get("by_region") or {}).get(r), "{:.2f}", 100)
                                              for m in measures])
    rows += [
        ["fragments", ""] + [fmtv(m["fragments"], "{:.0f}") for m in measures],
        ["d40", "m"] + [fmtv(m["grading"]["d40_m"]) for m in measures],
        ["d80", "m"] + [fmtv(m["grading"]["d80_m"]) for m in measures],
        ["funnel depth", "m"] + [fmtv(m["funnel"]["depth_m"]) for m in measures],
        ["funnel l_x", "m"] + [fmtv(m["funnel"]["l_x_m"]) for m in measures],
        ["funnel l_y", "m"] + ["n/a (2D)" if m["dimension"] == 2 else fmtv(m["funnel"]["l_y_m"]) for m in measures],
        ["funnel axial ratio l_y / l_x", ""] + ["n/a (2D)" if m["dimension"] == 2 else fmtv(m["funnel"]["axial_ratio"], "{:.3g}") for m in measures],
        ["footage", "m"] + [fmtv(m["funnel"]["footage_m"]) for m in measures],
        ["funnel broken volume", vol_u] + [fmtv(m["funnel"]["broken_volume"]) for m in measures],
        ["max displacement along up (fields)", "m"] + [fmtv(m["fly_rock"]["max_vertical_displacement_m"]) for m in measures],
        ["rise exceeded by the top share of the rock volume (criterion)", "m"] + [fmtv(m["fly_rock"].get("quantile_rise_m")) for m in measures],
        ["fragment speed exceeded by the top share of the fragments' volume (criterion)", "m/s"] + [fmtv(m["fly_rock"].get("quantile_launch_speed_m_s")) for m in measures],
        ["max fragment speed, last output", "m/s"] + [fmtv(m["fly_rock"].get("max_launch_speed_m_s")) for m in measures],
        ["90th percentile fragment speed", "m/s"] + [fmtv(m["fly_rock"].get("p90_launch_speed_m_s")) for m in measures],
        ["max upward fragment speed", "m/s"] + [fmtv(m["fly_rock"].get("max_upward_speed_m_s")) for m in measures],
        ["wall time", "s"] + [fmtv(m["wall_time_s"], "{:.3g}") for m in measures],
    ]
    if (study.design or {}).get("funnel"):
        for key, lab, unit, sc in (("fracture_degree", "fracture degree inside the design funnel", "%", 100),
                                   ("d40_m", "d40 inside the design funnel", "m", 1),
                                   ("d80_m", "d80 inside the design funnel", "m", 1),
                                   ("damaged_volume_outside", "damaged volume outside it (damage-weighted)", vol_u, 1)):
            rows.append([lab, unit] + [fmtv((m["design_funnel"] or {}).get(key), "{:.4g}", sc) for m in measures])
    out.append(("Key numbers", ["quantity", "unit"] + labels, rows))
    rows = []
    names = sorted({n for m in measures for n in m["monitors"]})
    for n in names:
        rows.append([n] + [fmtv((m["monitors"].get(n) or {}).get("peak_vertical_displacement_m"), "{:.4g}", 1e3)
                           for m in measures])
    if rows:
        out.append(("Peak displacement along up at the monitors (mm)", ["monitor"] + labels, rows))
    rows = []
    for key, lab in (("explosive_work", "explosive work"), ("kinetic", "kinetic"),
                     ("products_kinetic", "kinetic: the products' own part"),
                     ("block_strain", "block strain"), ("spring_strain", "spring strain"),
                     ("damping", "damping + absorbed"), ("fracture", "fracture"),
                     ("error", "balance error (relative)")):
        rows.append([lab, "" if key == "error" else ("MJ/m" if two_d else "MJ")]
                    + [fmtv((m.get("energy") or {}).get(key), "{:.3g}" if key == "error" else "{:.4g}",
                            1 if key == "error" else 1e-6) for m in measures])
    out.append(("Energy budget at the end", ["term", "unit"] + labels, rows))
    return out


def write_page(study, measures, rec, pictures, analyses, notes, kuz):
    e = html.escape
    t = tables(measures, rec, study)
    parts = ["<!DOCTYPE html>", "<html lang=\"en\"><head><meta charset=\"utf-8\">",
             f"<title>Study: {e(study.title)}</title>",
             "<style>body{font-family:sans-serif;max-width:1250px;margin:1em auto;padding:0 1em;"
             "color:#222}table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #ccc;"
             "padding:3px 8px;text-align:left}th{background:#f0f0f0}img{max-width:100%;border:1px "
             "solid #ddd}figure{margin:1.5em 0}.rec td:last-child{font-weight:bold}"
             "code{background:#f5f5f5}</style></head><body>",
             f"<h1>Study: {e(study.title)}</h1>",
             f"<p>Study file <code>{e(study.path)}</code>; runs in <code>{e(study.out)}</code>.</p>",
             "<ul>"]
    for m in measures:
        own = os.path.join(m["dir"], "report", "index.html")
        link = (f" (<a href=\"{e(os.path.relpath(own, study.out))}\">its report</a>)"
                if os.path.isfile(own) else "")
        parts.append(f"<li><b>{e(m['label'])}</b>: <code>{e(os.path.relpath(m['dir'], study.out))}"
                     f"</code>{link}</li>")
    parts.append("</ul>")
    title, header, rows = t[0]
    parts += [f"<h2>{e(title)}</h2>", "<div class=\"rec\">", html_table(header, rows), "</div>"]
    if rec.get("most_fly_rock"):
        lab = next(m["label"] for m in measures if m["name"] == rec["most_fly_rock"])
        parts.append(f"<p>Most fly-rock (largest fragment speed): <b>{e(lab)}</b>.</p>")
    for title, header, rows in t[1:]:
        parts += [f"<h2>{e(title)}</h2>", html_table(header, rows)]
    if kuz is not None:
        kj = kuz.to_json()
        parts += ["<h2>Kuz-Ram / Swebrec yardstick of the design</h2>", html_table(
            ["quantity", "value"],
            [["x50", f"{kj['x50_m']:.3g} m"], ["uniformity index n", f"{kj['uniformity_n']:.3g}"],
             ["powder factor", f"{kj['powder_factor_kg_m3']:.3g} kg/m³"],
             ["charge per hole", f"{kj['charge_per_hole_kg']:.3g} kg"],
             ["d40 / d80 (Rosin-Rammler)", f"{kj['rosin_rammler']['d40_m']:.3g} / "
                                           f"{kj['rosin_rammler']['d80_m']:.3g} m"]]
            + ([["d40 / d80 (Swebrec)", f"{kj['swebrec']['d40_m']:.3g} / {kj['swebrec']['d80_m']:.3g} m"]]
               if kj["swebrec"] else []))]
    parts.append("<h2>Pictures</h2>")
    for p in pictures:
        parts.append(f"<figure><img src=\"{e(p)}\" alt=\"{e(p)}\"><figcaption>"
                     f"{e(CAPTIONS.get(p, p))}</figcaption></figure>")
    for name, res in analyses:
        parts.append(f"<h2>Analysis: {e(name)}</h2>")
        for f in res.get("files", []):
            if f.endswith(".png"):
                parts.append(f"<figure><img src=\"{e(f)}\" alt=\"{e(f)}\"><figcaption>{e(f)}"
                             "</figcaption></figure>")
            else:
                parts.append(f"<p><a href=\"{e(f)}\">{e(f)}</a></p>")
    if notes:
        parts += ["<h2>Notes</h2>", "<ul>"] + [f"<li>{e(n)}</li>" for n in notes] + ["</ul>"]
    parts.append("</body></html>")
    with open(os.path.join(study.out, "index.html"), "w") as f:
        f.write("\n".join(parts) + "\n")


# ----------------------------------------------------------------------------- comparing
def compare(study, variants=None, pictures=True, log=print):
    """Compares the variants' runs: writes the pictures, index.html and study.json into the
    study directory; runs the study's analyses. Returns the study.json content."""
    variants = variants or [v for v in study.variants
                            if not v.optional or os.path.isfile(os.path.join(v.dir, "summary.json"))]
    notes = []
    failures = Failures()
    for v in variants:
        if not os.path.isfile(os.path.join(v.dir, "summary.json")):
            raise StudyError(f"{v.dir}/summary.json is missing (did the {v.name} run finish?)")
        v.run = Run(v.dir, label=v.label)
        v.setup = failures.run(f"set-up of {v.name}", notes, Setup, v.run)
    out_dir = study.out
    for name in list(CAPTIONS) + ["index.html", "study.json"]:
        p = os.path.join(out_dir, name)
        if os.path.isfile(p):
            os.remove(p)
    measures = []
    for v in variants:
        m = failures.run(f"measures of {v.name}", notes, measure_variant, v, study, notes)
        if m is None:
            raise RuntimeError(f"could not measure the {v.name} run (see above)")
        measures.append(m)
    rec = recommend(measures, study)
    kuz = None
    if study.design:
        kuz = failures.run("Kuz-Ram of the design", notes, kuzram_of, study.design, variants[0].setup)
    written = []
    runs = [v.run for v in variants]
    if pictures:
        times = study.compare.get("times", [])
        failures.run("vertical displacement", notes, plot_vertical, variants, times, out_dir,
                     written, notes)
        failures.run("damage.png", notes, plot_damage, variants, times, out_dir, written, notes)
        failures.run("monitors.png", notes, plot_monitors, runs, out_dir, written)
        failures.run("monitors_vertical.png", notes, plot_monitor_vertical, variants, out_dir,
                     written)
        failures.run("fracture.png", notes, plot_fracture, runs, out_dir, written)
        failures.run("fracture_regions.png", notes, plot_fracture_regions, variants, out_dir,
                     written, notes)
        failures.run("grading.png", notes, plot_grading, runs, out_dir, written, notes, kuz)
        failures.run("launch_speeds.png", notes, plot_launch_speeds, measures, out_dir, written)
        failures.run("energy.png", notes, plot_energy, runs, out_dir, written)
        failures.run("energy_budget.png", notes, plot_energy_budget, measures, out_dir, written)
        failures.run("ppv.png", notes, plot_ppv,
                     [(m["label"], (m["ppv"] or {}).get("points") or [], (m["ppv"] or {}).get("fit"),
                       m["dimension"] == 2) for m in measures], out_dir, written)
    analyses = []
    for name in study.analyses:
        try:
            mod = __import__(f"cdemblast.analyses.{name}", fromlist=["analyse"])
        except ImportError as ex:
            raise StudyError(f"{study.path}: unknown analysis '{name}' ({ex})") from None
        res = mod.analyse(study, {v.name: v for v in variants}, pictures=pictures, log=log)
        analyses.append((name, res))
    order = list(CAPTIONS)
    pics = sorted(dict.fromkeys(written), key=lambda p: order.index(p) if p in order else 99)
    result = {"study": study.title, "file": study.path, "out_dir": out_dir,
              "variants": measures, "recommendation": rec,
              "kuz_ram": kuz.to_json() if kuz is not None else None,
              "design": study.design, "pictures": pics,
              "analyses": {n: r.get("json_file") for n, r in analyses}, "notes": notes}
    with open(os.path.join(out_dir, "study.json"), "w") as f:
        json.dump(jsonable(result), f, indent=1)
        f.write("\n")
    write_page(study, measures, rec, pics, analyses, notes, kuz)
    for g in rec["goals"]:
        log(f"study: {g['goal']}: {pick_label(g, measures)} ({g['decided_by']})")
    log(f"study: {len(pics)} pictures, index.html and study.json in {out_dir}")
    if failures.count:
        result["failures"] = failures.count
    return result


def main(argv=None):
    ap = argparse.ArgumentParser(prog="cdemblast study",
                                 description="Run the variants of a study and compare them "
                                             "(docs/study.md).")
    ap.add_argument("file", help="the study file (TOML)")
    ap.add_argument("--out", help="the study directory (default: [study] out, else runs/<file name>)")
    ap.add_argument("--threads", type=int, help="OpenMP threads of every run")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="an override of every variant's case, after [study] set (repeatable)")
    ap.add_argument("--no-run", action="store_true", help="compare the runs already in the directory")
    ap.add_argument("--variant", action="append", default=[], metavar="NAME",
                    help="run only this variant (repeatable), e.g. one per process or machine "
                         "into the same directory; the comparison is made once all are finished")
    ap.add_argument("--bin", help="the cdemblast binary (default: $CDEM_BIN, else build/bin/cdemblast)")
    ap.add_argument("--no-pictures", action="store_true", help="tables and JSON only")
    ap.add_argument("-v", "--verbose", action="store_true", help="show the runs' progress")
    args = ap.parse_args(argv)
    if args.threads is not None and args.threads < 0:
        ap.error("--threads must be >= 0")
    try:
        study = Study(args.file, args.out, args.set)
        names = [v.name for v in study.variants]
        unknown = [n for n in args.variant if n not in names]
        if unknown:
            raise StudyError(f"--variant {unknown[0]}: no such variant in {args.file} "
                             f"(expected one of {', '.join(names)})")
        if not args.no_run:
            if args.variant:
                run_study(study, find_binary(args.bin), args.threads, only=args.variant,
                          verbose=args.verbose, resume_only=True)
            else:
                run_study(study, find_binary(args.bin), args.threads, verbose=args.verbose)
        if args.variant:
            waiting = [v.name for v in study.variants if not v.optional and not v.is_done()]
            if waiting:
                print(f"cdemblast study: {', '.join(args.variant)} done; not compared yet: "
                      f"{', '.join(waiting)} not finished (then: cdemblast study {args.file} --no-run)")
                return 0
        res = compare(study, pictures=not args.no_pictures)
    except StudyError as ex:
        print(f"cdemblast study: error: {ex}", file=sys.stderr)
        return 2
    except RuntimeError as ex:
        print(f"cdemblast study: {ex}", file=sys.stderr)
        return 1
    return 1 if res.get("failures") else 0
