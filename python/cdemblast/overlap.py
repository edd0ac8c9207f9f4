"""Interpenetration of fragments in a field output: the nodes that lie inside a block of
another fragment (docs/verification_contact.md, "With and without contact").

A node of fragment A lies inside tetrahedron T of fragment B != A when its barycentric
coordinates in T are all above tol (tol = 1e-3: a node on a face, where fragments touch, does
not count). Its depth is its distance to T's nearest face. A node that shares its mesh vertex
with T (the same reference position as one of T's corners) is counted apart: the two are
joined there by a spring point, broken but not yet released, which is their contact until it
is released (general contact leaves such pairs to it); a corner of T swung past the node by a
crack's shear holds the node without the fragments passing through each other. Candidate tetrahedra come from a
k-d tree over the tetrahedra's centroids, queried within the largest circumradius.
"""

from __future__ import annotations

import numpy as np

from .vtu import VTK_TETRA


def penetrating_nodes(grid, tol=1e-3, shared_vertex=False):
    """(node indices, depths (m), the fragment of each node) of the nodes of a 3D field output
    that lie inside a block of another fragment with which they share no mesh vertex (with
    shared_vertex=True: those that share one, instead)."""
    from scipy.spatial import cKDTree

    tets = grid.cell_nodes(VTK_TETRA)
    frag = grid.cell_array("fragment_id")
    if tets is None or len(tets) == 0 or frag is None:
        return np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int64)
    tet_cells = grid.cells_of_type(VTK_TETRA)
    frag = np.asarray(frag).astype(np.int64)[tet_cells]
    x = grid.points
    u = grid.point_array("displacement")
    X = x - (u if u is not None else 0.0)              # reference positions
    corners = x[tets]                                  # (nt, 4, 3)
    cen = corners.mean(axis=1)
    rad = np.sqrt(((corners - cen[:, None, :]) ** 2).sum(-1)).max(1)
    node_frag = np.full(len(x), -1, np.int64)
    node_frag[tets.ravel()] = np.repeat(frag, 4)
    # barycentric transform per tet: lambda_1..3 = M (p - x0), lambda_0 = 1 - sum
    d = corners[:, 1:, :] - corners[:, :1, :]           # (nt, 3, 3): rows x1-x0, x2-x0, x3-x0
    det = np.linalg.det(d)
    ok = np.abs(det) > 1e-30
    minv = np.zeros_like(d)
    minv[ok] = np.linalg.inv(np.transpose(d[ok], (0, 2, 1)))
    tree = cKDTree(cen)
    hits_node, hits_tet = [], []
    for n, cand in enumerate(tree.query_ball_point(x, rad.max())):
        if not cand:
            continue
        c = np.asarray(cand)
        c = c[(frag[c] != node_frag[n]) & ok[c]]
        if len(c) == 0:
            continue
        lam = np.einsum("kij,kj->ki", minv[c], x[n] - corners[c, 0, :])
        lam = np.concatenate([1.0 - lam.sum(1, keepdims=True), lam], 1)
        inside = (lam > tol).all(1)
        for t in c[inside]:
            shares = bool((np.abs(X[tets[t]] - X[n]).max(1) < 1e-9).any())
            if shares != shared_vertex:
                continue
            hits_node.append(n)
            hits_tet.append(t)
    if not hits_node:
        return np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int64)
    hn, ht = np.asarray(hits_node), np.asarray(hits_tet)
    # depth: the distance to the nearest face plane of the tet holding the node
    depth = np.full(len(hn), np.inf)
    for f in ((1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)):
        a, b, c3 = corners[ht, f[0]], corners[ht, f[1]], corners[ht, f[2]]
        nrm = np.cross(b - a, c3 - a)
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
        depth = np.minimum(depth, np.abs(((x[hn] - a) * nrm).sum(1)))
    # one row per node: its deepest
    order = np.lexsort((-depth, hn))
    hn, depth = hn[order], depth[order]
    first = np.r_[True, hn[1:] != hn[:-1]]
    return hn[first], depth[first], node_frag[hn[first]]
