#!/usr/bin/env python3
"""The cost-growth curve (docs/performance.md, "Cost growth"): `cdemblast bench --json` at several
model sizes, drawn as a PNG with its markdown table.

  scripts/cost_growth.py --bin build/bin/cdemblast --sizes 30000 100000 300000 1000000 \\
      --dir runs/growth --out docs/img/cost_growth.png
runs the bench at each size that has no report in --dir yet (BENCH_ARGS: more bench options),
then draws; with --no-run it only draws the reports found in --dir."""

import argparse
import glob
import os
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))

from cdemblast.perf import growth_rows, growth_table, plot_growth, read_bench  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default="build/bin/cdemblast")
    ap.add_argument("--sizes", type=int, nargs="+", default=[30000, 100000, 300000, 1000000])
    ap.add_argument("--dir", required=True, help="where the bench reports are kept (bench_<blocks>.json)")
    ap.add_argument("--out", required=True, help="the PNG to write")
    ap.add_argument("--no-run", action="store_true")
    ap.add_argument("--bench-args", default="--steps 20 --warmup-broken 0 --threads 2")
    args = ap.parse_args(argv)
    os.makedirs(args.dir, exist_ok=True)
    if not args.no_run:
        for n in args.sizes:
            path = os.path.join(args.dir, f"bench_{n}.json")
            if os.path.exists(path) and os.path.getsize(path) > 0:
                continue
            cmd = [args.bin, "bench", "--blocks", str(n), "--json", *args.bench_args.split()]
            print(" ".join(cmd), flush=True)
            out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
            with open(path, "w", encoding="utf-8") as f:
                f.write(out)
    reports = [read_bench(p) for p in sorted(glob.glob(os.path.join(args.dir, "bench_*.json")))
               if os.path.getsize(p) > 0]
    if not reports:
        sys.exit(f"no bench reports in {args.dir}")
    rows = growth_rows(reports)
    print(plot_growth(rows, args.out, "cdemblast bench: cost against model size"))
    print(growth_table(rows))


if __name__ == "__main__":
    main()
