#!/usr/bin/env python3
"""The roofline of the step (docs/performance.md, "Roofline"): reads `cdemblast bench --json`
reports of tet models and draws the measured peak and bandwidths with each report's block kernel
and whole step.

  build/bin/cdemblast bench --json --threads 2 > runs/roofline/default.json
  build/bin/cdemblast bench --json --threads 2 --warmup-broken 0.3 --steps 100 > runs/roofline/cracked.json
  scripts/roofline.py --out docs/img/roofline.png default=runs/roofline/default.json \\
      cracked=runs/roofline/cracked.json"""

import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))

from cdemblast.perf import plot_roofline, read_bench, roofline_points  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, help="the PNG to write")
    ap.add_argument("--title", default="")
    ap.add_argument("reports", nargs="+", help="LABEL=FILE, a bench --json report each")
    args = ap.parse_args(argv)
    reports = []
    for item in args.reports:
        label, sep, path = item.partition("=")
        if not sep:
            ap.error(f"{item}: expected LABEL=FILE")
        reports.append((label, read_bench(path)))
    for label, r in reports:
        p = roofline_points(r)
        print(f"{label}: block kernel {p['kernel_ai']:.2f} flop/B, {p['kernel_gflops']:.2f} GFlop/s; "
              f"whole step >= {p['step_ai']:.3f} flop/B, >= {p['step_gflops']:.2f} GFlop/s; "
              f"peak {p['peak']:.1f} GFlop/s, triad {p['triad']:.1f} GB/s")
    print(plot_roofline(reports, args.out, args.title))


if __name__ == "__main__":
    main()
