#!/usr/bin/env bash
# The bad-input table: every case is a malformed case file (fixtures in tests/data/bad_input/,
# each one good_2d.toml with one thing broken) or a bad command line. For each, cdemblast must
#   - exit with the expected code (2 for input errors),
#   - not crash (exit code < 128, no "Segmentation", "terminate called", "Aborted", no timeout),
#   - print on stderr every expected fragment (the file name, the key, what was expected).
# Usage: bash test_bad_input.sh <cdemblast-binary> <repo-root>
# Prints one PASS/FAIL/XFAIL line per case and exits non-zero if any case fails.
#
# XFAIL marks a case that fails because of a known problem in the program (the reason is
# printed); the check itself states what the program should do. A crash or a hang is always a
# FAIL. Strict: when such a case starts
# passing it is reported as XPASS and counts as a failure, so the mark gets removed.
set -u
BIN=${1:?usage: test_bad_input.sh <cdemblast-binary> <repo-root>}
ROOT=${2:?usage: test_bad_input.sh <cdemblast-binary> <repo-root>}
BIN=$(cd "$(dirname "$BIN")" && pwd)/$(basename "$BIN")
ROOT=$(cd "$ROOT" && pwd)
D=$ROOT/tests/data/bad_input
[[ -x $BIN ]] || { echo "FAIL: no executable at $BIN"; exit 1; }
[[ -d $D ]] || { echo "FAIL: no fixture directory $D"; exit 1; }

TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
cd "$TMP" || exit 1  # a run without --out must not write into the source tree

mkdir -p "$TMP/res"
XFAIL=""  # set to a reason just before a case known to fail; `expect` clears it
ncase=0

# expect NAME CODE STREAM FILE -- COMMAND... -- FRAGMENT...
#   CODE: the expected exit code; STREAM: where the fragments must appear (stderr or stdout);
#   FILE: a file name the message must name ("" for none). FILE is removed from the text before
#   the fragments are looked for, so that a fragment cannot match inside the file name.
# Cases run two at a time (each is mostly program start-up); results print in order at the end.
expect() {
  ncase=$((ncase + 1))
  local slot
  slot=$(printf '%03d' "$ncase")
  _expect "$slot" "$XFAIL" "$@" &
  XFAIL=""
  while [[ $(jobs -rp | wc -l) -ge 2 ]]; do wait -n; done
}

_expect() {
  local slot=$1 xfail=$2 name=$3 code=$4 stream=$5 file=$6
  shift 6
  [[ $1 == -- ]] && shift
  local cmd=()
  while [[ $# -gt 0 && $1 != -- ]]; do cmd+=("$1"); shift; done
  [[ $# -gt 0 ]] && shift
  local frags=("$@")
  local out=$TMP/$slot.out err=$TMP/$slot.err rc
  timeout 15 "${cmd[@]}" >"$out" 2>"$err"
  rc=$?
  local why=() crash=""
  if [[ $rc -eq 124 ]]; then
    crash="timed out after 15 s"
  elif [[ $rc -ge 128 ]]; then
    crash="crashed (exit code $rc)"
  elif [[ $rc -ne $code ]]; then
    why+=("exit code $rc, expected $code")
  fi
  if grep -qE 'Segmentation|terminate called|Aborted|core dumped|munmap_chunk|double free' "$out" "$err"; then
    crash="${crash:-crashed} (crash message in the output)"
  fi
  # A crash or a hang is a failure even in a case marked XFAIL (those marks are about messages).
  [[ -n $crash ]] && { why+=("$crash"); xfail=""; }
  local text=$err
  [[ $stream == stdout ]] && text=$out
  if [[ -n $file ]]; then
    grep -qF -- "$file" "$text" || why+=("$stream does not name '$file'")
  fi
  local body
  body=$(cat "$text")
  [[ -n $file ]] && body=${body//"$file"/}
  local f
  for f in "${frags[@]}"; do
    [[ $body == *"$f"* ]] || why+=("$stream lacks '$f'")
  done
  local first
  first=$(grep -m1 -v '^[[:space:]]*$' "$err" | cut -c1-150)
  local res=$TMP/res/$slot
  if [[ ${#why[@]} -eq 0 ]]; then
    if [[ -n $xfail ]]; then
      printf 'FAIL   %-30s XPASS: passes now; remove its XFAIL mark (%s)\n' "$name" "$xfail" >"$res"
    else
      printf 'PASS   %-30s rc=%d  %s\n' "$name" "$rc" "$first" >"$res"
    fi
  else
    local msg
    msg=$(IFS=';'; echo "${why[*]}")
    msg=${msg//;/; }
    if [[ -n $xfail ]]; then
      printf 'XFAIL  %-30s %s\n       %-30s known problem: %s\n' "$name" "$msg" "" "$xfail" >"$res"
    else
      printf 'FAIL   %-30s %s\n       %-30s stderr: %s\n' "$name" "$msg" "" "$first" >"$res"
    fi
  fi
}

# check CASE CODE FRAGMENT... : `cdemblast check D/CASE.toml`; the message names CASE.toml.
check() {
  local c=$1 code=$2
  shift 2
  expect "$c" "$code" stderr "$c.toml" -- "$BIN" check "$D/$c.toml" -- "$@"
}
# check_mesh CASE MESHFILE CODE FRAGMENT... : a mesh error; the message names the mesh file.
check_mesh() {
  local c=$1 mesh=$2 code=$3
  shift 3
  expect "$c" "$code" stderr "$mesh" -- "$BIN" check "$D/$c.toml" -- "$@"
}
# run CASE CODE FRAGMENT... : `cdemblast run D/CASE.toml --out ... -q`.
run() {
  local c=$1 code=$2
  shift 2
  expect "run:$c" "$code" stderr "$c.toml" -- "$BIN" run "$D/$c.toml" --out "$TMP/run_$c" -q -- "$@"
}

t0=$(date +%s%N)

# ---- controls: the base case is valid (else every other case proves nothing) ----
expect control_check 0 stdout "" -- "$BIN" check "$D/good_2d.toml" -- "check       OK" "face sets"
expect control_run 0 stdout "" -- bash -c "'$BIN' run '$D/good_2d.toml' --out '$TMP/run_good' -q && \
  test -f '$TMP/run_good/summary.json' && echo summary written" -- "summary written"
expect resolved_case_rerun 0 stdout "" -- bash -c "'$BIN' run '$D/good_2d.toml' --out '$TMP/run_res' -q && \
  '$BIN' check '$TMP/run_res/case.resolved.toml'" -- "check       OK"

# ---- TOML and keys ----
check syntax_error 2 "TOML syntax error" "10 | output_interval ="
check missing_end_time 2 "key 'simulation.end_time'" "missing" "expected a number"
check youngs_string 2 "key 'material[0].youngs_modulus'" "expected a number" "got a string"
check youngs_negative 2 "key 'material[0].youngs_modulus'" "expected a positive number" "got -3"
check poisson_half 2 "key 'material[0].poisson_ratio'" "(-1, 0.5)" "got 0.5"
check typo_end_tme 2 "key 'simulation.end_tme'" "unknown key" "end_time"
check dt_safety_above_one 2 "key 'simulation.dt_safety'" "(0, 1]" "got 1.5"
check interface_law_unknown 2 "key 'interface[0].law'" "'mohr_colomb'" "'mohr_coulomb'" "'fracture_energy'" "'elastic'"
check friction_angle_95 2 "key 'interface[0].friction_angle'" "[0, 90)" "got 95"
check boundary_type_unknown 2 "key 'boundary[0].type'" "'clamped'" "'fixed'" "'non_reflecting'"
# Not an error any more: an output time after end_time is dropped with a notice (a run shortened
# with --set simulation.end_time keeps working).
expect output_time_beyond_end 0 stdout output_time_beyond_end.toml -- "$BIN" check "$D/output_time_beyond_end.toml" -- \
  "key 'simulation.output_times'" "0.0002 s after end_time" "dropped" "check       OK"
check missing_tensile_strength 2 "key 'interface[0].tensile_strength'" "missing"
check missing_poisson_ratio 2 "key 'material[0].poisson_ratio'" "missing"

# ---- the case against its mesh ----
check material_unknown_region 2 "material 'granite'" "region 'granit' is not in the mesh" "'rock'"
check region_without_material 2 "region 'ore'" "no [[material]]"
check interface_pair_unknown_region 2 "interface 'bond'" "'rok'"
check boundary_unknown_faces 2 "key 'boundary[0].faces'" "no face set 'lft'" "'left'" "'bottom'"
check monitor_outside 2 "key 'monitor[0].point'" "outside the mesh"
run monitor_outside 2 "key 'monitor[0].point'" "monitor 'centre'" "outside the mesh"
check dt_above_stable 2 "key 'simulation.dt'" "above the stable step"
run dt_above_stable 2 "key 'simulation.dt'" "above the stable step"

# ---- mesh files: the message names the mesh file (and the element at fault) ----
check_mesh missing_mesh_file no_such_mesh.msh 2 "cannot open mesh file" "No such file"
expect run:missing_mesh_file 2 stderr no_such_mesh.msh -- "$BIN" run "$D/missing_mesh_file.toml" \
  --out "$TMP/run_nomesh" -q -- "cannot open mesh file" "No such file"
check_mesh garbage_mesh garbage.msh 2 "mesh file" "line 1"
check_mesh truncated_mesh truncated_2d.msh 2 "mesh file" "gmsh"
check_mesh undefined_node undefined_node_2d.msh 2 "mesh file" "node index 9"
check_mesh inverted_tet inverted_tet_3d.msh 2 "element 2" "inverted tetrahedron"
check_mesh degenerate_triangle degenerate_triangle_2d.msh 2 "element 9" "degenerate element"
check_mesh six_node_triangle six_node_triangle_2d.msh 2 "element 5" "Triangle 6" "Gmsh type 9" "linear elements only"

# ---- command line ----
expect set_bad_value 2 stderr "" -- "$BIN" check "$D/good_2d.toml" --set simulation.end_time=abc -- \
  "--set 'simulation.end_time=abc'" "not valid TOML" "strings need quotes"
expect set_wrong_type 2 stderr good_2d.toml -- "$BIN" check "$D/good_2d.toml" --set 'material.0.youngs_modulus="x"' -- \
  "key 'material[0].youngs_modulus'" "expected a number" "got a string"
expect set_index_out_of_range 2 stderr "" -- "$BIN" check "$D/good_2d.toml" --set material.3.density=1 -- \
  "--set 'material.3.density=1'" "index 3 out of range" "1 entries"
expect set_no_equals 2 stderr "" -- "$BIN" check "$D/good_2d.toml" --set simulation.end_time -- \
  "--set 'simulation.end_time'" "expected key=value"
expect set_before_case 0 stdout "" -- "$BIN" check --set material.0.density=3000 "$D/good_2d.toml" \
  --set simulation.end_time=2e-4 -- "check       OK"
expect run:set_negative 2 stderr good_2d.toml -- "$BIN" run "$D/good_2d.toml" --out "$TMP/run_neg" -q \
  --set material.0.density=-5 -- "key 'material[0].density'" "expected a positive number" "got -5"
expect circle_segments_range 2 stderr bar.toml -- "$BIN" check "$ROOT/examples/single_hole_2d/bar.toml" \
  --set mesh.generate.circle_segments=-3 -- "key 'mesh.generate.circle_segments'" "from 0 to 1000" "got -3"
expect hole_cavity_not_bool 2 stderr bar.toml -- "$BIN" check "$ROOT/examples/single_hole_2d/bar.toml" \
  --set hole.0.cavity=3 -- "key 'hole[0].cavity'" "expected true or false"
expect missing_case_file 2 stderr no_such_case.toml -- "$BIN" check "$D/no_such_case.toml" -- "no such file"
expect case_is_directory 2 stderr bad_input -- "$BIN" check "$D" -- "directory"
expect run:threads_negative 2 stderr "" -- "$BIN" run "$D/good_2d.toml" --out "$TMP/run_thr" -q --threads -1 -- "--threads" "-1"

wait
t1=$(date +%s%N)
npass=0 nfail=0 nxfail=0
failures=()
for r in "$TMP"/res/*; do
  status=$(awk 'NR == 1 {print $1}' "$r")
  cat "$r"
  case $status in
    PASS) npass=$((npass + 1)) ;;
    XFAIL) nxfail=$((nxfail + 1)) ;;
    *) nfail=$((nfail + 1)); failures+=("$(awk 'NR == 1 {print $2}' "$r")") ;;
  esac
done
results=("$TMP"/res/*)
[[ ${#results[@]} -eq $ncase ]] || { echo "FAIL: $ncase cases but ${#results[@]} results"; nfail=$((nfail + 1)); }
echo
ms=$(((t1 - t0) / 1000000))
printf '%d passed, %d failed, %d expected failures (XFAIL) of %d cases in %d.%d s\n' "$npass" "$nfail" \
  "$nxfail" "$ncase" $((ms / 1000)) $((ms % 1000 / 100))
if [[ $nfail -gt 0 ]]; then
  echo "failed: ${failures[*]}"
  exit 1
fi
exit 0
