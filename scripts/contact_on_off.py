#!/usr/bin/env python3
"""The nodes inside a block of another fragment at the last field output of runs (without
contact, with it, with contact.candidates = "cracked"), counted and drawn side by side
(scripts/contact_on_off.sh)."""

import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))

import numpy as np  # noqa: E402

from cdemblast import vtu  # noqa: E402
from cdemblast.overlap import penetrating_nodes  # noqa: E402
from cdemblast.plots import plt  # noqa: E402
from cdemblast.run import Run  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("runs", nargs="+", metavar="LABEL=RUN", help="a label and a run directory")
    ap.add_argument("--out", required=True, help="the PNG to write")
    args = ap.parse_args(argv)
    runs = [r.split("=", 1) if "=" in r else (os.path.basename(r.rstrip("/")), r) for r in args.runs]
    fig, axes = plt.subplots(1, len(runs), figsize=(5.2 * len(runs) + 0.6, 4.8),
                             constrained_layout=True, sharey=True, squeeze=False)
    axes = axes[0]
    rows = []
    for ax, (label, d) in zip(axes, runs):
        run = Run(d)
        if not run.fields:
            print(f"contact_on_off: {d}: no field output", file=sys.stderr)
            return 2
        t, path = run.fields[-1]
        g = vtu.read_vtu(path)
        x = g.points
        nodes, depth, _ = penetrating_nodes(g)
        shared, _, _ = penetrating_nodes(g, shared_vertex=True)
        ax.scatter(x[:, 0], x[:, 2], s=0.2, c="0.75", rasterized=True)
        if len(nodes):
            ax.scatter(x[nodes, 0], x[nodes, 2], s=4 + 400 * depth, c="crimson", alpha=0.7)
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_title(f"{label}: {len(nodes)} node{'' if len(nodes) == 1 else 's'} inside another fragment\n"
                     f"deepest {1e3 * (depth.max() if len(depth) else 0):.1f} mm "
                     f"(t = {1e3 * t:.2f} ms)")
        rows.append((label, len(nodes), depth.max() if len(depth) else 0.0,
                     float(np.mean(depth)) if len(depth) else 0.0, len(shared), len(x)))
    axes[0].set_ylabel("z (m)")
    fig.suptitle("examples/multihole_3d/bar.toml, side view. Grey: all nodes; red: nodes inside a "
                 "block of another fragment\nthey share no mesh vertex with (size by depth)",
                 fontsize=11)
    fig.savefig(args.out, dpi=130)
    print("| run | nodes inside another fragment | deepest (mm) | mean depth (mm) | "
          "inside at a shared vertex (broken, not released) | nodes |")
    print("|---|---|---|---|---|---|")
    for label, n, dmax, dmean, ns, nn in rows:
        print(f"| {label} | {n} | {1e3 * dmax:.2f} | {1e3 * dmean:.2f} | {ns} | {nn} |")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
