#!/usr/bin/env bash
# The Python package's unit tests (tests/python/test_*.py, unittest): the yardsticks
# (Kuz-Ram, Swebrec, PPV fit), the VTU reader and the study's helpers.
#
#   bash test_python.sh <cdemblast-binary> <repo-root>
set -euo pipefail
ROOT=${2:?usage: test_python.sh <cdemblast-binary> <repo-root>}
PY=/usr/bin/python3
"$PY" -c 'import numpy, matplotlib' 2>/dev/null ||
  { echo "FAIL: $PY lacks numpy or matplotlib (apt-get install python3-numpy python3-matplotlib)" >&2; exit 1; }
cd "$ROOT"
PYTHONPATH="$ROOT/python" MPLBACKEND=Agg "$PY" -m unittest discover -s tests/python -p 'test_*.py' -v
