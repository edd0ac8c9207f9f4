"""SPEC 5.2 (examples/multihole_3d): the efficiency of the bar explosive model against the solid
one on a 3D multi-hole face, and the damage around each hole. A study analysis (docs/study.md,
docs/multihole_3d.md) over the variants `bar`, `solid` and, when present, `bar_fine`. Writes
into the study directory:

  * speedup.json: solid_wall_s, bar_wall_s, solid_blocks, bar_blocks,
    speedup = solid_wall_s / bar_wall_s, the same ratio for CPU time and for the block-steps
    (the load-independent work ratio), each run's dt, steps and fracture degree, and per hole
    the extents of the cases and their differences ("damage": the last output time,
    "damage_at_outputs": every output time);
  * damage_rose.png (one polar plot per hole, the cases overlaid, laid out as the holes are on
    the face; damage_rose_<t>ms.png for the earlier output times) and damage_section.png (the
    damage of the blocks cut by the mid-charge plane, a row per output time, the cases side by
    side);

and prints the cost table and the damage-extent tables. The wall and CPU times come from the
study's timings.json (the bar case is run `repeat` times and its median counts).

Damage extent. A rock block counts as damaged when its damage (broken fraction of its
interface area) is above 0.5, or when it is detached from the main rock mass (its
fragment_id is not 0, the largest fragment). Blocks of the hole regions (the explosive blocks
of the solid case) are left out. Along a ray from the hole axis in direction theta (measured
around the axis from e1, the global x axis projected on the plane normal to the hole, towards
e2 = e1 x axis: for a hole drilled along +y this is from +x towards +z, i.e. counter-clockwise
as seen from the tunnel) the blocks are sampled every 5 mm, from the hole wall out to
max_radius (0.45 m: less than the 0.5 m hole spacing), in the reference (undeformed)
configuration. The extent is the distance from the axis to the outer end of the damaged run
that starts at the wall (undamaged gaps up to 2 cm are bridged; 0 when the rock at the wall is
not damaged; max_radius when the damage reaches the end of the ray). It is averaged over 5
planes normal to the axis spread over a slab of thickness `slab` (0.1 m) centred at
mid-charge depth. Options: [analysis.hole_damage] slab and max_radius in the study file.
"""

from __future__ import annotations

import json
import math
import os

import numpy as np
import matplotlib
from matplotlib.collections import PolyCollection

from ..plots import plt
from ..vtu import read_pvd, read_vtu

CASES = ("bar", "solid", "bar_fine")  # bar_fine: optional
BAR_CASES = ("bar", "bar_fine")
COLORS = {"bar": "tab:blue", "solid": "tab:red", "bar_fine": "tab:green"}
STYLES = {"bar": "-o", "solid": "--s", "bar_fine": ":^"}
LABELS = {"bar": "bar model", "solid": "solid model", "bar_fine": "bar model, solid's mesh"}
ANGLES = list(range(0, 360, 30))
DAMAGED = 0.5      # damage above this counts as damaged
STEP = 0.005       # sampling step along a ray, m
GAP = 0.02         # undamaged gaps up to this long are bridged, m
PLANES = 5         # planes sampled across the slab
FIRED_BEFORE = 2e-5  # the means over holes count the holes fired at least this long before, s


class Frame:
    """One field output: damage, and which rock blocks are damaged or detached."""

    def __init__(self, t, path):
        self.time = t
        g = read_vtu(path)
        pts = np.asarray(g.points, float)
        u = g.point_array("displacement")
        self.ref = pts - u if u is not None else pts  # reference (undeformed) configuration
        if g.cells_of_type(10).size != g.ncells:
            raise RuntimeError(f"speedup: {path}: expected a tetrahedral (3D) mesh")
        self.tet = g.cell_nodes(10)
        self.damage = np.asarray(g.cell_array("damage"), float)
        reg = g.cell_array("region")
        reg = np.zeros(g.ncells, int) if reg is None else np.asarray(reg, int)
        vals, counts = np.unique(reg, return_counts=True)
        self.rock = reg == vals[np.argmax(counts)]  # the most common region is the rock
        frag = g.cell_array("fragment_id")
        detached = np.zeros(g.ncells, bool) if frag is None else np.asarray(frag) != 0
        self.damaged = self.rock & ((self.damage > DAMAGED) | detached)
        self.detached = self.rock & detached


class Run:
    def __init__(self, name, run, log=print):
        self.name = name
        self.dir = run_dir = run.dir
        for f in ("summary.json", "case.resolved.toml", "fields.pvd"):
            if not os.path.isfile(os.path.join(run_dir, f)):
                raise RuntimeError(f"speedup: {run_dir}/{f} is missing (did the {name} run finish?)")
        self.summary = run.summary
        if self.summary.get("status") not in (None, "finished"):
            log(f"speedup: warning: the {name} run has status '{self.summary.get('status')}'"
                f": {self.summary.get('diagnosis', '')}")
        self.case = run.case
        fields = read_pvd(os.path.join(run_dir, "fields.pvd"))
        if not fields:
            raise RuntimeError(f"speedup: {run_dir}/fields.pvd lists no field output")
        self.frames = [Frame(t, path) for t, path in fields]
        f = self.frames[0]  # the geometry (reference configuration) is the same in every frame
        self.ref, self.tet, self.rock = f.ref, f.tet, f.rock
        v = self.ref[self.tet]  # (n, 4, 3)
        self.v0 = v[:, 0]
        m = np.stack([v[:, 1] - v[:, 0], v[:, 2] - v[:, 0], v[:, 3] - v[:, 0]], axis=2)
        self.minv = np.linalg.inv(m)  # barycentric coordinates: minv @ (p - v0)
        self.vmin = v.min(axis=1)
        self.vmax = v.max(axis=1)
        self.use(-1)

    def use(self, k):
        """Select field output k (its time, damage, damaged and detached flags)."""
        f = self.frames[k]
        self.time, self.damage = f.time, f.damage
        self.damaged, self.detached = f.damaged, f.detached

    def locate(self, p, cand):
        """Index of the tetrahedron (among cand) holding each point of p (m, 3); -1 if none."""
        d = p[:, None, :] - self.v0[cand][None, :, :]                 # (m, c, 3)
        lam = np.einsum("cij,mcj->mci", self.minv[cand], d)           # (m, c, 3)
        inside = (lam.min(axis=2) >= -1e-9) & (lam.sum(axis=2) <= 1 + 1e-9)
        hit = inside.any(axis=1)
        first = np.argmax(inside, axis=1)
        return np.where(hit, cand[first], -1)


def holes_of(case):
    """[(name, collar, end, radius, s0, s1)]: s0..s1 the charged part, distances from the collar."""
    out = []
    for h in case.get("hole", []):
        collar = np.array(h["collar"], float)
        end = np.array(h["end"], float)
        length = float(np.linalg.norm(end - collar))
        s, lo, hi = 0.0, None, None  # s: distance from the bottom, entries from the bottom up
        for q in h.get("charge", []):
            if "stemming" in q:
                s += float(q["stemming"])
                continue
            ln = float(q["length"])
            lo = s if lo is None else min(lo, s)
            hi = s + ln if hi is None else max(hi, s + ln)
            s += ln
        if lo is None:
            lo, hi = 0.0, length
        out.append((h["name"], collar, end, 0.5 * float(h["diameter"]), length - hi, length - lo))
    return out


def hole_delays(case):
    """{hole name: the earliest delay of its charges} (s)."""
    return {h["name"]: min((float(q.get("delay", 0.0)) for q in h.get("charge", [])
                            if "explosive" in q), default=0.0) for h in case.get("hole", [])}


def frame(axis):
    """e1 (global x projected on the plane normal to axis, or y when axis is along x), e2."""
    for g in (np.array([1.0, 0, 0]), np.array([0, 1.0, 0])):
        e1 = g - np.dot(g, axis) * axis
        if np.linalg.norm(e1) > 1e-6:
            e1 /= np.linalg.norm(e1)
            return e1, np.cross(e1, axis)
    raise ValueError("bad axis")


def ray_extent(flags, radii):
    """Outer end of the damaged run starting at the wall; flags: 1 damaged, 0 not, -1 no rock."""
    extent, last, gap_start = 0.0, None, None
    for f, r in zip(flags, radii):
        if f < 0:
            continue  # not rock (explosive block) or outside the mesh: neither
        if f == 1:
            if last is None and gap_start is not None and r - gap_start > GAP:
                return 0.0  # undamaged rock at the wall
            last, gap_start = r, None
            extent = r
        else:
            if gap_start is None:
                gap_start = r
            if r - gap_start > GAP:
                break
    return extent + 0.5 * STEP if last is not None else 0.0


def damage_extents(run, holes, slab, rmax):
    """{hole: [extent at each angle]} (m, from the hole axis), averaged over the slab planes."""
    res = {}
    for name, collar, end, r0, s0, s1 in holes:
        axis = (end - collar) / np.linalg.norm(end - collar)
        e1, e2 = frame(axis)
        smid = 0.5 * (s0 + s1)
        offs = np.linspace(-0.5 * slab, 0.5 * slab, PLANES) if PLANES > 1 else np.zeros(1)
        radii = np.arange(r0 + 0.5 * STEP, rmax + 1e-12, STEP)
        # Candidate tetrahedra: bounding boxes touching the sampled cylinder.
        c = collar + smid * axis
        half = np.abs(axis) * (0.5 * slab + 1e-6) + np.sqrt(np.clip(1 - axis ** 2, 0, 1)) * rmax
        cand = np.nonzero(np.all(run.vmax >= c - half - 1e-6, axis=1)
                          & np.all(run.vmin <= c + half + 1e-6, axis=1))[0]
        ext = np.zeros((len(offs), len(ANGLES)))
        for i, o in enumerate(offs):
            centre = collar + (smid + o) * axis
            for j, a in enumerate(ANGLES):
                d = math.cos(math.radians(a)) * e1 + math.sin(math.radians(a)) * e2
                p = centre[None, :] + radii[:, None] * d[None, :]
                lo, hi = p.min(axis=0) - 1e-9, p.max(axis=0) + 1e-9
                near = cand[np.all(run.vmax[cand] >= lo, axis=1)
                            & np.all(run.vmin[cand] <= hi, axis=1)]
                t = run.locate(p, near)
                flags = np.where(t < 0, -1, np.where(run.rock[t], run.damaged[t].astype(int), -1))
                ext[i, j] = ray_extent(flags, radii)
        res[name] = ext.mean(axis=0)
    return res


# ----------------------------------------------------------------------------- pictures
def rose_plot(holes, ext, series, path, time_ms, ray_max):
    """One polar plot per hole, placed on a grid as the holes are on the face."""
    pos = []
    for name, collar, end, r0, s0, s1 in holes:
        axis = (end - collar) / np.linalg.norm(end - collar)
        e1, e2 = frame(axis)
        pos.append((round(float(np.dot(collar, e1)), 6), round(float(np.dot(collar, e2)), 6)))
    xs = sorted(set(p[0] for p in pos))
    ys = sorted(set(p[1] for p in pos), reverse=True)
    grid = len(xs) <= 4 and len(ys) <= 4 and len(set(pos)) == len(pos)
    if grid:
        nr, nc = len(ys), len(xs)
    else:
        nc = min(3, len(holes))
        nr = math.ceil(len(holes) / nc)
    fig = plt.figure(figsize=(4.1 * nc, 3.6 * nr + 0.6))
    rmax = max(1e-3, max(float(np.max(ext[c][h[0]])) for c in series for h in holes))
    th = np.radians(ANGLES + [ANGLES[0]])
    for k, (name, _c, _e, r0, _s0, _s1) in enumerate(holes):
        idx = (ys.index(pos[k][1]) * nc + xs.index(pos[k][0]) + 1) if grid else k + 1
        ax = fig.add_subplot(nr, nc, idx, projection="polar")
        for c in series:
            r = list(ext[c][name]) + [ext[c][name][0]]
            ax.plot(th, r, STYLES[c], color=COLORS[c], ms=3.5, lw=1.6, label=LABELS[c])
            ax.fill(th, r, color=COLORS[c], alpha=0.08)
        ax.plot(np.linspace(0, 2 * np.pi, 73), np.full(73, r0), color="k", lw=1.0)
        ax.plot(np.linspace(0, 2 * np.pi, 73), np.full(73, ray_max), ":", color="0.4", lw=1.0,
                label="end of the rays")
        ax.set_ylim(0, max(rmax, ray_max) * 1.08)
        ax.set_rlabel_position(195)
        ax.set_thetagrids(ANGLES, [f"{a}" for a in ANGLES], fontsize=7)
        ax.tick_params(axis="y", labelsize=6.5, labelcolor="0.35")
        means = ", ".join(f"{c.replace('_', ' ')} {np.mean(ext[c][name]):.3f}" for c in series)
        ax.set_title(f"hole '{name}'\nmean extent (m): {means}", fontsize=8.5)
    h, l = fig.axes[0].get_legend_handles_labels()
    fig.legend(h, l, loc="lower center", ncol=len(l), fontsize=9)
    fig.suptitle(f"Radial extent of damaged rock (m from the hole axis) at mid-charge depth, "
                 f"t = {time_ms:.2f} ms\n(angles around each hole axis as seen from the tunnel; "
                 "black circle: the hole wall; dotted: the end of the sampled rays)", fontsize=10)
    fig.tight_layout(rect=(0, 0.05, 1, 0.95))
    fig.savefig(path, dpi=120)
    plt.close(fig)


def section_polygons(run, point, normal, e1, e2):
    """Polygons (in e1, e2 coordinates) of the tetrahedra cut by the plane, and their ids."""
    d = (run.ref[run.tet] - point) @ normal  # (n, 4)
    cut = np.nonzero((d.min(axis=1) < 0) & (d.max(axis=1) > 0))[0]
    polys, ids = [], []
    edges = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    for t in cut:
        v = run.ref[run.tet[t]]
        dd = d[t]
        pts = []
        for a, b in edges:
            if (dd[a] < 0) != (dd[b] < 0):
                p = v[a] + (v[b] - v[a]) * (dd[a] / (dd[a] - dd[b]))
                pts.append((np.dot(p, e1), np.dot(p, e2)))
        if len(pts) < 3:
            continue
        pts = np.array(pts)
        cen = pts.mean(axis=0)
        pts = pts[np.argsort(np.arctan2(pts[:, 1] - cen[1], pts[:, 0] - cen[0]))]
        polys.append(pts)
        ids.append(t)
    return polys, np.array(ids, int)


def section_plot(runs, series, holes, frames, path):
    """Damage of the blocks cut by the mid-charge plane: a row per output time (frames: one
    {case: output index} per row), the cases side by side."""
    name, collar, end, r0, s0, s1 = holes[0]
    axis = (end - collar) / np.linalg.norm(end - collar)
    e1, e2 = frame(axis)
    point = collar + 0.5 * (s0 + s1) * axis
    cuts = {c: section_polygons(runs[c], point, axis, e1, e2) for c in series}
    nr, nc = len(frames), len(series)
    fig, axs = plt.subplots(nr, nc, figsize=(5.4 * nc + 0.6, 5.0 * nr + 0.8), squeeze=False,
                            constrained_layout=True)
    cmap = plt.get_cmap("YlOrRd")
    for row, pick in enumerate(frames):
        for ax, c in zip(axs[row], series):
            run = runs[c]
            run.use(pick[c])
            polys, ids = cuts[c]
            val = np.where(run.detached[ids], 1.0, run.damage[ids])
            col = [cmap(0.1 + 0.9 * v) if run.rock[i] else (0.45, 0.65, 1.0, 1.0)
                   for v, i in zip(val, ids)]
            ax.add_collection(PolyCollection(polys, facecolors=col, edgecolors=(0, 0, 0, 0.3),
                                             linewidths=0.15))
            for _n, hc, _e, hr, *_x in holes:
                ax.add_patch(plt.Circle((np.dot(hc, e1), np.dot(hc, e2)), hr, fill=False,
                                        color="k", lw=0.8))
            ax.autoscale_view()
            ax.set_aspect("equal")
            ax.grid(False)
            ax.set_title(f"{LABELS[c]}, t = {run.time * 1e3:.2f} ms ({run.summary.get('blocks')} "
                         "blocks)", fontsize=10)
            ax.set_xlabel("along e1 = x (m)")
            ax.set_ylabel("along e2 (m)")
    sm = plt.cm.ScalarMappable(cmap=matplotlib.colors.ListedColormap(cmap(np.linspace(0.1, 1, 64))),
                               norm=plt.Normalize(0, 1))
    fig.colorbar(sm, ax=axs, shrink=0.5,
                 label="block damage (detached blocks: 1); blue: blocks of the hole region")
    fig.suptitle("Damage of the blocks cut by the plane at mid-charge depth "
                 f"({0.5 * (s0 + s1):.3f} m from the collar), seen from the tunnel")
    fig.savefig(path, dpi=100)
    plt.close(fig)


def extents_record(ext, series, holes, delays, slab, rmax, t):
    """The JSON record of the extents at one output time (bar and bar_fine against solid). The
    means over the holes count the holes fired at least FIRED_BEFORE before (all holes when
    none is)."""
    rec = {
        "time_s": t,
        "definition": (f"radial extent (m, from the hole axis) of the damaged rock (damage > "
                       f"{DAMAGED} or detached) along each direction, contiguous from the hole "
                       f"wall (gaps <= {GAP} m bridged), mean of {PLANES} planes over a "
                       f"{slab} m slab at mid-charge depth, sampled every {STEP} m up to "
                       f"{rmax} m; angles from e1 (global x projected) towards e2 = e1 x axis"),
        "angles_deg": ANGLES,
        "holes": {},
    }
    fired = ([h[0] for h in holes if delays.get(h[0], 0.0) < t - FIRED_BEFORE]
             or [h[0] for h in holes])
    rec["holes_fired"] = fired
    every = {c: [] for c in series}
    for name, *_x in holes:
        h = {"delay_s": delays.get(name, 0.0)}
        for c in series:
            v = np.asarray(ext[c][name])
            if name in fired:
                every[c] += list(v)
            h[f"{c}_m"] = [round(float(x), 4) for x in v]
            h[f"{c}_mean_m"] = round(float(v.mean()), 4)
            h[f"{c}_saturated_directions"] = int(np.sum(v >= rmax - 1e-9))
        s = np.asarray(ext["solid"][name])
        for c in series:
            if c == "solid":
                continue
            b = np.asarray(ext[c][name])
            key = "difference_m" if c == "bar" else f"{c}_difference_m"
            h[key] = [round(float(x - y), 4) for x, y in zip(b, s)]
            h[key.replace("difference_m", "mean_abs_difference_m")] = round(
                float(np.mean(np.abs(b - s))), 4)
        rec["holes"][name] = h
    s = np.array(every["solid"])
    rec["solid_mean_m"] = round(float(s.mean()), 4)
    rec["directions"] = int(s.size)
    for c in series:
        if c == "solid":
            continue
        b = np.array(every[c])
        rec[f"{c}_mean_m"] = round(float(b.mean()), 4)
        pre = "" if c == "bar" else f"{c}_"
        rec[f"{pre}mean_abs_difference_m"] = round(float(np.mean(np.abs(b - s))), 4)
        rec[f"{pre}mean_relative_difference_pct"] = (
            round(float((b.mean() - s.mean()) / s.mean() * 100), 1) if s.mean() > 0 else None)
        rec[f"{pre}directions_within_0.05m"] = int(np.sum(np.abs(b - s) <= 0.05))
    return rec


def print_extents(rec, series, holes, rmax, print=print):
    print(f"\ndamage extent (m from the hole axis) at t = {rec['time_s'] * 1e3:.2f} ms, "
          f"mid-charge slab ({rmax:g}: the end of the ray); differences: case - solid")
    print(f"{'hole':8s}{'':17s}" + "".join(f"{a:>7d}" for a in ANGLES) + f"{'mean':>8s}")
    for name, *_x in holes:
        h = rec["holes"][name]
        if name not in rec["holes_fired"]:
            print(f"{name:8s}(fires at {h['delay_s'] * 1e3:g} ms: left out of the means)")
            continue
        first = True
        for c in series:
            print(f"{name if first else '':8s}{c:17s}" + "".join(f"{x:7.3f}" for x in h[f"{c}_m"])
                  + f"{h[f'{c}_mean_m']:8.3f}")
            first = False
        for c in series:
            if c == "solid":
                continue
            key = "difference_m" if c == "bar" else f"{c}_difference_m"
            d = h[key]
            print(f"{'':8s}{(c + ' - solid'):17s}" + "".join(f"{x:7.3f}" for x in d)
                  + f"{float(np.mean(d)):8.3f}")
    for c in series:
        if c == "solid":
            continue
        pre = "" if c == "bar" else f"{c}_"
        print(f"fired holes, {c}: mean extent {rec[f'{c}_mean_m']:.3f} m against solid "
              f"{rec['solid_mean_m']:.3f} m ({rec[f'{pre}mean_relative_difference_pct']} %), "
              f"mean |{c} - solid| {rec[f'{pre}mean_abs_difference_m']:.3f} m; "
              f"{rec[f'{pre}directions_within_0.05m']} of {rec['directions']} directions "
              "within 0.05 m")




def analyse(study, variants, pictures=True, log=print):
    """The study analysis: needs the variants `bar` and `solid` (and uses `bar_fine` when it
    ran)."""
    for c in ("bar", "solid"):
        if c not in variants:
            raise RuntimeError(f"the hole_damage analysis needs a variant named '{c}'")
    opts = study.analysis.get("hole_damage", {})
    slab = float(opts.get("slab", 0.1))
    rmax = float(opts.get("max_radius", 0.45))
    out = study.out
    lines = []

    def print(*a):  # noqa: A001 - the tables are collected and logged once
        lines.append(" ".join(str(x) for x in a))

    timing = {}
    tpath = os.path.join(out, "timings.json")
    if os.path.isfile(tpath):
        with open(tpath) as f:
            timing = json.load(f)
    series = [c for c in CASES if c in variants]
    runs = {c: Run(c, variants[c].run, log) for c in series}
    holes = holes_of(runs["bar"].case)
    for c in series:
        if [h[0] for h in holes] != [h[0] for h in holes_of(runs[c].case)]:
            raise RuntimeError(f"speedup: the {c} case does not have the same holes as the bar case")
    # Field outputs after t = 0 present in every run (each run writes at the first step at or
    # after an output time: match within 2 steps of the largest dt).
    tol = 2 * max(runs[c].summary.get("dt", 0.0) for c in series)
    times = {c: np.array([f.time for f in runs[c].frames]) for c in series}
    frames = []
    for i, t in enumerate(times["bar"]):
        if t <= 0:
            continue
        pick = {"bar": i}
        for c in series[1:]:
            j = int(np.argmin(np.abs(times[c] - t)))
            if abs(times[c][j] - t) <= tol:
                pick[c] = j
        if len(pick) == len(series):
            frames.append(pick)
    if not frames:
        frames = [{c: len(times[c]) - 1 for c in series}]
    records = []
    for pick in frames:
        for c in series:
            runs[c].use(pick[c])
        ext = {c: damage_extents(runs[c], holes, slab, rmax) for c in series}
        records.append((ext, extents_record(ext, series, holes, hole_delays(runs["bar"].case),
                                            slab, rmax, runs["bar"].time)))

    sm = {c: runs[c].summary for c in series}
    # Wall time: the median of this script's runs of the case (timings.json) when it made the
    # run now in the directory, else the run's summary.json. CPU time: only from timings.json.
    wall, cpu = {}, {}
    for c in series:
        t = timing.get(c, {})
        w = t.get("wall_s") or []
        ours = bool(w) and abs(w[-1] - sm[c]["wall_time_s"]) < 1e-6  # the run in the directory
        wall[c] = float(np.median(w)) if ours else sm[c]["wall_time_s"]
        cpu[c] = float(np.median(t["cpu_s"])) if ours else None
    sb, ss = sm["bar"], sm["solid"]
    work = {c: sm[c]["blocks"] * sm[c]["steps"] for c in series}
    ratio = lambda a, b: (a / b) if (a is not None and b) else None  # noqa: E731
    res = {
        "solid_wall_s": wall["solid"],
        "bar_wall_s": wall["bar"],
        "solid_blocks": ss["blocks"],
        "bar_blocks": sb["blocks"],
        "speedup": wall["solid"] / wall["bar"],
        "block_ratio": ss["blocks"] / sb["blocks"],
        "dt_ratio": sb["dt"] / ss["dt"],
        "solid_cpu_s": cpu.get("solid"),
        "bar_cpu_s": cpu.get("bar"),
        "speedup_cpu": ratio(cpu.get("solid"), cpu.get("bar")),
        "solid_loop_s": ss.get("loop_time_s"),
        "bar_loop_s": sb.get("loop_time_s"),
        "speedup_loop": ratio(ss.get("loop_time_s"), sb.get("loop_time_s")),
        "solid_block_steps": work["solid"],
        "bar_block_steps": work["bar"],
        "work_ratio": work["solid"] / work["bar"],
        "threads": sb.get("threads"),
        "timing_note": ("wall times: median over this script's runs of each case (the bar case "
                        "is run --bar-repeat times), else summary.json; CPU times (user + system "
                        "of the cdemblast process, median) only for runs this script made"),
        "timings": {c: timing.get(c) for c in series},
    }
    for c in series:
        s = sm[c]
        res[f"{c}_wall_s"] = wall[c]
        for k in ("blocks", "wall_time_s", "loop_time_s", "dt", "dt_limit", "steps",
                  "spring_points", "fracture_degree", "energy_error", "explosive_work",
                  "kinetic_energy", "status"):
            res[f"{c}_{k}"] = s.get(k)
        res[f"{c}_cpu_s"] = cpu.get(c)
    bar_a = [h.get("attenuation_exponent") for h in runs["bar"].case.get("hole", [])]
    res["bar_attenuation_exponents"] = bar_a
    res["damage"] = records[-1][1]
    res["damage_at_outputs"] = [r for _e, r in records]

    # ---- tables ----
    print()
    print(f"{'':22s}" + "".join(f"{c:>14s}" for c in series) + "".join(
        f"{c + '/bar':>16s}" for c in series[1:]))
    rows = [("blocks", "blocks", "{:.0f}"), ("dt (s)", "dt", "{:.3g}"),
            ("steps", "steps", "{:.0f}"),
            ("block-steps", None, "{:.3g}"), ("wall time (s)", "wall", "{:.1f}"),
            ("loop time (s)", "loop_time_s", "{:.1f}"), ("CPU time (s)", "cpu", "{:.1f}"),
            ("explosive work (J)", "explosive_work", "{:.3g}"),
            ("fracture degree", "fracture_degree", "{:.3f}")]
    for label, key, f in rows:
        vals = [work[c] if key is None else cpu.get(c) if key == "cpu" else wall[c]
                if key == "wall" else sm[c].get(key) for c in series]
        if vals[0] is None:
            continue
        print(f"{label:22s}" + "".join(f"{'-' if v is None else f.format(v):>14s}" for v in vals)
              + "".join(f"{'-' if v is None or not vals[0] else f'{v / vals[0]:.2f}':>16s}"
                        for v in vals[1:]))
    print(f"\nspeed-up of the bar model (solid wall time / bar wall time): {res['speedup']:.1f}x"
          + (f"   (CPU time: {res['speedup_cpu']:.1f}x" if res.get("speedup_cpu") else "   (")
          + f"  work, blocks x steps: {res['work_ratio']:.1f}x)")
    print(f"bar attenuation exponents: {bar_a}")
    for _e, rec in records:
        print_extents(rec, series, holes, rmax, print)

    with open(os.path.join(out, "speedup.json"), "w") as f:
        json.dump(res, f, indent=2)
    pngs = []
    if pictures:
        for k, (ext, rec) in enumerate(records):
            name = ("damage_rose.png" if k == len(records) - 1
                    else f"damage_rose_{rec['time_s'] * 1e3:.2f}ms.png")
            rose_plot(holes, ext, series, os.path.join(out, name), rec["time_s"] * 1e3, rmax)
            pngs.append(name)
        section_plot(runs, series, holes, frames, os.path.join(out, "damage_section.png"))
        pngs.append("damage_section.png")
    log("\n".join(lines))
    log(f"\nspeedup: wrote {out}/speedup.json" + (", " + ", ".join(pngs) if pngs else ""))
    return {"json_file": "speedup.json", "files": ["speedup.json"] + pngs, "result": res}

