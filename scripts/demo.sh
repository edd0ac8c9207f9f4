#!/usr/bin/env bash
# make demo: run the bundled example (SPEC 5.1, the bar explosion model) and draw its report.
set -euo pipefail
bin=${1:-build/bin/cdemblast}
out=${2:-runs/demo}
case_file=examples/single_hole_2d/bar.toml
echo "== cdemblast demo: $case_file -> $out"
"$bin" check "$case_file"
"$bin" run "$case_file" --out "$out" --overwrite
"$bin" report "$out"
echo
echo "== done. Look at:"
echo "   $out/report/index.html      plots and key numbers (open in a browser)"
echo "   $out/fields.pvd             fields over time (open in ParaView)"
echo "   $out/cracks.pvd             broken interfaces (ParaView)"
echo "   $out/summary.json           key numbers"
