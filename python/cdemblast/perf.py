"""Performance figures from `cdemblast bench --json` reports: the cost-growth curve (ns per
block-step and bytes per block against the model size, with the set-up time per part) and its
table (docs/performance.md, "Cost growth")."""

from __future__ import annotations

import json
import os

from .plots import DPI, plt

SETUP_PARTS = ("mesh", "topology", "charges", "simulation")


def read_bench(path: str) -> dict:
    """One `cdemblast bench --json` report (a file holding its one JSON object)."""
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def growth_rows(reports: list[dict]) -> list[dict]:
    """Per report, ascending in blocks: the figures of the cost-growth curve, each cost also as a
    ratio to the smallest model's."""
    rows = []
    for d in sorted(reports, key=lambda r: r["blocks"]):
        rows.append({
            "blocks": d["blocks"],
            "ns_2t": d["ns_per_block_step_2_threads"],
            "ns_1t": d["ns_per_block_step_1_thread"],
            "speedup": d["speedup_2_threads"],
            "bytes_per_block": d["bytes_per_block_with_solver"],
            "setup_s": d["setup_s"]["total"],
            **{f"setup_{p}_s": d["setup_s"][p] for p in SETUP_PARTS},
        })
    if rows:
        for r in rows:
            r["ns_2t_ratio"] = r["ns_2t"] / rows[0]["ns_2t"]
            r["setup_us_per_block"] = 1e6 * r["setup_s"] / r["blocks"]
    return rows


def plot_growth(rows: list[dict], out_png: str, title: str = "") -> str:
    """Three panels against the block count: ns per block-step (1 and 2 threads), bytes per block
    (with the 1 KiB target), set-up time per block by part (labelled with the total).
    Returns the PNG's path."""
    n = [r["blocks"] for r in rows]
    fig, ax = plt.subplots(1, 3, figsize=(14, 4.2), constrained_layout=True)
    ax[0].plot(n, [r["ns_1t"] for r in rows], "o-", label="1 thread")
    ax[0].plot(n, [r["ns_2t"] for r in rows], "s-", label="2 threads")
    if rows:
        ax[0].axhline(1.25 * rows[0]["ns_2t"], color="0.5", ls=":", label="1.25 x the smallest (2 threads)")
    ax[0].set_ylabel("ns per block-step")
    ax[0].set_ylim(bottom=0)
    ax[1].plot(n, [r["bytes_per_block"] for r in rows], "o-", label="model + solver arrays")
    ax[1].axhline(1024, color="0.5", ls=":", label="target 1 KiB")
    ax[1].set_ylabel("bytes per block")
    ax[1].set_ylim(0, 1300)
    # set-up per block by part: flat bars = set-up linear in the model size
    bottom = [0.0] * len(rows)
    for p in SETUP_PARTS:
        v = [1e6 * r[f"setup_{p}_s"] / r["blocks"] for r in rows]
        ax[2].bar(range(len(rows)), v, bottom=bottom, label=p)
        bottom = [b + x for b, x in zip(bottom, v)]
    for i, r in enumerate(rows):
        ax[2].annotate(f"{r['setup_s']:.1f} s", (i, bottom[i]), ha="center", va="bottom", fontsize=8)
    ax[2].set_xticks(range(len(rows)), [f"{b / 1e3:.0f}k" for b in n])
    ax[2].set_ylabel("set-up per block (µs; flat = linear)")
    ax[2].set_ylim(0, 1.2 * max(bottom) if bottom else 1)
    for a in ax[:2]:
        a.set_xscale("log")
    for a in ax:
        a.set_xlabel("blocks")
        a.grid(alpha=0.3)
        a.legend(fontsize=8, loc="lower right", framealpha=0.9)
    if title:
        fig.suptitle(title)
    os.makedirs(os.path.dirname(os.path.abspath(out_png)), exist_ok=True)
    fig.savefig(out_png, dpi=DPI)
    plt.close(fig)
    return out_png


def growth_table(rows: list[dict]) -> str:
    """The markdown table of the curve."""
    head = ("| blocks | ns/block-step 2T | 1T | 2T speed-up | vs smallest (2T) | bytes/block | "
            "set-up (s): mesh + topology + charges + simulation = total | µs per block |")
    lines = [head, "|" + "---:|" * 8]
    for r in rows:
        parts = " + ".join(f"{r[f'setup_{p}_s']:.2f}" for p in SETUP_PARTS)
        lines.append(f"| {r['blocks']:,} | {r['ns_2t']:.1f} | {r['ns_1t']:.1f} | {r['speedup']:.2f} | "
                     f"{r['ns_2t_ratio']:.2f} | {r['bytes_per_block']:.0f} | {parts} = {r['setup_s']:.2f} | "
                     f"{r['setup_us_per_block']:.1f} |".replace(",", " "))
    return "\n".join(lines)


def roofline_points(report: dict) -> dict:
    """The roofline position of one `cdemblast bench --json` report of a tet model: the block
    kernel (its flops counted from the source, its bytes the bench's estimate, its time the
    kernel split's) and the whole step (a lower bound: the block kernel's flops over all the
    step's bytes)."""
    nb = report["blocks"]
    flops = report["tet_flops_per_block"]
    step_bytes = report["step_bytes_estimate"] / nb
    return {
        "peak": report["peak_gflops"],
        "triad": report["triad_gb_s"],
        "triad_ws": report["triad_ws_gb_s"],
        "kernel_ai": flops / report["block_kernel_bytes_per_block"],
        "kernel_gflops": report["block_kernel_gflops"],
        "step_ai": flops / step_bytes,
        "step_gflops": flops / report["ns_per_block_step"],
    }


def plot_roofline(reports: list[tuple[str, dict]], out_png: str, title: str = "") -> str:
    """Roofline (log-log): the measured peak and the two triad bandwidths (memory, and the
    model-size working set), with each report's block kernel (filled) and whole step (open, a
    lower bound) marked. Returns the PNG's path."""
    pts = [(label, roofline_points(r)) for label, r in reports]
    fig, ax = plt.subplots(figsize=(7.5, 5), constrained_layout=True)
    ai = [10 ** (k / 20) for k in range(-40, 41)]  # 0.01 to 100 flop/B
    p0 = pts[0][1]
    ax.plot(ai, [min(p0["peak"], a * p0["triad"]) for a in ai], "k-",
            label=f"peak {p0['peak']:.0f} GFlop/s, triad {p0['triad']:.0f} GB/s")
    ax.plot(ai, [min(p0["peak"], a * p0["triad_ws"]) for a in ai], "k:",
            label=f"triad over the model's size {p0['triad_ws']:.0f} GB/s")
    markers = "osD^v<>"
    for i, (label, p) in enumerate(pts):
        c = f"C{i}"
        ax.plot(p["kernel_ai"], p["kernel_gflops"], markers[i % 7], color=c, ms=8,
                label=f"{label}: block kernel")
        ax.plot(p["step_ai"], p["step_gflops"], markers[i % 7], color=c, ms=8, mfc="none",
                label=f"{label}: whole step (lower bound)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("arithmetic intensity (flop per byte)")
    ax.set_ylabel("GFlop/s")
    ax.set_xlim(0.01, 100)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="lower right", framealpha=0.9)
    if title:
        ax.set_title(title, fontsize=10)
    os.makedirs(os.path.dirname(os.path.abspath(out_png)), exist_ok=True)
    fig.savefig(out_png, dpi=DPI)
    plt.close(fig)
    return out_png
