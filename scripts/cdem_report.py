#!/usr/bin/python3
"""Turn finished cdemblast runs into PNG pictures, a summary.md, an index.html and a
report.json (docs/report.md). A thin command: the report is python/cdemblast/report.py.

    cdem_report.py RUN [RUN ...] [--out OUTDIR] [--frames N] [--magnify M] [--design TOML]
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "python"))
from cdemblast.report import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
