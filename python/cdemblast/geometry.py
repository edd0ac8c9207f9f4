"""Geometry of one field output (a VTU file of a run): the blocks in their reference,
current and drawn positions; 2D polygons, the 3D vertical section and the view of the free
surface; block sizes, volumes and centroids; the charge length a hole's axis runs through
each block. docs/report.md, "Field pictures", describes the conventions.
"""

from __future__ import annotations

import sys

import numpy as np

from . import vtu
from .vtu import VTK_LINE, VTK_QUAD, VTK_TETRA, VTK_TRIANGLE, VtuError

AXIS = "xyz"


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

    def __init__(self, run, index, magnify=1.0):
        self.time, path = run.fields[index]
        self.path = path
        self.index = index
        self.grid = g = vtu.read_vtu(path)
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
                c = vtu.read_vtu(self.crack_path)
            except VtuError as e:
                print(f"cdemblast: warning: {e}", file=sys.stderr)
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

    def _crack_cells(self, vtk_type):
        """(reference, drawn positions, node ids of the crack cells of a type), or None."""
        c = self.cracks()
        if c is None:
            return None
        grid, Xc, Pc = c
        nodes = grid.cell_nodes(vtk_type)
        return None if nodes.size == 0 else (Xc, Pc, nodes)

    def crack_segments_2d(self):
        c = self._crack_cells(VTK_LINE)
        return None if c is None else c[1][c[2]][:, :, :2]

    # ---- 3D ----
    def _cut(self, X, P, elems, edges):
        """Where the edges of the elements (node ids, (n, k)) cross the reference plane
        X[h2] = section_at: (kept elements, crossing points (m, e, 2) in (h1, va) at the drawn
        positions P, crossing mask (m, e)). X: reference positions deciding the cut."""
        d = X[elems][:, :, self.h2] - self.section_at
        keep = (d.min(1) < 0) & (d.max(1) >= 0)
        elems, d = elems[keep], d[keep]
        da, db = d[:, edges[:, 0]], d[:, edges[:, 1]]
        cross = (da >= 0) != (db >= 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(cross, da / (da - db), 0.0)
        Pa = P[elems[:, edges[:, 0]]][:, :, [self.h1, self.va]]
        Pb = P[elems[:, edges[:, 1]]][:, :, [self.h1, self.va]]
        return keep, Pa + s[:, :, None] * (Pb - Pa), cross

    def section(self):
        """Cut of the tets by the reference plane X[h2] = section_at:
        [(verts (n, k, 2) in (h1, va) coordinates, cell ids)]."""
        tets = self.grid.cell_nodes(VTK_TETRA)
        ids = self.grid.cells_of_type(VTK_TETRA)
        if tets.size == 0:
            return []
        edges = np.array([(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)])
        keep, pts, cross = self._cut(self.X, self.P, tets, edges)
        ids = ids[keep]
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
        c = self._crack_cells(VTK_TRIANGLE)
        if c is None:
            return None
        Xc, Pc, tri = c
        _keep, pts, cross = self._cut(Xc, Pc, tri, np.array([(0, 1), (1, 2), (2, 0)]))
        two = cross.sum(1) == 2
        if not two.any():
            return None
        return pts[two][cross[two]].reshape(-1, 2, 2)

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


# ----------------------------------------------------------------------------- block measures
def cell_node_lists(grid):
    """[(cell ids, (n, k) node ids)] per cell type present (triangles, quads, tets)."""
    out = []
    for t in (VTK_TRIANGLE, VTK_QUAD, VTK_TETRA):
        ids = grid.cells_of_type(t)
        if ids.size:
            out.append((ids, grid.cell_nodes(t)))
    return out


def polygon_area(p):
    """Areas of polygons (n, k, 2) by the shoelace formula (counter-clockwise positive)."""
    x, y = p[..., 0], p[..., 1]
    return 0.5 * np.sum(x * np.roll(y, -1, axis=-1) - np.roll(x, -1, axis=-1) * y, axis=-1)


def block_measures(X, grid):
    """Per cell of `grid` at positions X (reference, normally): volume (3D m3; 2D area x 1 m),
    centroid (3), longest side of the bounding box l_max, the characteristic size of the
    block alone (eq. 17: (V^(1/3) + L_max) / 2; 2D (A^(1/2) + L_max) / 2) and the largest
    edge length. Cells of other types get NaN."""
    n = grid.ncells
    vol = np.full(n, np.nan)
    cen = np.full((n, 3), np.nan)
    lmax = np.full(n, np.nan)
    edge = np.full(n, np.nan)
    dim2 = not np.any(grid.types == VTK_TETRA)
    for ids, nodes in cell_node_lists(grid):
        P = X[nodes]
        cen[ids] = P.mean(1)
        lmax[ids] = np.ptp(P, axis=1).max(1)
        k = nodes.shape[1]
        if dim2:
            vol[ids] = np.abs(polygon_area(P[:, :, :2]))
            e = np.linalg.norm(P - np.roll(P, -1, axis=1), axis=2)
        else:
            a, b, c, d = P[:, 0], P[:, 1], P[:, 2], P[:, 3]
            vol[ids] = np.abs(np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))) / 6.0
            pairs = [(i, j) for i in range(k) for j in range(i + 1, k)]
            e = np.stack([np.linalg.norm(P[:, i] - P[:, j], axis=1) for i, j in pairs], 1)
        edge[ids] = e.max(1)
    size = 0.5 * ((np.sqrt(vol) if dim2 else np.cbrt(vol)) + lmax)
    return {"volume": vol, "centroid": cen, "l_max": lmax, "l_bc": size, "edge": edge}


def _clip(planes, a, b, n):
    """Cyrus-Beck clipping of the segment a + t (b - a), t in [0, 1], against n convex cells
    given as their bounding planes [(inward normals (n, dim), points on the planes (n, dim))]:
    (t0, t1) of the part inside each cell; t1 < t0 when the segment misses it."""
    d = b - a
    t0, t1 = np.zeros(n), np.ones(n)
    for nrm, p in planes:
        num = np.einsum("ij,ij->i", nrm, a - p)
        den = nrm @ d
        with np.errstate(divide="ignore", invalid="ignore"):
            t = -num / den
        t0 = np.where(den > 0, np.maximum(t0, t), t0)
        t1 = np.where(den < 0, np.minimum(t1, t), t1)
        t1 = np.where((den == 0) & (num < 0), -1.0, t1)
    return t0, t1


def _clip_triangles(tri, a, b):
    """(t0, t1) of the segment a-b inside each triangle (n, 3, 2)."""
    sgn = np.where(polygon_area(tri) >= 0, 1.0, -1.0)[:, None]
    planes = []
    for i in range(3):
        p, q = tri[:, i], tri[:, (i + 1) % 3]
        e = q - p
        planes.append((sgn * np.stack([-e[:, 1], e[:, 0]], 1), p))  # inward normal of p->q
    return _clip(planes, a, b, len(tri))


def _clip_tets(tet, a, b):
    """(t0, t1) of the segment a-b inside each tetrahedron (n, 4, 3)."""
    planes = []
    for i, j, k, o in ((1, 2, 3, 0), (0, 3, 2, 1), (0, 1, 3, 2), (0, 2, 1, 3)):
        p, q, r = tet[:, i], tet[:, j], tet[:, k]
        nrm = np.cross(q - p, r - p)
        s = np.einsum("ij,ij->i", nrm, tet[:, o] - p)
        planes.append((np.where(s[:, None] < 0, -nrm, nrm), p))  # inward: to the opposite vertex
    return _clip(planes, a, b, len(tet))


def segment_length_per_block(X, grid, a, b, samples=1000):
    """The length (m) of the segment a-b that runs through each block (positions X).

    The segment is clipped against every block; a piece along a face or an edge shared by
    several blocks is split equally among them (each of `samples` points along the segment
    gives its share to every block whose clipped interval holds it), so the lengths add up to
    the part of the segment inside the mesh. Returns an array over the cells."""
    a = np.asarray(a, float)[:3]
    b = np.asarray(b, float)[:3]
    out = np.zeros(grid.ncells)
    seg_len = float(np.linalg.norm(b - a))
    if seg_len == 0:
        return out
    dim2 = not np.any(grid.types == VTK_TETRA)
    tol = 1e-9 * (float(np.ptp(X, axis=0).max()) or 1.0)
    ids_all, t0_all, t1_all = [], [], []
    for ids, nodes in cell_node_lists(grid):
        P = X[nodes]
        lo, hi = P.min(1), P.max(1)
        near = np.all((hi >= np.minimum(a, b) - tol) & (lo <= np.maximum(a, b) + tol), axis=1)
        if not near.any():
            continue
        ids, P = ids[near], P[near]
        if dim2:
            parts = [_clip_triangles(P[:, [0, 1, 2], :2], a[:2], b[:2])]
            if P.shape[1] == 4:
                parts.append(_clip_triangles(P[:, [0, 2, 3], :2], a[:2], b[:2]))
            for t0, t1 in parts:
                ids_all.append(ids)
                t0_all.append(t0)
                t1_all.append(t1)
        else:
            t0, t1 = _clip_tets(P, a, b)
            ids_all.append(ids)
            t0_all.append(t0)
            t1_all.append(t1)
    if not ids_all:
        return out
    ids = np.concatenate(ids_all)
    t0 = np.concatenate(t0_all)
    t1 = np.concatenate(t1_all)
    keep = t1 > t0
    ids, t0, t1 = ids[keep], t0[keep], t1[keep]
    if ids.size == 0:
        return out
    s = (np.arange(samples) + 0.5) / samples
    cover = (t0[:, None] <= s[None, :]) & (s[None, :] <= t1[:, None])  # (pieces, samples)
    # the two triangles of one quad must not count twice: merge pieces per block
    blocks, inv = np.unique(ids, return_inverse=True)
    bcover = np.zeros((blocks.size, samples), bool)
    np.logical_or.at(bcover, inv, cover)
    count = bcover.sum(0)
    share = np.where(count > 0, 1.0 / np.maximum(count, 1), 0.0) * (seg_len / samples)
    out[blocks] = (bcover * share[None, :]).sum(1)
    return out
