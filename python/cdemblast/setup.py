"""The set-up of a run as an engineer reads it: the charges (kg and J per hole and deck), the
rock they blast, the powder factor, the element sizes, the time step, the boundary conditions;
and a picture of the model (mesh, regions, holes with decks and stemming, monitors,
boundaries by type). Everything comes from the run directory: case.resolved.toml,
summary.json and the first field file.

Plane strain (2D): a hole of diameter d is a slot d wide, so a deck of length L holds
rho d L kg per metre of thickness; the rock volume is per metre too, and the powder factor,
their ratio, is a true kg/m3.
"""

from __future__ import annotations

import math

import numpy as np

from .geometry import FieldFrame, block_measures, segment_length_per_block
from .run import finite
from .vtu import VtuError

# A bound block holding at least this share of charge counts as charge, not rock (the bar
# model's rule, docs/theory.md section 7: its interfaces are unbreakable, like explosive blocks).
CHARGE_SHARE = 0.5


# ----------------------------------------------------------------------------- the case
def explosives(case):
    """{name: explosive table} of the resolved case (built-ins are written out in full)."""
    return {e.get("name"): e for e in case.get("explosive", []) if e.get("name")}


def specific_energy(expl):
    """Energy per kg (J/kg): Landau Q_w (detonation_heat); JWL E0 / rho0. None if unknown."""
    if not expl:
        return None
    if expl.get("eos", "landau") == "jwl":
        e0, rho = finite(expl.get("E0")), finite(expl.get("density"))
        return e0 / rho if e0 and rho else None
    return finite(expl.get("detonation_heat"))


def hole_axis(h):
    """(collar, end) of a hole (3-vectors) from collar + end, or collar + direction x depth."""
    collar = np.zeros(3)
    c = h.get("collar", [0, 0, 0])
    collar[:len(c[:3])] = c[:3]
    if "end" in h:
        end = np.zeros(3)
        e = h["end"]
        end[:len(e[:3])] = e[:3]
        return collar, end
    d = np.zeros(3)
    dd = h.get("direction", [0, 0, -1])
    d[:len(dd[:3])] = dd[:3]
    n = np.linalg.norm(d)
    return collar, collar + (d / n if n else d) * float(h.get("depth", 0.0))


def charges(case, dim):
    """One record per hole part, from the bottom up: decks (explosive) and stemming, with
    their end points, delay, and for decks the mass (kg; 2D kg per metre) and energy (J; 2D
    J/m). A hole's top part not covered by its entries is stemming (case_reference 3.11)."""
    ex = explosives(case)
    out = []
    for h in case.get("hole", []):
        collar, end = hole_axis(h)
        length = float(np.linalg.norm(end - collar))
        if length <= 0:
            continue
        up_axis = (collar - end) / length  # from the bottom towards the collar
        d = float(h.get("diameter", 0.0))
        area = d if dim == 2 else math.pi * d * d / 4  # slot width x 1 m in 2D
        s, deck = 0.0, 0
        for q in h.get("charge", []):
            if "stemming" in q:
                ln = float(q["stemming"])
                out.append({"hole": h.get("name"), "kind": "stemming", "length_m": ln,
                            "start": end + s * up_axis, "stop": end + (s + ln) * up_axis,
                            "diameter_m": d, "model": h.get("model", "bar")})
                s += ln
                continue
            ln = float(q.get("length", 0.0))
            deck += 1
            e = ex.get(q.get("explosive"), {})
            rho = finite(e.get("density"))
            mass = rho * area * ln if rho else None
            spec = specific_energy(e)
            out.append({"hole": h.get("name"), "kind": "deck", "deck": deck,
                        "explosive": q.get("explosive"), "length_m": ln, "diameter_m": d,
                        "delay_s": float(q.get("delay", 0.0)), "model": h.get("model", "bar"),
                        "start": end + s * up_axis, "stop": end + (s + ln) * up_axis,
                        "mass_kg": mass, "energy_j": mass * spec if mass and spec else None,
                        "density": rho, "specific_energy_j_per_kg": spec,
                        "group": q.get("group") or h.get("group")})
            s += ln
        if s < length - 1e-9:
            out.append({"hole": h.get("name"), "kind": "stemming", "length_m": length - s,
                        "start": end + s * up_axis, "stop": collar, "diameter_m": d,
                        "model": h.get("model", "bar"), "implicit": True})
    return out


def region_names(run):
    """Region names by index (the `region` cell array), or None when they cannot be known.

    summary.json `regions` when the run wrote it; else, for a generated mesh, the order the
    generator gives them (src/cdem/mesh/gmsh_generate.cpp): the main region, the filled holes'
    regions in hole order, then "ring"."""
    names = run.summary.get("regions")
    if isinstance(names, list) and all(isinstance(n, str) for n in names):
        return names
    gen = run.case.get("mesh", {}).get("generate")
    if not isinstance(gen, dict):
        return None
    order = [gen.get("region", "rock")]
    for h in gen.get("hole", []):
        r = h.get("region", "")
        if r and r not in order:
            order.append(r)
    if gen.get("shape") == "cylinder" and float(gen.get("ring_width", 0) or 0) > 0:
        order.append("ring")
    return order


def region_materials(case):
    """{region name: material table}."""
    out = {}
    for m in case.get("material", []):
        for r in m.get("regions", []):
            out[r] = m
    return out


def damping_regions(case):
    """Names of the regions that absorb waves: [[damping_zone]] regions and regions whose
    material has mass-proportional damping."""
    names = [z.get("region") for z in case.get("damping_zone", []) if z.get("region")]
    for m in case.get("material", []):
        if (finite(m.get("damping")) or 0) > 0 and not m.get("explosive"):
            names += [r for r in m.get("regions", []) if r not in names]
    return names


# ----------------------------------------------------------------------------- the model
class Setup:
    """The set-up numbers of a run (needs the first field file for volumes and sizes)."""

    def __init__(self, run):
        self.run = run
        self.notes = []
        self.dim = run.dim or 3
        self.per_metre = self.dim == 2
        self.case = run.case
        self.parts = charges(self.case, self.dim)
        self.decks = [p for p in self.parts if p["kind"] == "deck"]
        self.frame = None
        if run.fields:
            try:
                self.frame = FieldFrame(run, 0)
            except (VtuError, OSError) as e:
                self.notes.append(f"first field file unreadable: {e}")
        self.names = region_names(run)
        self.materials = region_materials(self.case)
        self.damping = damping_regions(self.case)
        self.measures = None
        self.region_of_cell = None
        if self.frame is not None:
            self._measure()

    # ---- geometry of the blocks ----
    def _measure(self):
        fr = self.frame
        m = block_measures(fr.X, fr.grid)
        self.measures = m
        reg = fr.cell("region")
        reg = np.zeros(fr.grid.ncells, int) if reg is None else np.asarray(reg, int)
        self.region_index = reg
        names = self.names
        if names is not None and reg.size and reg.max() >= len(names):
            self.notes.append("region indices beyond the known region names: names not used")
            names = self.names = None
        self.region_of_cell = (np.array(names, dtype=object)[reg] if names is not None
                               else np.array([f"region {i}" for i in reg], dtype=object))
        explosive_regions = {r for r, mat in self.materials.items() if mat.get("explosive")}
        self.explosive_cell = np.array([r in explosive_regions for r in self.region_of_cell], bool)
        self.damping_cell = np.array([r in self.damping for r in self.region_of_cell], bool)
        # The bar charges' share of each block: charge volume (diameter x length in 2D,
        # pi r0^2 x length in 3D) over the block volume.
        self.charge_volume = np.zeros(fr.grid.ncells)
        self.block_charge = []  # per bar deck: (cell ids, share) of the blocks it runs through
        for p in self.decks:
            if p["model"] != "bar":
                continue
            ln = segment_length_per_block(fr.X, fr.grid, p["start"], p["stop"])
            area = p["diameter_m"] if self.dim == 2 else math.pi * p["diameter_m"] ** 2 / 4
            vol = area * ln
            self.charge_volume += vol
            ids = np.nonzero(ln > 0)[0]
            self.block_charge.append((p, ids, vol[ids] / m["volume"][ids]))
        with np.errstate(divide="ignore", invalid="ignore"):
            self.share = np.where(m["volume"] > 0, self.charge_volume / m["volume"], 0.0)
        self.charge_cell = self.explosive_cell | (self.share >= CHARGE_SHARE)

    # ---- numbers ----
    @property
    def total_mass(self):
        m = [p["mass_kg"] for p in self.decks if p["mass_kg"] is not None]
        return sum(m) if m else None

    @property
    def total_energy(self):
        e = [p["energy_j"] for p in self.decks if p["energy_j"] is not None]
        return sum(e) if e else None

    def rock_volume(self):
        """Volume (m3; 2D m3 per metre) of the rock that counts for the powder factor: the
        blocks of non-explosive materials outside damping zones, less the bar charges' volume
        inside them."""
        if self.measures is None:
            return None
        rock = ~self.explosive_cell & ~self.damping_cell
        vol = self.measures["volume"]
        return float(np.nansum(vol[rock]) - np.sum(self.charge_volume[rock]))

    def rock_density(self):
        """Volume-weighted density (kg/m3) of the rock that counts."""
        if self.measures is None:
            return None
        rock = ~self.explosive_cell & ~self.damping_cell
        rho = np.array([finite(self.materials.get(r, {}).get("density")) or np.nan
                        for r in self.region_of_cell])
        vol = self.measures["volume"]
        ok = rock & np.isfinite(rho)
        return float(np.sum(rho[ok] * vol[ok]) / np.sum(vol[ok])) if ok.any() else None

    def powder_factor(self):
        """(kg/m3, kg/t) over the rock that counts, or (None, None)."""
        m, v, rho = self.total_mass, self.rock_volume(), self.rock_density()
        if not m or not v:
            return None, None
        k = m / v
        return k, (k / (rho / 1000.0) if rho else None)

    def element_sizes(self):
        """{'edge_min', 'edge_median', 'edge_max', 'block_size_median'} (m) over all blocks:
        the largest edge of each block, and the median characteristic size of one block
        (eq. 17), the finest fragment size the mesh can resolve."""
        if self.measures is None:
            return {}
        e = self.measures["edge"]
        e = e[np.isfinite(e)]
        s = self.measures["l_bc"]
        rock = ~self.charge_cell & ~self.damping_cell
        s = s[rock & np.isfinite(s)] if (rock & np.isfinite(s)).any() else s[np.isfinite(s)]
        if not e.size:
            return {}
        return {"edge_min_m": float(e.min()), "edge_median_m": float(np.median(e)),
                "edge_max_m": float(e.max()),
                "block_size_median_m": float(np.median(s)) if s.size else None}

    def max_charge_share(self):
        """[(deck record, largest share, number of blocks with share > 1)] per bar deck."""
        out = []
        for p, ids, share in self.block_charge:
            if share.size:
                out.append((p, float(share.max()), int(np.sum(share > 1.0 + 1e-9)), ids, share))
        return out

    def to_json(self):
        k, kt = self.powder_factor()
        return {
            "dimension": self.dim,
            "per_metre": self.per_metre,
            "charges": [{k2: (v.tolist() if isinstance(v, np.ndarray) else v)
                         for k2, v in p.items()} for p in self.parts],
            "charge_mass_kg": self.total_mass,
            "charge_energy_j": self.total_energy,
            "rock_volume_m3": self.rock_volume(),
            "rock_density_kg_m3": self.rock_density(),
            "powder_factor_kg_m3": k,
            "powder_factor_kg_t": kt,
            "element_sizes": self.element_sizes(),
            "regions": self.names,
            "damping_regions": self.damping,
        }


# ----------------------------------------------------------------------------- the picture
SIDE_NAMES = {
    "rectangle": {(0, 0): "left", (0, 1): "right", (1, 0): "bottom", (1, 1): "top"},
    "box": {(0, 0): "left", (0, 1): "right", (1, 0): "front", (1, 1): "back", (2, 0): "bottom",
            (2, 1): "top"},
    "cylinder": {(0, 0): "side", (0, 1): "side", (1, 0): "side", (1, 1): "side",
                 (2, 0): "bottom", (2, 1): "top"},
}
BC_STYLE = {  # boundary type -> (colour, line width, line style, legend)
    "fixed": ("black", 4.0, "-", "fixed"),
    "roller": ("tab:green", 4.0, "-", "roller (normal velocity 0)"),
    "non_reflecting": ("tab:blue", 4.0, (0, (3, 1.5)), "non-reflecting (absorbing)"),
    "pressure": ("tab:red", 3.0, "-", "pressure"),
    "velocity": ("tab:purple", 3.0, "-", "prescribed velocity"),
    "free": ("0.55", 1.0, ":", "free"),
}
DECK_COLORS = ["#d62728", "#ff7f0e", "#bcbd22", "#e377c2", "#8c564b"]


def boundary_types(case):
    """{face set: type} of the case's boundaries (the last one wins on a face set)."""
    return {b.get("faces"): b.get("type") for b in case.get("boundary", []) if b.get("faces")}


def plot_setup(setup, out_dir, written):
    """setup.png: the model as set up (reference configuration): blocks coloured by region with
    the mesh lines, holes with their decks and stemming, monitors, boundary conditions by type
    along the sides of generated shapes. 2D: the whole model; 3D: the vertical section through
    the model centre and the view from above (holes and monitors projected on both)."""
    from matplotlib import colors as mcolors
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch, Polygon

    from .plots import box_aspect, plt, save, set_limits, view_box
    fr = setup.frame
    if fr is None:
        return None
    run = setup.run
    names = setup.region_of_cell
    counts = {r: int(np.sum(names == r)) for r in dict.fromkeys(names)}
    regions = sorted(counts, key=lambda r: -counts[r])  # the main region gets the first colour
    palette = ["#e0dcd3", "#c7e9c0", "#dadaeb", "#fff2ae", "#d9f0f3", "#f2e6f7"]
    rcol = {r: mcolors.to_rgba(palette[i % len(palette)]) for i, r in enumerate(regions)}
    for r in regions:
        if r in setup.damping:
            rcol[r] = mcolors.to_rgba("#c6dbef")
        elif setup.materials.get(r, {}).get("explosive"):
            rcol[r] = mcolors.to_rgba("#fcbba1")
    colours = np.array([rcol[r] for r in names])
    shape = setup.case.get("mesh", {}).get("generate", {}).get("shape")
    btypes = boundary_types(setup.case)

    if setup.dim == 2:
        views = [("model (plane strain, per metre of thickness)", (0, 1), None)]
    else:
        views = [(f"section {'xyz'[fr.h2]} = {fr.section_at:.3g} m through the centre (holes "
                  "near it)",
                  (fr.h1, fr.va), "section"),
                 ("seen from above (faces looking up)", (fr.h1, fr.h2), "top")]
    boxes, polys_per_view = [], []
    for _, idx, kind in views:
        if kind is None:
            X = fr.X
            polys = []
            for ids, nodes in _lists(fr.grid):
                polys.append((X[nodes][:, :, :2], ids))
        elif kind == "section":
            ref = FieldFrame.__new__(FieldFrame)  # the section of the reference configuration
            ref.__dict__.update(fr.__dict__)
            ref.P = fr.X
            polys = ref.section()
        else:
            ref = FieldFrame.__new__(FieldFrame)
            ref.__dict__.update(fr.__dict__)
            ref.P = fr.X
            top = ref.top_faces()
            polys = [(top[0], top[1])] if top is not None else []
        polys_per_view.append(polys)
        boxes.append(view_box([polys], fr, idx) if polys else None)
    aspect = box_aspect(boxes[0]) if boxes[0] is not None else 1.0
    ncols = len(views)
    aspects = [box_aspect(b) if b is not None else 1.0 for b in boxes]
    ah = min(7.5 / aspect, 6.0) if ncols == 1 else 4.2
    widths = [ah * a for a in aspects]
    fig, axes = plt.subplots(1, ncols, squeeze=False, constrained_layout=True,
                             gridspec_kw={"width_ratios": widths},
                             figsize=(sum(widths) + 0.9 * ncols + 3.4, ah + 1.3))
    from matplotlib.collections import PolyCollection
    lo_ref, hi_ref = fr.X.min(0), fr.X.max(0)
    handles = {}
    for k, ((title, idx, kind), polys, box) in enumerate(zip(views, polys_per_view, boxes)):
        ax = axes[0, k]
        for verts, ids in polys:
            ax.add_collection(PolyCollection(verts, facecolors=colours[ids],
                                             edgecolors=(0.3, 0.3, 0.3, 0.6), linewidths=0.25))
        # boundaries along the sides of generated shapes
        sides = SIDE_NAMES.get(shape, {})
        ia, ib = idx
        for axis, draw_at in ((ia, "v"), (ib, "h")):
            for side in (0, 1):
                name = sides.get((axis, side))
                if name is None or (kind == "top" and axis == fr.va):
                    continue
                kind_bc = btypes.get(name, "free")
                col, lw, ls, lab = BC_STYLE.get(kind_bc, ("tab:gray", 3.0, "-", kind_bc))
                level = (lo_ref if side == 0 else hi_ref)[axis]
                other = ib if draw_at == "v" else ia
                span = (lo_ref[other], hi_ref[other])
                xy = ([level, level], span) if draw_at == "v" else (span, [level, level])
                if setup.dim == 3 and kind == "section" and axis == fr.va:
                    pass
                ax.plot(*xy, color=col, lw=lw, ls=ls, solid_capstyle="butt", zorder=4)
                handles.setdefault(lab, Line2D([], [], color=col, lw=lw, ls=ls, label=lab))
        # holes: decks and stemming along the axis (the collar: the last part's top)
        hole_top = {}
        for p in setup.parts:
            hole_top[p["hole"]] = p["stop"]
        def near_plane(part):
            """A hole part is drawn on the section when its axis is near the plane."""
            mid = 0.5 * (np.asarray(part["start"]) + np.asarray(part["stop"]))
            return abs(mid[fr.h2] - fr.section_at) <= max(part["diameter_m"],
                                                         0.02 * float(np.max(hi_ref - lo_ref)))

        if kind == "section" or (kind is None and len(setup.decks) > 3):
            for h, c in hole_top.items():
                if kind == "section" and not any(near_plane(q) for q in setup.parts
                                                 if q["hole"] == h):
                    continue
                ax.annotate(h, np.asarray(c)[[ia, ib]], textcoords="offset points",
                            xytext=(0, 4), ha="center", fontsize=7.5, zorder=7)
        deck_i = 0
        for p in setup.parts:
            a, b = np.asarray(p["start"]), np.asarray(p["stop"])
            if p["kind"] == "deck":
                col = DECK_COLORS[deck_i % len(DECK_COLORS)] if p.get("deck") else "red"
                deck_i += 1
                face, hatch, lab = col, None, "charge deck"
            else:
                face, hatch, lab = (0.55, 0.55, 0.55, 1.0), "....", "stemming"
            d = p["diameter_m"]
            ext = float(np.max(hi_ref - lo_ref))
            if kind == "top":
                if np.allclose(p["stop"], hole_top.get(p["hole"], p["stop"])):
                    c = np.asarray(p["stop"])[[ia, ib]]
                    ax.add_patch(plt.Circle(c, max(d / 2, 0.012 * ext), facecolor="white",
                                            edgecolor="black", lw=1.0, zorder=5))
                    ax.annotate(p["hole"], c, textcoords="offset points", xytext=(5, -10),
                                fontsize=7.5, zorder=7)
                continue
            if kind == "section" and not near_plane(p):
                continue
            e = (b - a)[[ia, ib]]
            ln = np.linalg.norm(e)
            if ln == 0:
                continue
            nrm = np.array([-e[1], e[0]]) / ln * max(d / 2, 0.004 * ext)
            pa, pb = a[[ia, ib]], b[[ia, ib]]
            quad = np.array([pa + nrm, pb + nrm, pb - nrm, pa - nrm])
            ax.add_patch(Polygon(quad, closed=True, facecolor=face, edgecolor="black", lw=0.6,
                                 hatch=hatch, zorder=5))
            if p["kind"] == "deck" and kind != "top" and len(setup.decks) <= 3:
                unit = "kg/m" if setup.per_metre else "kg"
                mass = f"{p['mass_kg']:.3g} {unit}" if p.get("mass_kg") else "?"
                ax.annotate(f"{p['hole']} deck {p['deck']}: {mass} {p['explosive']}, "
                            f"t0 = {p['delay_s'] * 1e3:g} ms", 0.5 * (pa + pb),
                            textcoords="offset points", xytext=(-8, 0), ha="right", va="center",
                            fontsize=7, zorder=7,
                            bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8))
            if p["kind"] == "deck":
                handles.setdefault("deck", Patch(facecolor=DECK_COLORS[0], edgecolor="black",
                                                 label="charge deck (colour per deck)"))
            else:
                handles.setdefault("stemming", Patch(facecolor=(0.55, 0.55, 0.55), edgecolor="black",
                                                     hatch="....", label="stemming"))
            del lab
        # monitors
        for i, (n, pt) in enumerate(run.monitor_points.items()):
            if not isinstance(pt, list):
                continue
            q = np.zeros(3)
            q[:len(pt[:3])] = pt[:3]
            ax.plot([q[ia]], [q[ib]], marker="v", color="black", ms=6, zorder=6, ls="none")
            ax.annotate(n, (q[ia], q[ib]), textcoords="offset points",
                        xytext=(4, 5 if i % 2 == 0 else -11), fontsize=7.5, zorder=6)
            handles.setdefault("monitor", Line2D([], [], marker="v", color="black", ls="none",
                                                 label="monitor"))
        if box is not None:
            set_limits(ax, box, f"{'xyz'[ia]} (m)", f"{'xyz'[ib]} (m)",
                       flip=(kind == "section" and fr.s < 0))
        ax.set_title(title, fontsize=10)
    for r in regions:
        tag = (" (damping zone)" if r in setup.damping else
               " (explosive)" if setup.materials.get(r, {}).get("explosive") else "")
        handles.setdefault("region " + r, Patch(facecolor=rcol[r], edgecolor="0.3",
                                                label=f"region {r}{tag}"))
    axes[0, -1].legend(handles=list(handles.values()), loc="upper left", fontsize=8,
                       bbox_to_anchor=(1.02, 1.0), borderaxespad=0, title="set-up",
                       title_fontsize=9)
    k, kt = setup.powder_factor()
    m = setup.total_mass
    unit = "kg/m" if setup.per_metre else "kg"
    charge = f"charge {m:.3g} {unit}" if m else "no charge"
    pf = f", powder factor {k:.3g} kg/m³" + (f" ({kt:.3g} kg/t)" if kt else "") if k else ""
    fig.suptitle(f"Set-up: {run.label} ({len(fr.grid.types)} blocks; {charge}{pf})")
    return save(fig, out_dir, "setup.png", written)


def _lists(grid):
    from .geometry import cell_node_lists
    return cell_node_lists(grid)
