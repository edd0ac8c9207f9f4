#!/usr/bin/env bash
# The three gas models on a 3D cylinder (docs/verification_gas.md, "3D"): SPEC 5.3 scheme A on
# the coarse pile-pit mesh (8 380 tets), 5 ms, gas = cracks, cavity and literal, then the
# comparison (table and runs/gas3d/gas_models_3d.png).
#   bash scripts/gas_models_3d.sh [build/bin/cdemblast]
set -u
cd "$(dirname "$0")/.."
BIN=${1:-build/bin/cdemblast}
mkdir -p runs/gas3d
COARSE=(--set mesh.generate.element_size=0.2 --set mesh.generate.ring_element_size=0.25
        --set mesh.generate.refine.0.size=0.03 --set mesh.generate.refine.0.radius=0.04
        --set simulation.end_time=0.005 --set "simulation.output_times=[0.001, 0.002, 0.005]"
        --set simulation.history_interval=1e-5)
for g in cracks cavity literal; do
  G=(); for i in $(seq 0 11); do G+=(--set "hole.$i.gas=\"$g\""); done
  "$BIN" run examples/pile_pit_3d/case.toml "${COARSE[@]}" "${G[@]}" \
    --threads 2 --out runs/gas3d/$g -q > runs/gas3d/$g.log 2>&1
  echo "gas = $g: exit $?"
done
/usr/bin/python3 scripts/gas_models_3d.py runs/gas3d
