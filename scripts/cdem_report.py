#!/usr/bin/python3
"""Turn finished cdemblast runs into PNG pictures, a summary.md, an index.html and a
report.json (docs/report.md). A thin command: the report is python/cdemblast/report.py.

    cdem_report.py RUN [RUN ...] [--out OUTDIR] [--frames N] [--magnify M]
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "python"))
try:
    from cdemblast.report import main
except ImportError as e:  # numpy or matplotlib missing
    sys.exit(f"cdem_report: {e}; run it with a python3 that has numpy and matplotlib "
             "(Debian: /usr/bin/python3 with python3-numpy and python3-matplotlib)")

if __name__ == "__main__":
    sys.exit(main())
