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
