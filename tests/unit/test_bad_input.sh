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
  if grep -qE 'Segmentation|terminate called|Aborted|core dumped|munmap_chunk|double free|Sanitizer|runtime error:' "$out" "$err"; then
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
check contact_energy_limit_negative 2 "key 'simulation.contact_energy_limit'" "expected a number >= 0"
check interface_energy_limit_negative 2 "key 'simulation.interface_energy_limit'" "expected a number >= 0"
check release_angle_above_180 2 "key 'simulation.release_angle'" "(0, 180]" "got 200"
# mass scaling (simulation.mass_scaling_dt): negative, in the springs mode, with a fixed dt, a
# limit above 0.1, and a step that needs more mass than the limit
expect mass_scaling_negative 2 stderr good_2d.toml -- "$BIN" check "$D/good_2d.toml" --set simulation.mass_scaling_dt=-1e-6 -- \
  "key 'simulation.mass_scaling_dt'" "got -1e-06"
expect mass_scaling_springs 2 stderr good_2d.toml -- "$BIN" check "$D/good_2d.toml" --set 'simulation.interfaces="springs"' \
  --set simulation.mass_scaling_dt=1e-6 -- "key 'simulation.mass_scaling_dt'" "tied interface mode only"
expect mass_scaling_fixed_dt 2 stderr good_2d.toml -- "$BIN" check "$D/good_2d.toml" --set simulation.dt=1e-9 \
  --set simulation.mass_scaling_dt=1e-6 -- "key 'simulation.mass_scaling_dt'" "not both"
expect mass_scaling_limit_large 2 stderr good_2d.toml -- "$BIN" check "$D/good_2d.toml" --set simulation.mass_scaling_dt=1e-6 \
  --set simulation.mass_scaling_limit=0.5 -- "key 'simulation.mass_scaling_limit'" "(0, 0.1]" "got 0.5"
expect mass_scaling_too_much 2 stderr good_2d.toml -- "$BIN" check "$D/good_2d.toml" --set simulation.mass_scaling_dt=1e-3 -- \
  "key 'simulation.mass_scaling_dt'" "simulation.mass_scaling_limit = 0.0001"
check interface_law_unknown 2 "key 'interface[0].law'" "'mohr_colomb'" "'mohr_coulomb'" "'fracture_energy'" "'elastic'"
check friction_angle_95 2 "key 'interface[0].friction_angle'" "[0, 90)" "got 95"
check boundary_type_unknown 2 "key 'boundary[0].type'" "'clamped'" "'fixed'" "'non_reflecting'"
# Not an error any more: an output time after end_time is dropped with a notice (a run shortened
# with --set simulation.end_time keeps working).
expect output_time_beyond_end 0 stderr output_time_beyond_end.toml -- "$BIN" check "$D/output_time_beyond_end.toml" -- \
  "key 'simulation.output_times'" "0.0002 s after end_time" "dropped"
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
check_mesh truncated_mesh truncated_2d.msh 2 "mesh file" "\$Nodes, line 17" "expected a node tag" "found '\$EndNodes'"
check_mesh undefined_node undefined_node_2d.msh 2 "mesh file" "element 8" "line 29" "node 9 is not defined"
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
expect contact_candidates_bad 2 stderr good_2d.toml -- "$BIN" check "$D/good_2d.toml" \
  --set 'contact.candidates="all"' -- "key 'contact.candidates'" "released" "cracked"
# checkpoints and restart (docs/checkpoint.md)
expect checkpoint_interval_negative 2 stderr good_2d.toml -- "$BIN" check "$D/good_2d.toml" \
  --set simulation.checkpoint_interval=-1 -- "key 'simulation.checkpoint_interval'" "got -1"
expect checkpoint_wall_not_number 2 stderr good_2d.toml -- "$BIN" check "$D/good_2d.toml" \
  --set 'simulation.checkpoint_wall_interval="often"' -- "key 'simulation.checkpoint_wall_interval'"
expect run:restart_no_checkpoint 2 stderr "" -- "$BIN" run "$D/good_2d.toml" --restart "$TMP/run_nockpt" -q -- \
  "no checkpoint in"
expect run:restart_and_overwrite 2 stderr "" -- "$BIN" run "$D/good_2d.toml" --restart "$TMP/run_ro" --overwrite -q -- \
  "give one of them"
expect resume_missing_dir 2 stderr "" -- "$BIN" resume "$TMP/no_such_run" -q -- "case.resolved.toml"

# ---- issue 10: untrusted input (docs/input_safety.md) ----
# Mesh files are read, never interpreted: a Gmsh script under any name is refused and its
# command does not run (the script would create cdem_pwned_by_* in the current directory).
for c in script_mesh script_geo; do
  expect "$c" 2 stderr "script." -- bash -c "'$BIN' check '$D/$c.toml'; rc=\$?; \
    if ls cdem_pwned_by_* >/dev/null 2>&1; then echo 'the script ran' >&2; exit 99; fi; exit \$rc" -- \
    "line 1: not a Gmsh MSH file" "never scripts"
done
check_mesh mesh_etc_passwd /etc/passwd 2 "line 1: not a Gmsh MSH file"
# Only regular files are read.
check_mesh mesh_dev_zero /dev/zero 2 "cannot open mesh file" "character device" "not a regular file"
check_mesh mesh_directory bad_input 2 "cannot open mesh file" "is a directory"
mkfifo "$TMP/fifo_case.toml"
expect case_is_fifo 2 stderr fifo_case.toml -- "$BIN" check "$TMP/fifo_case.toml" -- \
  "cannot open case file" "FIFO" "not a regular file"
head -c 5000000 /dev/zero | tr '\0' '#' >"$TMP/big_case.toml"
expect case_too_big 2 stderr big_case.toml -- "$BIN" check "$TMP/big_case.toml" -- \
  "cannot open case file" "more than the"
# Corrupt meshes: the section and line or byte, never a crash.
check_mesh node_count_huge node_count_huge_2d.msh 2 "\$Nodes, line 13" "number of nodes 1000000000000000000" "more than the rest of the file"
check_mesh truncated_binary truncated_binary_2d.msh 2 "\$Nodes, byte" "more than the rest of the file"
check_mesh element_dim_mismatch element_dim_mismatch.msh 2 "\$Elements, line 15" "'Triangle 3' elements (dimension 2) on an entity of dimension 3"
check_mesh node_nan node_nan_2d.msh 2 "\$Nodes, line 16" "node 3: coordinate x = nan is not a finite number"
check_mesh node_huge node_huge_2d.msh 2 "\$Nodes, line 16" "node 3: coordinate x = 1e+30" "beyond +-1e+07"
expect node_far 0 stderr node_far_2d.msh -- "$BIN" check "$D/node_far.toml" -- \
  "element 6 (triangle): area 2.5e+06 m^2 is 1e+07 times the median element's" "a misplaced vertex?" "(1e+07, 1, 0)"
check_mesh duplicate_node duplicate_node_2d.msh 2 "node tag 4 is defined twice" "\$Nodes, line 17" "\$Nodes, line 18"
check_mesh hexahedra hexahedra_3d.msh 2 "element 2" "'Hexahedron 8' (Gmsh type 5)" "linear elements only"
# Files that crash libgmsh 4.8's reader (tests/fuzz/regressions/msh): refused with a message.
for m in "$ROOT"/tests/fuzz/regressions/msh/*.msh; do
  n=$(basename "$m" .msh)
  expect "$n" 2 stderr "$n.msh" -- "$BIN" check "$D/good_2d.toml" --set "mesh.file=\"$m\"" -- "error: mesh file"
done
# Case text is checked before the TOML parser (toml11 3.7.1 overflows on this one).
check invalid_utf8_key 2 "line 2, column 4" "invalid UTF-8 (byte 0xff)"
check nul_byte 2 "line 2, column 13" "a NUL byte"
expect set_nul_free_control 2 stderr "" -- "$BIN" check "$D/good_2d.toml" --set $'title="a\x01b"' -- \
  "control character U+0001"
# Resource guards, before the work starts.
check element_size_tiny 2 "key 'mesh.generate.element_size'" "about 2.56e+11 elements (mostly from element_size 3e-06 m)" "more than the 1e+08"
check refine_size_tiny 2 "key 'mesh.generate.refine[0].size'" "(mostly from refine[0]: size 1e-06 m" "more than the 1e+08"
expect memory_guard 2 stderr good_2d.toml -- env CDEM_MEMORY_AVAILABLE=100000000 "$BIN" check "$D/good_2d.toml" \
  --set 'mesh={generate={shape="rectangle", size=[1.0, 1.0], element_size=0.002}}' -- \
  "key 'mesh.generate.element_size'" "need about" "this machine has 100 MB available (CDEM_MEMORY_AVAILABLE)"
expect mesh_file_memory_guard 2 stderr square_2d.msh -- env CDEM_MEMORY_AVAILABLE=1000 "$BIN" check "$D/good_2d.toml" -- \
  "cannot open mesh file" "more than the 250 B read at most" "1 kB of memory available, CDEM_MEMORY_AVAILABLE"
expect mesh_model_memory_guard 2 stderr square_2d.msh -- env CDEM_MEMORY_AVAILABLE=5000 "$BIN" check "$D/good_2d.toml" -- \
  "about 4 elements need about 8 kB of memory" "this machine has 5 kB available"
check output_interval_tiny 2 "key 'simulation.output_interval'" "1e+11 field outputs" "allow_large_run"
check dt_tiny 2 "'simulation.dt'" "1e+26 steps" "more than a run can count"
run dt_tiny 2 "'simulation.dt'" "1e+26 steps"
expect run:history_interval_tiny 0 stdout "" -- bash -c "'$BIN' run '$D/good_2d.toml' --out '$TMP/run_hist' -q \
  --set simulation.history_interval=1e-30 && echo finished" -- "finished"
check end_time_huge 2 "key 'simulation.end_time'" "2.29e+14 steps" "more than the 1e+08" "allow_large_run"
# NaN anywhere.
check gravity_nan 2 "key 'simulation.gravity'" "entry 1 is nan"
check table_nan 2 "key 'boundary[1].table'" "nan"
check output_times_nan 2 "key 'simulation.output_times'" "entry 1 is nan"
# Nonsense, naming the key.
check threads_huge 2 "key 'simulation.threads'" "from 0 (all cores) to 4096" "got 100000"
expect run:threads_beyond_machine 0 stderr threads_beyond_machine.toml -- "$BIN" run "$D/threads_beyond_machine.toml" \
  --out "$TMP/run_thr_many" -q -- "4096 threads asked (key 'simulation.threads')" "processors: using"
expect delay_after_end 0 stderr delay_after_end.toml -- "$BIN" check "$D/delay_after_end.toml" -- \
  "key 'hole[0].charge[0].delay'" "fires at 0.0002 s" "never fires"
check holes_coincident 2 "key 'hole[1].collar'" "hole 'h2' lies on hole 'h1'"
expect hole_wider_than_model 2 stderr delay_after_end.toml -- "$BIN" check "$D/delay_after_end.toml" --set 'hole.0.diameter=1e300' -- \
  "key 'hole[0].diameter'" "wider than the model (1 m across)"
expect hole_far_away 2 stderr delay_after_end.toml -- "$BIN" check "$D/delay_after_end.toml" --set 'hole.0.collar=[0.5, 1e300]' -- \
  "key 'hole[0].collar'" "is 1e+300 m outside the model, which is 1 m across"
check monitor_z_in_2d 2 "key 'monitor[0].point'" "z = 0.3 in a 2D case"
check stress_yz_in_2d 2 "key 'initial_stress.stress'" "yz component 200000 in a 2D case"
expect mesh_in_mm 0 stderr square_2d_mm.msh -- "$BIN" check "$D/mesh_in_mm.toml" -- \
  "1000 m across with a median element of 804.738 m" "is the mesh in millimetres?" "the whole run is 1 step(s)"
# Messages that name the real culprit.
check youngs_huge 2 "key 'material[0].youngs_modulus'" "1e+308 Pa is no Young's modulus"
check density_tiny 2 "key 'material[0].density'" "1e-300 kg/m^3 is no density"
expect set_negative_index 2 stderr "" -- "$BIN" check "$D/good_2d.toml" --set material.-1.density=5 -- \
  "--set 'material.-1.density=5'" "'-1' is not an index"
check main_faces_typo 2 "key 'analysis.main_faces'" "no face set 'bottm'"
expect run:unstable_quiet 3 stderr "" -- "$BIN" run "$D/unstable_run.toml" --out "$TMP/run_unstable" -q -- \
  "run stopped: at t = " "energy blow-up"
expect run:pressure_overflow 3 stderr "" -- "$BIN" run "$D/good_2d.toml" --out "$TMP/run_overflow" -q \
  --set boundary.1.pressure=1e300 -- "run stopped: at t = " "the output written so far is in"
expect cli_unknown_option 2 stderr "" -- "$BIN" check "$D/good_2d.toml" --no-such-option -- "--no-such-option"

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
