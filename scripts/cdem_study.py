#!/usr/bin/python3
"""Run the variants of a study and compare them (docs/study.md). A thin command: the study is
python/cdemblast/study.py.

    cdem_study.py FILE [--out DIR] [--threads N] [--no-run] [--bin PATH] [--no-pictures] [-v]
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "python"))
from cdemblast.study import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
