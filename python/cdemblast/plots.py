"""The pictures shared by the run report and the studies: time histories (monitors,
fracture degree, energy), grading curves and field pictures (2D maps, 3D top view and
section). Each plot function saves a PNG into an output directory and appends its name to a
`written` list. docs/report.md describes every picture.
"""

from __future__ import annotations

import math
import os

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
from matplotlib import colors as mcolors  # noqa: E402
from matplotlib.collections import LineCollection, PolyCollection  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

from .geometry import AXIS, FieldFrame  # noqa: E402
from .run import read_table  # noqa: E402
from .vtu import VTK_QUAD, VTK_TETRA, VTK_TRIANGLE, VtuError  # noqa: E402

DPI = 150
MAX_FRAMES = 6
RUN_STYLES = ["-", "--", ":", "-.", (0, (5, 1, 1, 1, 1, 1)), (0, (8, 2))]
DAMAGE_CMAP = "YlOrRd"
VM_CMAP = "YlGnBu"
CRACK_COLOR = "black"

plt.rcParams.update({
    "font.size": 10,
    "axes.titlesize": 11,
    "axes.labelsize": 10,
    "legend.fontsize": 9,
    "xtick.labelsize": 9,
    "ytick.labelsize": 9,
    "figure.titlesize": 12,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "savefig.dpi": DPI,
})


def time_scale(tmax):
    """(factor, unit) for time axes: ms unless the run lasts 10 s or more."""
    return (1.0, "s") if tmax >= 10 else (1e3, "ms")


def energy_scale(vmax):
    if vmax >= 1e7:
        return 1e-6, "MJ"
    if vmax >= 1e4:
        return 1e-3, "kJ"
    return 1.0, "J"


def save(fig, out_dir, name, written):
    path = os.path.join(out_dir, name)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    written.append(name)
    return name


def run_colors(n):
    cmap = plt.get_cmap("tab10")
    return [cmap(i % 10) for i in range(n)]


def choose_frames(fields, k):
    """Up to k field outputs evenly spread over the run, always with the last one; the t=0
    output (nothing happened yet) is left out when there are later ones."""
    idx = [i for i, (t, _) in enumerate(fields) if t > 0] or list(range(len(fields)))
    if len(idx) <= k:
        return idx
    pick = np.unique(np.round(np.linspace(0, len(idx) - 1, k)).astype(int))
    return [idx[i] for i in pick]


def fmt_time(t):
    f, u = time_scale(t)
    return f"t = {t * f:.3g} {u}"


# ----------------------------------------------------------------------------- drawing fields
def draw_polys(ax, polys, values, cmap, norm):
    """Filled polygons coloured by per-cell values (one collection per cell type)."""
    mappable = None
    for verts, ids in polys:
        pc = PolyCollection(verts, array=values[ids], cmap=cmap, norm=norm,
                            edgecolors="face", linewidths=0.15)
        ax.add_collection(pc)
        mappable = pc
    return mappable


def view_box(polys_list, frame, idx):
    """(lo, hi) drawing limits covering the polygons of several pictures, padded by 2 %.
    Fragments thrown far away would shrink the model to a dot: the limits stay within the
    model's reference box enlarged by half its size on every side."""
    pts = [v.reshape(-1, 2) for polys in polys_list for v, _ in polys]
    pts = np.concatenate(pts) if pts else np.zeros((1, 2))
    lo, hi = pts.min(0), pts.max(0)
    ref = frame.X[:, list(idx)]
    rlo, rhi = ref.min(0), ref.max(0)
    ext = rhi - rlo
    lo, hi = np.maximum(lo, rlo - 0.5 * ext), np.minimum(hi, rhi + 0.5 * ext)
    pad = 0.02 * float(max(hi - lo)) if np.any(hi > lo) else 1.0
    return lo - pad, hi + pad


def box_aspect(box):
    w, h = box[1] - box[0]
    return float(np.clip(w / h if h > 0 else 1.0, 0.3, 4.0))


def set_limits(ax, box, xlabel, ylabel, flip=False):
    ax.set_xlim(box[0][0], box[1][0])
    ax.set_ylim(box[0][1], box[1][1])
    if flip:
        ax.invert_yaxis()
    ax.set_aspect("equal")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(False)


def colorbar(fig, mappable, ax=None, shrink=0.9, extend="neither"):
    """A slim colour bar next to the given axes (or axes list)."""
    return fig.colorbar(mappable, ax=ax, shrink=shrink, extend=extend, fraction=0.05, aspect=25,
                        pad=0.02)


def draw_cracks(ax, segs, lw=0.5):
    if segs is not None and len(segs):
        ax.add_collection(LineCollection(segs, colors=CRACK_COLOR, linewidths=lw, alpha=0.9))


def cell_values(frame, name, scale=1.0):
    v = frame.cell(name)
    if v is None:
        return None
    v = np.asarray(v, float)
    if v.ndim > 1:
        v = np.linalg.norm(v, axis=1)
    return v * scale


def node_magnitude_per_cell(frame):
    """Cell mean of the nodal displacement magnitude (m), per cell id."""
    g = frame.grid
    out = np.zeros(g.ncells)
    umag = np.linalg.norm(frame.u, axis=1)
    for t in (VTK_TRIANGLE, VTK_QUAD, VTK_TETRA):
        ids = g.cells_of_type(t)
        if ids.size:
            out[ids] = umag[g.cell_nodes(t)].mean(1)
    return out


def figsize_for(ncols, nrows, aspect, aw, cbar_each, cbar_shared, title_lines=1, suptitle=True):
    """Figure size (in) giving axes of width aw and the view's aspect, with room for the
    tick labels, titles and colour bars, so constrained_layout leaves little white space."""
    ah = aw / aspect
    if ah > 7.0:  # tall views: keep the figure on a screen
        aw, ah = aw * 7.0 / ah, 7.0
    w = ncols * (aw + 0.8 + (1.1 if cbar_each else 0.0)) + (1.2 if cbar_shared else 0.0)
    h = nrows * (ah + 0.55 + 0.2 * title_lines) + (0.8 if suptitle else 0.3)
    return w, h


def aw_of(fig, ncols):
    """Rough width (in) of one panel of a grid figure."""
    return fig.get_figwidth() / ncols


def grid_shape(n):
    ncols = 1 if n == 1 else 2 if n in (2, 4) else 3
    return math.ceil(n / ncols), ncols


CHARGE_FACE = (0.62, 0.62, 0.66, 1.0)
CHARGE_HATCH = "xxxx"


def draw_charge(ax, polys, charge):
    """The charge blocks (explosive blocks, or blocks mostly filled by a bar charge) drawn grey
    and hatched over a field picture: their damage is not blast damage (their interfaces are
    unbreakable), so they must not read as intact stemming. Returns a legend handle or None."""
    if charge is None or not np.any(charge):
        return None
    drawn = False
    for verts, ids in polys:
        sel = charge[ids]
        if sel.any():
            ax.add_collection(PolyCollection(verts[sel], facecolors=CHARGE_FACE,
                                             edgecolors="0.35", linewidths=0.3,
                                             hatch=CHARGE_HATCH))
            drawn = True
    if not drawn:
        return None
    from matplotlib.patches import Patch
    return Patch(facecolor=CHARGE_FACE, edgecolor="0.35", hatch=CHARGE_HATCH,
                 label="charge blocks (not counted as rock)")


def shared_scale(values, polys_list, pct=99.0, log_decades=3.0):
    """One colour scale for the panels of one quantity: the top is the pct-th percentile of
    every drawn value (the clipping shows as the colour bar's arrow), the bottom log_decades
    decades below on a log scale (peak and residual stresses differ by orders of magnitude).
    Returns (norm, top, vmax)."""
    vis = [v[ids] for v, polys in zip(values, polys_list) if v is not None for _, ids in polys]
    vis = np.concatenate(vis) if vis else np.zeros(1)
    vis = vis[np.isfinite(vis)]
    vmax = float(vis.max()) if vis.size else 1.0
    top = float(np.percentile(vis, pct)) if vis.size else 1.0
    if not top > 0:
        top = vmax if vmax > 0 else 1.0
    return mcolors.LogNorm(top * 10 ** -log_decades, top, clip=False), top, vmax


def plot_field_grid(run, frames, quantity, out_dir, name, written, charge=None):
    """A grid of damage or von Mises pictures at several output times, one colour scale for
    all panels (von Mises: log scale, clipped at the 99th percentile of every panel)."""
    nrows, ncols = grid_shape(len(frames))
    views = [fr.view() for fr in frames]
    box = view_box([v.polys for v in views], frames[-1], views[-1].idx)
    aspect = box_aspect(box)
    w, h = figsize_for(ncols, nrows, aspect, 3.6, False, True)
    fig, axes = plt.subplots(nrows, ncols, squeeze=False, constrained_layout=True,
                             figsize=(max(w, 7.5), h))
    if quantity == "damage":
        values = [cell_values(fr, "damage") for fr in frames]
        norm, cmap, extend = mcolors.Normalize(0, 1), DAMAGE_CMAP, "neither"
    else:
        values = [cell_values(fr, "von_mises", 1e-6) for fr in frames]
        norm, top, vmax = shared_scale(values, [v.polys for v in views])
        cmap = plt.get_cmap(VM_CMAP).copy()
        cmap.set_under("white")
        extend = "both" if vmax > top else "min"
    mappable, handle = None, None
    for k, ax in enumerate(axes.ravel()):
        if k >= len(frames):
            ax.set_visible(False)
            continue
        fr, v, vals = frames[k], views[k], values[k]
        polys = v.polys
        if vals is None or not polys:
            ax.text(0.5, 0.5, "no data", ha="center", va="center", transform=ax.transAxes)
            ax.set_title(fmt_time(fr.time))
            continue
        mappable = draw_polys(ax, polys, vals, cmap, norm)
        hc = draw_charge(ax, polys, charge)
        if hc is not None and handle is None:
            handle, handle_ax = hc, ax
        draw_cracks(ax, v.segs, lw=0.3)
        set_limits(ax, box, v.xlabel, v.ylabel, v.flip)
        ax.set_title(fmt_time(fr.time))
        if k % ncols:
            ax.set_ylabel("")
        if k // ncols < nrows - 1 and k + ncols < len(frames):
            ax.set_xlabel("")
    if mappable is not None:
        cb = colorbar(fig, mappable, ax=axes.ravel().tolist(), shrink=0.8, extend=extend)
        if quantity == "damage":
            cb.set_label("damage" if nrows * aw_of(fig, ncols) / aspect < 4.5
                         else "damage (broken fraction of interface area)")
        else:
            cb.set_label(f"von Mises (MPa, log scale)\nclipped at {top:.3g} (99th pct.), "
                         f"max {vmax:.3g}")
    if handle is not None:
        handle_ax.legend(handles=[handle], loc="lower left", fontsize=7, framealpha=0.85)
    where = f", {views[-1].where}" if views[-1].where else ""
    what = "Damage" if quantity == "damage" else "von Mises stress"
    scale = "" if quantity == "damage" else "; one colour scale for all panels"
    fig.suptitle(f"{what}{where}: {run.label}{magnify_note(frames[-1])}\n"
                 f"black lines: cracks (broken interfaces){scale}")
    return save(fig, out_dir, name, written)


def magnify_note(frame):
    return "" if frame.magnify == 1.0 else f" (displacements x{frame.magnify:g})"


def plot_damage_final(run, frame, out_dir, name, written, ax=None, fig=None, charge=None, box=None):
    """The last damage picture, large (or into a given axes for the comparison; `box`: limits
    shared with the other panels, else the frame's own)."""
    v = frame.view()
    polys = v.polys
    box = box if box is not None else view_box([polys], frame, v.idx)
    own = ax is None
    if own:
        aspect = box_aspect(box)
        fig, ax = plt.subplots(figsize=figsize_for(1, 1, aspect, 6.5, True, False, 2, False),
                               constrained_layout=True)
    vals = cell_values(frame, "damage")
    handle = None
    if vals is None or not polys:
        ax.text(0.5, 0.5, "no damage data", ha="center", va="center", transform=ax.transAxes)
        m = None
    else:
        m = draw_polys(ax, polys, vals, DAMAGE_CMAP, mcolors.Normalize(0, 1))
        handle = draw_charge(ax, polys, charge)
        draw_cracks(ax, v.segs, lw=0.6 if own else 0.4)
        set_limits(ax, box, v.xlabel, v.ylabel, v.flip)
    where = f", {v.where}" if v.where else ""
    fd = run.summary.get("fracture_degree")
    fdt = f", fracture degree {100 * fd:.1f} %" if isinstance(fd, (int, float)) else ""
    if handle is not None:
        ax.legend(handles=[handle], loc="lower left", fontsize=8)
    if own:
        ax.set_title(f"Damage at {fmt_time(frame.time)}{where}: {run.label}{magnify_note(frame)}\n"
                     f"black lines: cracks{fdt}")
        if m is not None:
            cb = colorbar(fig, m, ax=ax, shrink=0.85)
            cb.set_label("damage (broken fraction of interface area)")
        return save(fig, out_dir, name, written)
    ax.set_title(f"{run.label}\n{fmt_time(frame.time)}{where}{fdt}")
    return m


def fragment_colors(ids):
    """RGBA per cell: fragment 0 (the largest, usually the rock mass) light grey, the others
    from a qualitative palette by id."""
    pal = np.array(plt.get_cmap("tab20").colors)
    pal = np.delete(pal, [14, 15], axis=0)        # no greys: grey is the rock mass
    pal = np.concatenate([pal[0::2], pal[1::2]])  # strong colours first
    rgba = np.ones((len(ids), 4))
    rgba[:, :3] = pal[(np.maximum(ids, 1) - 1) % len(pal)]
    rgba[ids == 0, :3] = 0.85
    rgba[ids < 0, :3] = 1.0
    return rgba


def fragment_count(run, frame):
    """(count, counted ids) of the fragments of a field output, the way fragments.csv and
    summary.json count them (rock fragments; charge blocks have their own fragment_id in the
    fields but are not fragments). Without fragments.csv: the distinct ids of the field."""
    tab = run.fragments_at(frame.path)
    if tab is not None and isinstance(tab.get("id"), np.ndarray):
        ids = tab["id"].astype(np.int64)
        return int(ids.size), ids
    fid = frame.cell("fragment_id")
    if fid is None:
        return None, None
    ids = np.unique(np.asarray(fid).astype(np.int64))
    ids = ids[ids >= 0]
    return int(ids.size), ids


def plot_fragments_final(run, frame, out_dir, written, charge=None):
    """The blocks of the last output coloured by fragment (needs the fragment_id array). The
    title gives the fragment count of fragments.csv (the summary's); blocks whose id is not a
    counted fragment (the charge) are drawn hatched."""
    fid = frame.cell("fragment_id")
    if fid is None:
        return None
    fid = np.asarray(fid).astype(np.int64)
    v = frame.view()
    polys = v.polys
    if not polys:
        return None
    box = view_box([polys], frame, v.idx)
    fig, ax = plt.subplots(figsize=figsize_for(1, 1, box_aspect(box), 6.5, False, False, 2, False),
                           constrained_layout=True)
    n, counted = fragment_count(run, frame)
    not_counted = ~np.isin(fid, counted) if counted is not None else np.zeros(fid.size, bool)
    if charge is not None:
        not_counted |= charge
    rgba = fragment_colors(fid)
    for verts, ids in polys:
        ax.add_collection(PolyCollection(verts, facecolors=rgba[ids], edgecolors=rgba[ids],
                                         linewidths=0.15))
    handle = draw_charge(ax, polys, not_counted)
    draw_cracks(ax, v.segs, lw=0.3)
    set_limits(ax, box, v.xlabel, v.ylabel, v.flip)
    if handle is not None:
        handle.set_label("charge blocks (not fragments)")
        ax.legend(handles=[handle], loc="lower left", fontsize=8)
    where = f", {v.where}" if v.where else ""
    count = f"{n} fragments (the count of fragments.csv and summary.json)" if n is not None else ""
    ax.set_title(f"Fragments at {fmt_time(frame.time)}{where}: {run.label}{magnify_note(frame)}\n"
                 f"{count}\ngrey: the largest (the rock mass); colours: the others")
    return save(fig, out_dir, "fragments_final.png", written)


def up_words(frame):
    """How the free-surface normal is named in titles: 'vertical' for +z, else the vector."""
    if np.allclose(frame.up, (0, 0, 1)):
        return "vertical displacement u_z", "top view (from +z)"
    n = ", ".join(f"{c:g}" for c in np.round(frame.up, 3))
    return f"displacement along up = ({n})", f"view of the free surface (up = ({n}))"


def plot_3d_views(run, frame, out_dir, written):
    """top_view.png (damage, displacement out of the free surface) and section.png (damage,
    |u|). 'Top' is the free surface: the case's analysis.up, +z by default."""
    names = []
    disp_words, view_words = up_words(frame)
    h1, h2 = AXIS[frame.h1], AXIS[frame.h2]
    top = frame.top_faces()
    if top is not None and len(top[0]):
        verts, ids, un = top
        polys = [(verts, ids)]
        box = view_box([polys], frame, (frame.h1, frame.h2))
        fig, axes = plt.subplots(1, 2, figsize=figsize_for(2, 1, box_aspect(box), 4.6, True, False),
                                 constrained_layout=True)
        dmg = cell_values(frame, "damage")
        if dmg is not None:
            m = draw_polys(axes[0], polys, dmg, DAMAGE_CMAP, mcolors.Normalize(0, 1))
            colorbar(fig, m, ax=axes[0], shrink=0.85).set_label("damage")
        set_limits(axes[0], box, f"{h1} (m)", f"{h2} (m)")
        axes[0].set_title("Damage of the faces looking up")
        unmm = un * 1e3
        lim = float(np.nanpercentile(np.abs(unmm), 98)) or 1.0
        pc = PolyCollection(verts, array=unmm, cmap="RdBu_r", norm=mcolors.Normalize(-lim, lim),
                            edgecolors="face", linewidths=0.15)
        axes[1].add_collection(pc)
        colorbar(fig, pc, ax=axes[1], shrink=0.85, extend="both").set_label(f"{disp_words} (mm)")
        set_limits(axes[1], box, f"{h1} (m)", f"{h2} (m)")
        axes[1].set_title(disp_words[0].upper() + disp_words[1:])
        fig.suptitle(f"{view_words[0].upper() + view_words[1:]} at {fmt_time(frame.time)}: "
                     f"{run.label}{magnify_note(frame)}")
        names.append(save(fig, out_dir, "top_view.png", written))
    v = frame.view()
    if v.polys:
        box = view_box([v.polys], frame, v.idx)
        fig, axes = plt.subplots(1, 2, figsize=figsize_for(2, 1, box_aspect(box), 4.6, True, False),
                                 constrained_layout=True)
        dmg = cell_values(frame, "damage")
        if dmg is not None:
            m = draw_polys(axes[0], v.polys, dmg, DAMAGE_CMAP, mcolors.Normalize(0, 1))
            colorbar(fig, m, ax=axes[0], shrink=0.85).set_label("damage")
        draw_cracks(axes[0], v.segs, lw=0.5)
        set_limits(axes[0], box, v.xlabel, v.ylabel, v.flip)
        axes[0].set_title("Damage (black lines: cracks)")
        umag = node_magnitude_per_cell(frame) * 1e3
        vis = np.concatenate([umag[ids] for _, ids in v.polys])
        top = float(np.nanpercentile(vis, 98)) or 1.0
        m = draw_polys(axes[1], v.polys, umag, "viridis", mcolors.Normalize(0, top))
        colorbar(fig, m, ax=axes[1], shrink=0.85, extend="max").set_label(
            "displacement magnitude |u| (mm)")
        set_limits(axes[1], box, v.xlabel, v.ylabel, v.flip)
        axes[1].set_title("Displacement magnitude")
        fig.suptitle(f"Section {h2} = {frame.section_at:.3g} m (through the model centre, free "
                     f"surface on top) at {fmt_time(frame.time)}: {run.label}{magnify_note(frame)}")
        names.append(save(fig, out_dir, "section.png", written))
    return names


# ----------------------------------------------------------------------------- time histories
def dominant_component(runs, prefix):
    """The component (x, y or z) of ux/vx... with the largest peak over all monitors."""
    best, peak = "x", -1.0
    for c in "xyz":
        for r in runs:
            for m in r.monitors.values():
                v = m.get(prefix + c)
                if v is not None and v.size:
                    p = float(np.nanmax(np.abs(v)))
                    if p > peak:
                        best, peak = c, p
    return best


def plot_monitors(runs, out_dir, written):
    runs_with = [r for r in runs if r.monitors]
    if not runs_with:
        return None
    names = list(dict.fromkeys(n for r in runs_with for n in r.monitors))
    tmax = max(float(m["time"].max()) for r in runs_with for m in r.monitors.values())
    tf, tu = time_scale(tmax)
    vc = dominant_component(runs_with, "v")
    uc = dominant_component(runs_with, "u")
    panels = [("von_mises", 1e-6, "von Mises stress (MPa)"),
              ("v" + vc, 1.0, f"velocity v_{vc} (m/s)"),
              ("u" + uc, 1e3, f"displacement u_{uc} (mm)")]
    fig, axes = plt.subplots(3, 1, figsize=(9, 9.5), sharex=True, constrained_layout=True)
    colors = run_colors(len(names))
    multi = len(runs_with) > 1
    for ri, r in enumerate(runs_with):
        for mi, n in enumerate(names):
            m = r.monitors.get(n)
            if m is None:
                continue
            for ax, (col, sc, _) in zip(axes, panels):
                if col in m:
                    ax.plot(m["time"] * tf, m[col] * sc, color=colors[mi],
                            ls=RUN_STYLES[ri % len(RUN_STYLES)], lw=1.2)
    for ax, (_, _, lab) in zip(axes, panels):
        ax.set_ylabel(lab)
    axes[-1].set_xlabel(f"time ({tu})")
    axes[0].set_xlim(0, tmax * tf)

    def mlabel(n):
        for r in runs_with:
            p = r.monitor_points.get(n)
            if isinstance(p, list) and p and all(isinstance(c, (int, float)) for c in p):
                p = p[:3]
                if len(p) == 3 and p[2] == 0 and r.dim == 2:
                    p = p[:2]
                return f"{n} ({', '.join(f'{c:g}' for c in p)})"
        return n

    handles = [Line2D([], [], color=colors[i], lw=1.5, label=mlabel(n)) for i, n in enumerate(names)]
    leg = axes[0].legend(handles=handles, title="monitor (point, m)", loc="upper left",
                         bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    if multi:
        axes[0].add_artist(leg)
        rh = [Line2D([], [], color="0.2", ls=RUN_STYLES[i % len(RUN_STYLES)], lw=1.5, label=r.label)
              for i, r in enumerate(runs_with)]
        axes[1].legend(handles=rh, title="run", loc="upper left", bbox_to_anchor=(1.01, 1.0),
                       borderaxespad=0)
    title = "Monitor time histories" + ("" if multi else f": {runs_with[0].label}")
    fig.suptitle(title)
    return save(fig, out_dir, "monitors.png", written)


def history_runs(runs, attr):
    """(the runs that have the history `attr`, its longest time, the time axis factor and
    unit); ([], None, None, None) when none has it."""
    runs_with = [r for r in runs if getattr(r, attr) is not None]
    if not runs_with:
        return [], None, None, None
    tmax = max(float(getattr(r, attr)["time"].max()) for r in runs_with)
    return (runs_with, tmax) + time_scale(tmax)


def plot_fracture(runs, out_dir, written):
    runs_with, tmax, tf, tu = history_runs(runs, "fracture")
    if not runs_with:
        return None
    parts = [("degree_area", "total (area)"), ("tensile_area", "tensile"), ("shear_area", "shear"),
             ("degree_count", "count-based")]
    if len(runs_with) == 1:
        r = runs_with[0]
        fr = r.fracture
        fig, ax = plt.subplots(figsize=(8.5, 5), constrained_layout=True)
        styles = {"degree_area": dict(color="black", lw=2.0), "tensile_area": dict(color="tab:blue", lw=1.5),
                  "shear_area": dict(color="tab:red", lw=1.5),
                  "degree_count": dict(color="0.5", lw=1.2, ls="--")}
        for col, lab in parts:
            if col in fr:
                v = fr[col] * 100
                ax.plot(fr["time"] * tf, v, label=f"{lab}: {v[-1]:.1f} %", **styles[col])
        ax.set_title(f"Fracture degree (broken / total spring-point area): {r.label}")
        ax.legend(loc="upper left", title="at the end")
        ax.set_xlabel(f"time ({tu})")
        ax.set_ylabel("fracture degree (%)")
        ax.set_xlim(0, tmax * tf)
        ax.set_ylim(bottom=0)
        return save(fig, out_dir, "fracture.png", written)
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.8), sharey=True, constrained_layout=True)
    colors = run_colors(len(runs_with))
    for ax, (col, lab) in zip(axes, parts[:3]):
        for i, r in enumerate(runs_with):
            fr = r.fracture
            if col in fr:
                v = fr[col] * 100
                ax.plot(fr["time"] * tf, v, color=colors[i], lw=1.6,
                        label=f"{r.label}: {v[-1]:.1f} %")
        ax.set_title(f"{lab}")
        ax.set_xlabel(f"time ({tu})")
        ax.set_xlim(0, tmax * tf)
        ax.set_ylim(bottom=0)
        ax.legend(loc="best", fontsize=8)
    axes[0].set_ylabel("fracture degree (%)")
    fig.suptitle("Fracture degree (broken / total spring-point area)")
    return save(fig, out_dir, "fracture.png", written)


def plot_charges(runs, out_dir, written):
    """charges.csv: the gas pressure of every deck against time (log), and the products' mass
    in the charges, in cracks and vented, summed over the decks. None without charges."""
    runs_with = [r for r in runs if r.charges]
    if not runs_with:
        return None
    tmax = max(float(c["time"].max()) for r in runs_with for c in r.charges.values() if c["time"].size)
    tf, tu = time_scale(tmax)
    per_m = " per metre" if any(r.per_metre for r in runs_with) else ""
    fig, (ax_p, ax_m) = plt.subplots(1, 2, figsize=(14, 5), constrained_layout=True)
    styles = ["-", "--", ":", "-."]
    colors = run_colors(len(runs_with))
    for i, r in enumerate(runs_with):
        decks = [(hole, deck, cols) for hole, cols in r.charges.items() for deck in np.unique(cols["deck"])]
        dcolors = run_colors(len(decks)) if len(runs_with) == 1 else [colors[i]] * len(decks)
        mass = {}
        for j, (hole, deck, cols) in enumerate(decks):
            sel = cols["deck"] == deck
            t, p = cols["time"][sel], cols["pressure"][sel]
            if t.size == 0:
                continue
            lab = f"{hole} deck {int(deck)}" + (f" ({r.label})" if len(runs_with) > 1 else "")
            ls = styles[j % len(styles)] if len(runs_with) > 1 else "-"  # several runs: style per deck
            ax_p.semilogy(t * tf, np.maximum(p, 1e3), color=dcolors[j], ls=ls, lw=1.2,
                          label=lab if len(decks) <= 16 else None)
            for col in ("gas_mass_charge", "gas_mass_cracks", "vented_mass"):
                if col in cols:
                    v = cols[col][sel]
                    if col in mass and mass[col][0].size == t.size:
                        mass[col] = (t, mass[col][1] + v)
                    elif col not in mass:
                        mass[col] = (t, v.copy())
        names = {"gas_mass_charge": "in the charges", "gas_mass_cracks": "in cracks", "vented_mass": "vented"}
        for k, (col, (t, v)) in enumerate(mass.items()):
            ax_m.plot(t * tf, v, color=colors[i] if len(runs_with) > 1 else f"C{k}", ls=styles[k % 3],
                      label=names[col] + (f" ({r.label})" if len(runs_with) > 1 else ""))
    ax_p.set(xlabel=f"time ({tu})", ylabel="gas pressure (Pa)", xlim=(0, tmax * tf),
             title="Deck gas pressure (floored at 1 kPa on the log axis)")
    ax_m.set(xlabel=f"time ({tu})", ylabel=f"products (kg{per_m})", xlim=(0, tmax * tf),
             title="Detonation products: in the charges, in cracks, vented (all decks)")
    ax_m.set_ylim(bottom=0)
    for a in (ax_p, ax_m):
        a.grid(alpha=0.3)
        if a.get_legend_handles_labels()[0]:
            a.legend(fontsize=7, loc="best")
    return save(fig, out_dir, "charges.png", written)


ENERGY_TERMS = [
    ("kinetic", "kinetic", "tab:blue", "-"),
    ("block_strain", "block strain", "tab:orange", "-"),
    ("spring_strain", "spring strain", "tab:green", "-"),
    ("external_work", "external work (input)", "black", "--"),
    ("gravity_work", "gravity work (input)", "0.4", "--"),
    ("explosive_work", "explosive work (input)", "tab:red", "--"),
    ("damping", "damping + absorbed", "tab:purple", "-."),
    ("fracture", "fracture dissipation", "tab:brown", "-."),
    ("initial", "initial stored", "0.6", ":"),
    ("insertion", "opened points at insertion (input)", "tab:olive", ":"),
    ("contact_strain", "contact (penalty) energy", "tab:cyan", "-"),
    ("contact_friction", "contact friction dissipation", "tab:pink", "-."),
]


def plot_error(ax, t, err, color, label=None):
    e = np.abs(np.asarray(err, float))
    e = np.where(e > 0, e, np.nan)
    ax.semilogy(t, e, color=color, lw=1.2, label=label)
    # Plain "1e-05" labels: no mathtext (its parser costs a noticeable start-up time).
    ax.yaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:.0e}"))
    ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())


def per_metre_suffix(runs):
    """'/m' when every run is plane strain (energies per metre of thickness), a note when some
    are, '' otherwise."""
    flags = [bool(getattr(r, "per_metre", False)) for r in runs]
    if flags and all(flags):
        return "/m"
    return "; 2D runs per metre" if any(flags) else ""


def explosive_work_label(e, drop=0.01):
    """The legend entry of the explosive work when it falls after its peak by more than `drop`
    of it: then the rock does work on the products (the cavity is pushed back), and the work
    done by the charge flows back into them; None when it does not fall."""
    w = e.get("explosive_work")
    if w is None or w.size < 2:
        return None
    i = int(np.nanargmax(w))
    peak, last = float(w[i]), float(w[-1])
    if not peak > 0 or peak - last <= drop * peak:
        return None
    tf, tu = time_scale(float(e["time"].max()))
    return (f"explosive work (input); falls {100 * (peak - last) / peak:.0f} % from its peak at "
            f"{e['time'][i] * tf:.3g} {tu}:\nthe rock pushes the products back, work flows "
            "back into them")


def plot_energy(runs, out_dir, written):
    runs_with, tmax, tf, tu = history_runs(runs, "energy")
    if not runs_with:
        return None
    if len(runs_with) == 1:
        r = runs_with[0]
        e = r.energy
        t = e["time"] * tf
        present = [(c, l, col, ls) for c, l, col, ls in ENERGY_TERMS
                   if c in e and np.nanmax(np.abs(e[c])) > 1e-9 * max(1e-300, max(
                       np.nanmax(np.abs(e[k])) for k, *_ in ENERGY_TERMS if k in e))]
        vmax = max([np.nanmax(np.abs(e[c])) for c, *_ in present] or [1.0])
        sc, unit = energy_scale(vmax)
        fig, (a1, a2) = plt.subplots(2, 1, figsize=(11, 8), sharex=True,
                                     gridspec_kw={"height_ratios": [2.2, 1]}, constrained_layout=True)
        unit += per_metre_suffix([r])
        for c, l, col, ls in present:
            if c == "explosive_work":
                l = explosive_work_label(e) or l
            a1.plot(t, e[c] * sc, color=col, ls=ls, lw=1.5, label=l)
        a1.set_ylabel(f"energy ({unit})")
        a1.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
        a1.set_title("Energy terms (stored, input work, dissipated)")
        if "error" in e:
            plot_error(a2, t, e["error"], "black")
            fe = r.summary.get("energy_error")
            if isinstance(fe, (int, float)):
                a2.set_title(f"Balance error |balance| / max(|work in|, mech. energy): final {fe:.2g}",
                             fontsize=10)
            else:
                a2.set_title("Balance error |balance| / max(|work in|, mech. energy)", fontsize=10)
        a2.set_ylabel("relative error")
        a2.set_xlabel(f"time ({tu})")
        a2.set_xlim(0, tmax * tf)
        fig.suptitle(f"Energy balance: {r.label}")
        return save(fig, out_dir, "energy.png", written)
    groups = [("kinetic", ["kinetic"]),
              ("strain (blocks + springs + contacts)", ["block_strain", "spring_strain", "contact_strain"]),
              ("work input (external + gravity + explosive + insertion)",
               ["external_work", "gravity_work", "explosive_work", "insertion"]),
              ("damping + absorbed", ["damping"]), ("fracture dissipation", ["fracture"])]
    vmax = 1.0
    series = {}
    for r in runs_with:
        for g, cols in groups:
            v = sum((r.energy[c] for c in cols if c in r.energy), np.zeros_like(r.energy["time"]))
            series[(r.label, g)] = v
            vmax = max(vmax, float(np.nanmax(np.abs(v))) if v.size else 0)
    sc, unit = energy_scale(vmax)
    unit += per_metre_suffix(runs_with)
    fig, axes = plt.subplots(2, 3, figsize=(15, 8.5), sharex=True, constrained_layout=True)
    colors = run_colors(len(runs_with))
    for ax, (g, _) in zip(axes.ravel(), groups):
        for i, r in enumerate(runs_with):
            ax.plot(r.energy["time"] * tf, series[(r.label, g)] * sc, color=colors[i], lw=1.5,
                    ls=RUN_STYLES[i % len(RUN_STYLES)], label=r.label)
        ax.set_title(g)
        ax.set_ylabel(f"energy ({unit})")
    ax = axes.ravel()[5]
    for i, r in enumerate(runs_with):
        if "error" in r.energy:
            plot_error(ax, r.energy["time"] * tf, r.energy["error"], colors[i], r.label)
    ax.set_title("balance error (relative)")
    ax.set_ylabel("relative error")
    for ax in axes[1]:
        ax.set_xlabel(f"time ({tu})")
    axes[0, 0].set_xlim(0, tmax * tf)
    axes[0, 0].legend(loc="best", fontsize=8)
    fig.suptitle("Energy balance")
    return save(fig, out_dir, "energy.png", written)


# ----------------------------------------------------------------------------- grading
def grading_data(run):
    """(sizes m, passing %, source text) of the run's grading curve, or None."""
    s = run.summary

    def pick(d, names):
        for n in names:
            if isinstance(d.get(n), list) and d[n]:
                return d[n]
        return None

    size_names = ("size_m", "sizes_m", "size", "sizes", "l_bc_m", "L_bc_m")
    pass_names = ("passing_pct", "passing_percent", "passing", "percent_passing")
    for d in (s.get("grading"), s):
        if isinstance(d, dict):
            a = pick(d, size_names) or pick(d, tuple("grading_" + n for n in size_names))
            b = pick(d, pass_names) or pick(d, tuple("grading_" + n for n in pass_names))
            if a and b and len(a) == len(b):
                try:
                    return np.array(a, float), np.array(b, float), "summary.json"
                except (TypeError, ValueError):
                    pass
    g = read_table(os.path.join(run.dir, "grading.csv"))
    if g:
        sc = next((k for k in g if "size" in k.lower() or "l_bc" in k.lower()), None)
        pc = next((k for k in g if "pass" in k.lower()), None)
        if sc and pc:
            size, passing = np.asarray(g[sc], float), np.asarray(g[pc], float)
            ok = np.isfinite(size) & np.isfinite(passing)
            if ok.any():
                return size[ok], passing[ok], "grading.csv"
    pts = [(s.get(f"d{x}_m"), x) for x in range(10, 100, 10)]
    pts = [(float(v), x) for v, x in pts if isinstance(v, (int, float)) and math.isfinite(v)]
    if len(pts) >= 2:
        return np.array([p[0] for p in pts]), np.array([p[1] for p in pts], float), "d10..d90 in summary.json"
    return None


def plot_grading(runs, out_dir, written, notes, yardstick=None, name="grading.png", curves=None):
    """The grading curves of the runs (d40, d80 marked); with `yardstick` (a
    yardsticks.KuzRam) the Kuz-Ram (Rosin-Rammler) and Swebrec curves of the design beside
    them; `curves` replaces the runs' own grading data ([(run, (size, passing, source))])."""
    data = curves if curves is not None else [(r, grading_data(r)) for r in runs]
    data = [(r, d) for r, d in data if d is not None]
    why = "no grading data (no grading curve or d10..d90 in summary.json, no grading.csv)"
    if not data:
        notes.append(f"{why}: grading.png skipped.")
        return None
    for r in runs:
        if all(r is not rr for rr, _ in data):
            r.notes.append(f"{why}: left out of grading.png.")
    fig, ax = plt.subplots(figsize=(8.5, 5.5), constrained_layout=True)
    colors = run_colors(len(data))
    allsize = np.concatenate([d[0] for _, d in data])
    allsize = allsize[allsize > 0]
    for i, (r, (size, passing, src)) in enumerate(data):
        order = np.argsort(size, kind="stable")
        lab = r.label if len(data) > 1 else f"grading curve ({src})"
        if len(data) > 1:  # the d values go in the legend: labels on the plot would collide
            dv = [(k[:3], r.summary.get(k)) for k in ("d40_m", "d80_m")]
            dv = [f"{n} {v:.3g} m" for n, v in dv if isinstance(v, (int, float)) and math.isfinite(v)]
            lab += f" ({', '.join(dv)})" if dv else ""
        ax.plot(size[order], passing[order], color=colors[i], lw=1.8, label=lab,
                marker="o" if size.size <= 60 else None, ms=3)
        for key, pct, ls in (("d40_m", 40, "--"), ("d80_m", 80, ":")):
            v = r.summary.get(key)
            if isinstance(v, (int, float)) and math.isfinite(v) and v > 0:
                ax.plot([v, v], [0, pct], color=colors[i], ls=ls, lw=1)
                ax.plot([v], [pct], "o", color=colors[i], ms=6, mfc="white")
                if len(data) == 1:
                    ax.annotate(f"{key[:3]} = {v:.3g} m", (v, pct), textcoords="offset points",
                                xytext=(7, -13), fontsize=9, color=colors[i],
                                bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none",
                                          alpha=0.8))
    if yardstick is not None:
        lo = min(float(allsize.min()) if allsize.size else yardstick.x50, yardstick.x50) / 5
        hi = max(float(allsize.max()) if allsize.size else yardstick.x50, yardstick.xmax) * 1.05
        xs = np.geomspace(max(lo, 1e-4), hi, 300)
        ax.plot(xs, yardstick.passing(xs), color="0.25", ls="--", lw=1.4,
                label=f"Kuz-Ram, Rosin-Rammler (x50 {yardstick.x50:.3g} m, n {yardstick.n:.2f})")
        sw = yardstick.passing(xs, "swebrec")
        if sw is not None:
            ax.plot(xs, sw, color="0.25", ls=":", lw=1.6,
                    label=f"Swebrec, KCO (xmax {yardstick.xmax:.3g} m, b {yardstick.b:.2f})")
        allsize = np.concatenate([allsize, xs[[0, -1]]])
    if allsize.size and allsize.max() / allsize.min() > 20:
        ax.set_xscale("log")
        ax.xaxis.set_major_locator(matplotlib.ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_ylim(0, 102)
    ax.set_xlabel("fragment size L_bc (m)")
    ax.set_ylabel("cumulative volume passing (%)")
    ax.set_title("Fragment size grading" + ("" if len(data) > 1 else f": {data[0][0].label}"))
    ax.legend(loc="lower right", fontsize=8)
    return save(fig, out_dir, name, written)


def load_frames(run, indices, magnify, notes):
    """FieldFrames of the given outputs; unreadable files are noted and left out."""
    frames = []
    for i in indices:
        try:
            fr = FieldFrame(run, i, magnify)
            fr.grid.types, fr.grid.cell_array("damage")  # decode now: fail here, not mid-plot
            frames.append(fr)
        except (VtuError, OSError) as ex:
            notes.append(f"field output skipped: {ex}")
    return frames


def last_frame(run, magnify, notes):
    """The last readable field output (None if there is none)."""
    for i in reversed(range(len(run.fields))):
        got = load_frames(run, [i], magnify, notes)
        if got:
            return got[0]
    return None


def compare_damage(runs, out_dir, written, notes, args):
    frames = []
    for r in runs:
        fr = last_frame(r, args.magnify, r.notes) if r.fields else None
        if fr is not None:
            frames.append((r, fr))
        else:
            r.notes.append("no readable field output: left out of damage_final_compare.png.")
    if not frames:
        return None
    n = len(frames)
    ncols = min(n, 3)
    nrows = math.ceil(n / ncols)
    f0 = frames[0][1]
    aspect = box_aspect(view_box([f0.view().polys], f0, f0.view().idx))
    fig, axes = plt.subplots(nrows, ncols, figsize=figsize_for(ncols, nrows, aspect, 4.4, False, True, 3),
                             squeeze=False, constrained_layout=True)
    m = None
    for k, ax in enumerate(axes.ravel()):
        if k >= n:
            ax.set_visible(False)
            continue
        r, fr = frames[k]
        mm = plot_damage_final(r, fr, out_dir, None, written, ax=ax, fig=fig)
        m = mm or m
    if m is not None:
        colorbar(fig, m, ax=axes.ravel().tolist(), shrink=0.8).set_label(
            "damage (broken fraction of interface area)")
    fig.suptitle("Damage at the last output time (black lines: cracks)")
    return save(fig, out_dir, "damage_final_compare.png", written)




def plot_ppv(records, out_dir, written, name="ppv.png"):
    """Peak particle velocity at the monitors against scaled distance R / sqrt(Q), log-log, with
    the fitted PPV = K SD^-beta of each run. records: [(label, points, fit, per_metre)]."""
    records = [r for r in records if r[1]]
    if not records:
        return None
    fig, ax = plt.subplots(figsize=(8.0, 5.5), constrained_layout=True)
    colors = run_colors(len(records))
    per_metre = all(r[3] for r in records)
    for i, (label, pts, fit, _pm) in enumerate(records):
        sd = np.array([p["scaled_distance"] for p in pts], float)
        v = np.array([p["ppv_m_s"] for p in pts], float)
        ax.loglog(sd, v, "o", color=colors[i], ms=6, label=f"{label}: monitors")
        for p in pts:
            ax.annotate(p["monitor"], (p["scaled_distance"], p["ppv_m_s"]), fontsize=7,
                        textcoords="offset points", xytext=(4, 3), color=colors[i])
        if fit:
            xs = np.geomspace(sd.min() / 1.3, sd.max() * 1.3, 50)
            ax.loglog(xs, fit["K"] * xs ** -fit["beta"], "-", color=colors[i], lw=1.3,
                      label=f"{label}: PPV = {fit['K']:.3g} SD^-{fit['beta']:.2f} (R² {fit['r2']:.3f})")
    unit = "m/(kg/m)^0.5, plane strain: Q per metre" if per_metre else "m/kg^0.5"
    ax.set_xlabel(f"scaled distance SD = R / sqrt(Q) ({unit})")
    ax.set_ylabel("peak particle velocity (m/s)")
    ax.set_title("Peak particle velocity against scaled distance\n(R: distance to the nearest "
                 "charge; Q: the largest charge per delay)", fontsize=10)
    ax.legend(loc="best", fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    plain = matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}")
    for axis in (ax.xaxis, ax.yaxis):  # plain numbers: no mathtext (slow to parse)
        axis.set_major_formatter(plain)
        axis.set_minor_formatter(plain)
    return save(fig, out_dir, name, written)
