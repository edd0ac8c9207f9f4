#!/usr/bin/python3
"""Turn finished cdemblast runs into PNG pictures, a summary.md and an index.html.

    cdem_report.py RUN [RUN ...] [--out OUTDIR] [--frames N] [--magnify M]

One run: the report goes to RUN/report (or OUTDIR). Several runs: their histories are
overlaid and their key numbers compared side by side in FIRST_RUN/report_compare (or OUTDIR).
Needs numpy and matplotlib (Debian: /usr/bin/python3 with python3-matplotlib). The field
files are read by cdem_vtu.py next to this script. See docs/report.md.
"""

from __future__ import annotations

import argparse
import csv
import html
import json
import math
import os
import sys
import traceback

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

try:
    import numpy as np
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    from matplotlib.collections import LineCollection, PolyCollection
    from matplotlib.lines import Line2D
    from matplotlib import colors as mcolors
except ImportError as e:  # pragma: no cover - depends on the machine
    sys.exit(f"cdem_report: {e}; run it with a python3 that has numpy and matplotlib "
             "(Debian: /usr/bin/python3 with python3-numpy and python3-matplotlib)")

import cdem_vtu
from cdem_vtu import VTK_LINE, VTK_QUAD, VTK_TETRA, VTK_TRIANGLE, VtuError

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


# ----------------------------------------------------------------------------- reading
def read_table(path):
    """{column: np.array} (floats; text columns stay lists of str), or None if the file is
    missing or has no data row."""
    if not os.path.isfile(path):
        return None
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if len(rows) < 2:
        return None
    header = [h.strip() for h in rows[0]]
    cols = {h: [] for h in header}
    for r in rows[1:]:
        if len(r) != len(header):
            continue  # a truncated last line of an interrupted run
        for h, v in zip(header, r):
            cols[h].append(v)
    out = {}
    for h, vals in cols.items():
        try:
            out[h] = np.array([float(v) for v in vals])
        except ValueError:
            out[h] = vals
    if not any(len(v) for v in out.values()):
        return None
    return out


def read_csv(path):
    """A time history table (read_table with a numeric time column), or None."""
    out = read_table(path)
    if not out or not isinstance(out.get("time"), np.ndarray) or out["time"].size == 0:
        return None
    return out


def read_monitors(path):
    """{monitor name: {column: np.array}} in order of appearance, or {}."""
    data = read_csv(path)
    if not data or "monitor" not in data:
        return {}
    names = data["monitor"]
    order = list(dict.fromkeys(names))
    names = np.array(names)
    out = {}
    for n in order:
        sel = names == n
        out[n] = {k: v[sel] for k, v in data.items() if isinstance(v, np.ndarray)}
    return out


def read_up(run_dir):
    """The free-surface normal (analysis.up of case.resolved.toml), default +z."""
    path = os.path.join(run_dir, "case.resolved.toml")
    try:
        import tomllib
        with open(path, "rb") as f:
            up = tomllib.load(f).get("analysis", {}).get("up")
        up = np.array(up, float)[:3]
        if up.shape == (3,) and np.all(np.isfinite(up)) and np.linalg.norm(up) > 0:
            return up / np.linalg.norm(up)
    except Exception:  # no case file, no key: the default
        pass
    return np.array([0.0, 0.0, 1.0])


def read_monitor_points(run_dir):
    """{monitor name: point} from case.resolved.toml (empty when unavailable)."""
    path = os.path.join(run_dir, "case.resolved.toml")
    try:
        import tomllib
        with open(path, "rb") as f:
            case = tomllib.load(f)
        return {m["name"]: m.get("point") for m in case.get("monitor", []) if "name" in m}
    except Exception:  # optional decoration only
        return {}


class Run:
    """Everything the report reads from one run directory."""

    def __init__(self, path):
        self.dir = os.path.abspath(path)
        self.notes = []
        self.summary = {}
        sp = os.path.join(self.dir, "summary.json")
        if os.path.isfile(sp):
            try:
                with open(sp) as f:
                    self.summary = json.load(f)
            except (OSError, ValueError) as e:
                self.notes.append(f"summary.json could not be read ({e}).")
        else:
            self.notes.append("summary.json is missing (the run may not have finished).")
        self.label = str(self.summary.get("title") or os.path.basename(self.dir.rstrip("/")))
        self.energy = read_csv(os.path.join(self.dir, "energy.csv"))
        self.fracture = read_csv(os.path.join(self.dir, "fracture.csv"))
        self.monitors = read_monitors(os.path.join(self.dir, "monitors.csv"))
        self.monitor_points = read_monitor_points(self.dir)
        self.up = read_up(self.dir)
        self.fields = cdem_vtu.read_pvd(os.path.join(self.dir, "fields.pvd"))
        self.fields = [(t, p) for t, p in self.fields if os.path.isfile(p)]
        self.cracks = cdem_vtu.read_pvd(os.path.join(self.dir, "cracks.pvd"))
        self.cracks = [(t, p) for t, p in self.cracks if os.path.isfile(p)]
        self._dim = None

    @property
    def dim(self):
        """2 or 3 from the cell types of the first field file (None without fields)."""
        if self._dim is None and self.fields:
            for _, path in reversed(self.fields):
                try:
                    g = cdem_vtu.read_vtu(path)
                    self._dim = 3 if np.any(g.types == VTK_TETRA) else 2
                    break
                except VtuError:
                    continue
        return self._dim

    def cracks_at(self, t):
        """The crack file written with the field file of time t (None if there is none)."""
        best = None
        for tc, p in self.cracks:
            if abs(tc - t) <= 1e-9 * max(abs(t), 1e-12) + 1e-15:
                best = p
        return best


# ----------------------------------------------------------------------------- helpers
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


def match_points(ref, query):
    """For every row of query, the index of an identical row of ref (-1 if none)."""
    if len(query) == 0:
        return np.zeros(0, np.int64)
    allp = np.concatenate([ref, query])
    _, inv = np.unique(allp, axis=0, return_inverse=True)
    inv = inv.ravel()
    first = np.full(inv.max() + 1, -1, np.int64)
    first[inv[:len(ref)][::-1]] = np.arange(len(ref))[::-1]
    return first[inv[len(ref):]]


# ----------------------------------------------------------------------------- field geometry
class FieldFrame:
    """One field output, with the geometry the pictures need."""

    def __init__(self, run, index, magnify):
        self.time, path = run.fields[index]
        self.grid = g = cdem_vtu.read_vtu(path)
        x = g.points
        u = g.point_array("displacement")
        if u is None:
            u = np.zeros_like(x)
        self.u = u
        self.X = x - u                      # reference positions
        self.P = self.X + magnify * u        # drawn positions
        self.magnify = magnify
        self.dim = 3 if np.any(g.types == VTK_TETRA) else 2
        self.crack_path = run.cracks_at(self.time)
        self._cracks = None
        self._view = None
        # 3D orientation: `up` is the free-surface normal; va its dominant axis (s its sign);
        # (h1, h2) the horizontal axes, ordered so that e_h1 x e_h2 = up (a view from above
        # is not mirrored). The top view shows (h1, h2); the section is the plane
        # h2 = centre, drawn in (h1, va) with the free surface at the top.
        self.up = np.asarray(getattr(run, "up", (0.0, 0.0, 1.0)), float)
        self.va = int(np.argmax(np.abs(self.up)))
        self.s = 1.0 if self.up[self.va] >= 0 else -1.0
        self.h1, self.h2 = [(1, 2), (2, 0), (0, 1)][self.va]
        if self.s < 0:
            self.h1, self.h2 = self.h2, self.h1
        self.section_at = 0.5 * (self.X[:, self.h2].min() + self.X[:, self.h2].max())

    def view(self):
        """The picture of this frame: the whole model in 2D, the section in 3D (cached)."""
        if self._view is None:
            self._view = View(self)
        return self._view

    def cell(self, name):
        return self.grid.cell_array(name)

    def cracks(self):
        """Crack grid with positions mapped like the field (None without cracks)."""
        if self._cracks is None and self.crack_path:
            try:
                c = cdem_vtu.read_vtu(self.crack_path)
            except VtuError as e:
                print(f"cdem_report: warning: {e}", file=sys.stderr)
                return None
            pts = c.points
            if self.magnify != 1.0 or self.dim == 3:
                # Crack points are copies of block node positions: find their nodes to get
                # the displacement (for magnification and the reference-plane cut).
                idx = match_points(self.grid.points, pts)
                ok = idx >= 0
                uc = np.zeros_like(pts)
                uc[ok] = self.u[idx[ok]]
                Xc = pts - uc
                Pc = Xc + self.magnify * uc
            else:
                Xc, Pc = pts, pts
            self._cracks = (c, Xc, Pc)
        return self._cracks

    # ---- 2D ----
    def polygons_2d(self):
        """[(verts (n, k, 2), cell ids)] per cell type."""
        out = []
        for t in (VTK_TRIANGLE, VTK_QUAD):
            ids = self.grid.cells_of_type(t)
            if ids.size:
                nodes = self.grid.cell_nodes(t)
                out.append((self.P[nodes][:, :, :2], ids))
        return out

    def crack_segments_2d(self):
        c = self.cracks()
        if c is None:
            return None
        grid, _, Pc = c
        nodes = grid.cell_nodes(VTK_LINE)
        if nodes.size == 0:
            return None
        return Pc[nodes][:, :, :2]

    # ---- 3D ----
    def section(self):
        """Cut of the tets by the reference plane X[h2] = section_at:
        [(verts (n, k, 2) in (h1, va) coordinates, cell ids)]."""
        tets = self.grid.cell_nodes(VTK_TETRA)
        ids = self.grid.cells_of_type(VTK_TETRA)
        if tets.size == 0:
            return []
        d = self.X[tets][:, :, self.h2] - self.section_at
        cut = (d.min(1) < 0) & (d.max(1) >= 0)
        tets, ids, d = tets[cut], ids[cut], d[cut]
        edges = np.array([(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)])
        da, db = d[:, edges[:, 0]], d[:, edges[:, 1]]
        cross = (da >= 0) != (db >= 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(cross, da / (da - db), 0.0)
        Pa = self.P[tets[:, edges[:, 0]]][:, :, [self.h1, self.va]]
        Pb = self.P[tets[:, edges[:, 1]]][:, :, [self.h1, self.va]]
        pts = Pa + s[:, :, None] * (Pb - Pa)
        n = cross.sum(1)
        out = []
        for k in (3, 4):
            sel = n == k
            if not sel.any():
                continue
            v = pts[sel][cross[sel]].reshape(-1, k, 2)
            if k == 4:  # order the quad's corners around its centre
                c = v.mean(1, keepdims=True)
                ang = np.arctan2(v[:, :, 1] - c[:, :, 1], v[:, :, 0] - c[:, :, 0])
                v = np.take_along_axis(v, np.argsort(ang, 1)[:, :, None], 1)
            out.append((v, ids[sel]))
        return out

    def crack_section(self):
        """Crack traces in the section plane as segments (m, 2, 2) in (h1, va), or None."""
        c = self.cracks()
        if c is None:
            return None
        grid, Xc, Pc = c
        tri = grid.cell_nodes(VTK_TRIANGLE)
        if tri.size == 0:
            return None
        d = Xc[tri][:, :, self.h2] - self.section_at
        cut = (d.min(1) < 0) & (d.max(1) >= 0)
        tri, d = tri[cut], d[cut]
        edges = np.array([(0, 1), (1, 2), (2, 0)])
        da, db = d[:, edges[:, 0]], d[:, edges[:, 1]]
        cross = (da >= 0) != (db >= 0)
        keep = cross.sum(1) == 2
        if not keep.any():
            return None
        tri, da, db, cross = tri[keep], da[keep], db[keep], cross[keep]
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(cross, da / (da - db), 0.0)
        Pa = Pc[tri[:, edges[:, 0]]][:, :, [self.h1, self.va]]
        Pb = Pc[tri[:, edges[:, 1]]][:, :, [self.h1, self.va]]
        pts = Pa + s[:, :, None] * (Pb - Pa)
        return pts[cross].reshape(-1, 2, 2)

    def top_faces(self):
        """Boundary faces looking up (out of the free surface), lowest first:
        (verts (n, 3, 2) in (h1, h2), cell ids, mean displacement along up)."""
        tets = self.grid.cell_nodes(VTK_TETRA)
        ids = self.grid.cells_of_type(VTK_TETRA)
        if tets.size == 0:
            return None
        # Coincident nodes of neighbouring blocks share their reference position.
        ext = float(np.ptp(self.X, axis=0).max()) or 1.0
        q = np.round(self.X / (1e-7 * ext)).astype(np.int64)
        _, vid = np.unique(q, axis=0, return_inverse=True)
        vid = vid.ravel()
        local = np.array([(1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1)])
        opp = np.array([0, 1, 2, 3])
        faces = tets[:, local].reshape(-1, 3)          # node ids
        keys = np.sort(vid[faces], axis=1)
        _, inv, cnt = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
        inv = inv.ravel()
        bnd = cnt[inv] == 1
        owner = np.repeat(np.arange(len(tets)), 4)[bnd]
        other = tets[:, opp].reshape(-1)[bnd]
        f = faces[bnd]
        a, b, c = self.X[f[:, 0]], self.X[f[:, 1]], self.X[f[:, 2]]
        nrm = np.cross(b - a, c - a)
        flip = np.einsum("ij,ij->i", nrm, self.X[other] - a) > 0
        nrm[flip] *= -1
        facing = nrm @ self.up > 0.2 * np.linalg.norm(nrm, axis=1)
        f, owner = f[facing], owner[facing]
        height = (self.P[f] @ self.up).mean(1)
        order = np.argsort(height, kind="stable")
        f, owner = f[order], owner[order]
        return (self.P[f][:, :, [self.h1, self.h2]], ids[owner],
                (self.u[f] @ self.up).mean(1))


AXIS = "xyz"


class View:
    """What a field picture of one frame draws: polygons with their cell ids, crack segments,
    the axes (indices into xyz), whether the vertical axis is flipped (free surface on top
    when up points to -axis) and the words for titles."""

    def __init__(self, frame):
        if frame.dim == 2:
            self.polys = frame.polygons_2d()
            self.segs = frame.crack_segments_2d()
            self.idx, self.flip, self.where = (0, 1), False, ""
        else:
            self.polys = frame.section()
            self.segs = frame.crack_section()
            self.idx, self.flip = (frame.h1, frame.va), frame.s < 0
            self.where = f"section {AXIS[frame.h2]} = {frame.section_at:.3g} m"
        self.xlabel = f"{AXIS[self.idx[0]]} (m)"
        self.ylabel = f"{AXIS[self.idx[1]]} (m)"


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


def plot_field_grid(run, frames, quantity, out_dir, name, written):
    """A grid of damage or von Mises pictures at several output times."""
    nrows, ncols = grid_shape(len(frames))
    views = [fr.view() for fr in frames]
    box = view_box([v.polys for v in views], frames[-1], views[-1].idx)
    aspect = box_aspect(box)
    shared = quantity == "damage"
    fig, axes = plt.subplots(nrows, ncols, squeeze=False, constrained_layout=True,
                             figsize=figsize_for(ncols, nrows, aspect, 3.6, not shared, shared))
    mappable = None
    for k, ax in enumerate(axes.ravel()):
        if k >= len(frames):
            ax.set_visible(False)
            continue
        fr = frames[k]
        v = views[k]
        polys = v.polys
        if quantity == "damage":
            vals = cell_values(fr, "damage")
            norm = mcolors.Normalize(0, 1)
            cmap = DAMAGE_CMAP
        else:
            vals = cell_values(fr, "von_mises", 1e-6)
            vis = np.concatenate([vals[ids] for _, ids in polys]) if polys else np.zeros(1)
            top = float(np.nanpercentile(vis, 97)) if vis.size else 1.0
            norm = mcolors.Normalize(0, top if top > 0 else 1.0)
            cmap = VM_CMAP
        if vals is None or not polys:
            ax.text(0.5, 0.5, "no data", ha="center", va="center", transform=ax.transAxes)
            ax.set_title(fmt_time(fr.time))
            continue
        m = draw_polys(ax, polys, vals, cmap, norm)
        draw_cracks(ax, v.segs, lw=0.3)
        set_limits(ax, box, v.xlabel, v.ylabel, v.flip)
        ax.set_title(fmt_time(fr.time))
        if k % ncols:
            ax.set_ylabel("")
        if k // ncols < nrows - 1 and k + ncols < len(frames):
            ax.set_xlabel("")
        if quantity == "damage":
            mappable = m
        else:
            cb = colorbar(fig, m, ax=ax, shrink=0.85, extend="max")
            cb.set_label("von Mises (MPa)")
    if quantity == "damage" and mappable is not None:
        cb = colorbar(fig, mappable, ax=axes.ravel().tolist(), shrink=0.8)
        cb.set_label("damage" if nrows * aw_of(fig, ncols) / aspect < 4.5
                     else "damage (broken fraction of interface area)")
    where = f", {views[-1].where}" if views[-1].where else ""
    what = "Damage" if quantity == "damage" else "von Mises stress"
    fig.suptitle(f"{what}{where}: {run.label}{magnify_note(frames[-1])}\n"
                 "black lines: cracks (broken interfaces)")
    return save(fig, out_dir, name, written)


def magnify_note(frame):
    return "" if frame.magnify == 1.0 else f" (displacements x{frame.magnify:g})"


def plot_damage_final(run, frame, out_dir, name, written, ax=None, fig=None):
    """The last damage picture, large (or into a given axes for the comparison)."""
    v = frame.view()
    polys = v.polys
    box = view_box([polys], frame, v.idx)
    own = ax is None
    if own:
        aspect = box_aspect(box)
        fig, ax = plt.subplots(figsize=figsize_for(1, 1, aspect, 6.5, True, False, 2, False),
                               constrained_layout=True)
    vals = cell_values(frame, "damage")
    if vals is None or not polys:
        ax.text(0.5, 0.5, "no damage data", ha="center", va="center", transform=ax.transAxes)
        m = None
    else:
        m = draw_polys(ax, polys, vals, DAMAGE_CMAP, mcolors.Normalize(0, 1))
        draw_cracks(ax, v.segs, lw=0.6 if own else 0.4)
        set_limits(ax, box, v.xlabel, v.ylabel, v.flip)
    where = f", {v.where}" if v.where else ""
    fd = run.summary.get("fracture_degree")
    fdt = f", fracture degree {100 * fd:.1f} %" if isinstance(fd, (int, float)) else ""
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


def plot_fragments_final(run, frame, out_dir, written):
    """The blocks of the last output coloured by fragment (needs the fragment_id array)."""
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
    rgba = fragment_colors(fid)
    for verts, ids in polys:
        ax.add_collection(PolyCollection(verts, facecolors=rgba[ids], edgecolors=rgba[ids],
                                         linewidths=0.15))
    draw_cracks(ax, v.segs, lw=0.3)
    set_limits(ax, box, v.xlabel, v.ylabel, v.flip)
    n = int(np.unique(fid[fid >= 0]).size)
    where = f", {v.where}" if v.where else ""
    ax.set_title(f"Fragments at {fmt_time(frame.time)}{where}: {run.label}{magnify_note(frame)}\n"
                 f"{n} fragments; grey: the largest (the rock mass), colours: the others")
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


def plot_fracture(runs, out_dir, written):
    runs_with = [r for r in runs if r.fracture is not None]
    if not runs_with:
        return None
    tmax = max(float(r.fracture["time"].max()) for r in runs_with)
    tf, tu = time_scale(tmax)
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


def plot_energy(runs, out_dir, written):
    runs_with = [r for r in runs if r.energy is not None]
    if not runs_with:
        return None
    tmax = max(float(r.energy["time"].max()) for r in runs_with)
    tf, tu = time_scale(tmax)
    if len(runs_with) == 1:
        r = runs_with[0]
        e = r.energy
        t = e["time"] * tf
        present = [(c, l, col, ls) for c, l, col, ls in ENERGY_TERMS
                   if c in e and np.nanmax(np.abs(e[c])) > 1e-9 * max(1e-300, max(
                       np.nanmax(np.abs(e[k])) for k, *_ in ENERGY_TERMS if k in e))]
        vmax = max([np.nanmax(np.abs(e[c])) for c, *_ in present] or [1.0])
        sc, unit = energy_scale(vmax)
        fig, (a1, a2) = plt.subplots(2, 1, figsize=(9, 8), sharex=True,
                                     gridspec_kw={"height_ratios": [2.2, 1]}, constrained_layout=True)
        for c, l, col, ls in present:
            a1.plot(t, e[c] * sc, color=col, ls=ls, lw=1.5, label=l)
        a1.set_ylabel(f"energy ({unit})")
        a1.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
        a1.set_title("Energy terms (stored, input work, dissipated)")
        if "error" in e:
            plot_error(a2, t, e["error"], "black")
            fe = r.summary.get("energy_error")
            if isinstance(fe, (int, float)):
                a2.set_title(f"Balance error |balance| / max(|work in|, mechanical energy): "
                             f"final {fe:.2g}")
            else:
                a2.set_title("Balance error |balance| / max(|work in|, mechanical energy)")
        a2.set_ylabel("relative error")
        a2.set_xlabel(f"time ({tu})")
        a2.set_xlim(0, tmax * tf)
        fig.suptitle(f"Energy balance: {r.label}")
        return save(fig, out_dir, "energy.png", written)
    groups = [("kinetic", ["kinetic"]), ("strain (blocks + springs + contacts)",
                                     ["block_strain", "spring_strain", "contact_strain"]),
              ("work input (external + gravity + explosive + insertion)",
               ["external_work", "gravity_work", "explosive_work", "insertion"]),
              ("damping + absorbed", ["damping"]),
              ("fracture + contact dissipation", ["fracture", "contact_friction"])]
    vmax = 1.0
    series = {}
    for r in runs_with:
        for g, cols in groups:
            v = sum((r.energy[c] for c in cols if c in r.energy), np.zeros_like(r.energy["time"]))
            series[(r.label, g)] = v
            vmax = max(vmax, float(np.nanmax(np.abs(v))) if v.size else 0)
    sc, unit = energy_scale(vmax)
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


def plot_grading(runs, out_dir, written, notes):
    data = [(r, grading_data(r)) for r in runs]
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
    if allsize.size and allsize.max() / allsize.min() > 20:
        ax.set_xscale("log")
        ax.xaxis.set_major_locator(matplotlib.ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_ylim(0, 102)
    ax.set_xlabel("fragment size L_bc (m)")
    ax.set_ylabel("cumulative volume passing (%)")
    ax.set_title("Fragment size grading" + ("" if len(data) > 1 else f": {data[0][0].label}"))
    ax.legend(loc="lower right")
    return save(fig, out_dir, "grading.png", written)


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
        runs = [Run(d) for d in args.runs]
    except VtuError as ex:
        print(f"cdem_report: {ex}", file=sys.stderr)
        return 2
    # Unique labels: runs sharing a title are told apart by their directory names.
    counts = {}
    for r in runs:
        counts[r.label] = counts.get(r.label, 0) + 1
    for r in runs:
        if counts[r.label] > 1:
            r.label = f"{r.label} [{os.path.basename(r.dir)}]"
    seen = set()
    for i, r in enumerate(runs):
        if r.label in seen:
            r.label = f"{r.label} #{i + 1}"
        seen.add(r.label)
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


if __name__ == "__main__":
    sys.exit(main())
