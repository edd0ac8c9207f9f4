#!/usr/bin/python3
"""Run the variants of a study and compare them (docs/study.md). A thin command: the study is
python/cdemblast/study.py.

    cdem_study.py FILE [--out DIR] [--threads N] [--no-run] [--bin PATH] [--no-pictures] [-v]
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "python"))
try:
    from cdemblast.study import main
except ImportError as e:  # numpy or matplotlib missing
    sys.exit(f"cdem_study: {e}; run it with a python3 that has numpy and matplotlib "
             "(Debian: /usr/bin/python3 with python3-numpy and python3-matplotlib)")

if __name__ == "__main__":
    sys.exit(main())
