#!/usr/bin/env bash
# Rewrites tests/regression/single_hole_reference.json, the reference values of the SPEC 5.1
# regression test (tests/regression/test_single_hole_regression.sh), from fresh runs.
#
# Run it ONLY when a change of the results is intended (a physics fix, a new default, a changed
# example case), check the diff of the JSON (git diff) and say why the numbers moved in the
# commit message. The test itself never rewrites the reference.
#
# Usage: scripts/regenerate_regression.sh [cdemblast-binary] [repo-root]
#   binary: default $CDEM_BIN, else <repo>/build/bin/cdemblast; repo: default this script's repo.
#
# The coarse settings (the --set options) live here and are written into the JSON; the test
# reads them from there, so the test always runs exactly what the reference was made from.
set -euo pipefail
ROOT=${2:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)}
ROOT=$(cd "$ROOT" && pwd)
BIN=${1:-${CDEM_BIN:-$ROOT/build/bin/cdemblast}}
[[ -x $BIN ]] || { echo "regenerate_regression: no executable cdemblast at $BIN" >&2; exit 1; }
PY=${PYTHON:-/usr/bin/python3}
[[ -x $PY ]] || PY=python3
REF=$ROOT/tests/regression/single_hole_reference.json

# The coarse SPEC 5.1 pair: 0.2 m elements, no refinement near the hole, 1 ms (the stress wave
# has passed all three monitors by 0.7 ms), no field files. 256 blocks, well under a second a run.
SETS=(
  "mesh.generate.element_size=0.2"
  "mesh.generate.refine=[]"
  "simulation.end_time=1e-3"
  "simulation.output_times=[]"
)
args=()
for s in "${SETS[@]}"; do args+=(--set "$s"); done

TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
for c in bar solid; do
  "$BIN" run "$ROOT/examples/single_hole_2d/$c.toml" --out "$TMP/$c" -q --threads 1 "${args[@]}"
done

"$PY" - "$TMP" "$REF" "$("$BIN" --version)" "${SETS[@]}" <<'EOF'
import json, sys, datetime
tmp, ref, version, sets = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
out = {
    "description": "SPEC 5.1 single hole, coarse bar/solid pair: reference values of "
                   "tests/regression/test_single_hole_regression.sh. Rewrite only with "
                   "scripts/regenerate_regression.sh, when a change of results is intended.",
    "generated_with": version,
    "generated_on": datetime.date.today().isoformat(),
    "cases": ["examples/single_hole_2d/bar.toml", "examples/single_hole_2d/solid.toml"],
    "set": sets,
    "threads": 1,
    "values": {},
}
for c in ("bar", "solid"):
    s = json.load(open(f"{tmp}/{c}/summary.json"))
    if s.get("status", "finished") != "finished":
        sys.exit(f"regenerate_regression: the {c} run did not finish: {s.get('status')}")
    out["values"][c] = {
        "blocks": s["blocks"],
        "steps": s["steps"],
        "fracture_degree": s["fracture_degree"],
        "fracture_degree_tensile": s["fracture_degree_tensile"],
        "fracture_degree_shear": s["fracture_degree_shear"],
        "explosive_work": s["explosive_work"],
        "energy_error": s["energy_error"],
        "monitors": {k: {"peak_von_mises": v["peak_von_mises"], "time": v["time"]}
                     for k, v in s["monitors"].items()},
    }
with open(ref, "w") as f:
    json.dump(out, f, indent=2)
    f.write("\n")
print(f"regenerate_regression: wrote {ref}")
for c, v in out["values"].items():
    peaks = ", ".join(f"{k} {m['peak_von_mises'] / 1e6:.2f} MPa" for k, m in v["monitors"].items())
    print(f"  {c}: {v['blocks']} blocks, fracture degree {v['fracture_degree']:.4f}, "
          f"explosive work {v['explosive_work'] / 1e6:.3f} MJ/m, peaks {peaks}")
EOF
