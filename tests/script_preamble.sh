# The common start of the script tests (tests/*/test_*.sh), sourced with the script's arguments:
#   source "$(dirname "$0")/../script_preamble.sh" "$@"
# sets BIN (the cdemblast binary) and ROOT (the repository), PY (Debian's python3), fail (print
# FAIL and exit 1), TMP (a directory removed at exit), and passive OpenMP waiting (ctest runs
# tests side by side: spinning threads of one would hold the cores of another).
set -euo pipefail
BIN=${1:?usage: $(basename "$0") <cdemblast-binary> <repo-root>}
ROOT=${2:?usage: $(basename "$0") <cdemblast-binary> <repo-root>}
PY=/usr/bin/python3
fail() { echo "FAIL: $*" >&2; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
export OMP_WAIT_POLICY=PASSIVE
