#!/usr/bin/env bash
# A distributed run (mpirun -np N, docs/parallel.md) gives the results of one process bit for
# bit: 1, 2, 3 and 4 ranks on a 2D bar blast (SPEC 5.1's case, shortened) and on a 3D blast with
# cracking, contact and 12 bars (the coarse SPEC 5.3 cylinder, shortened); a checkpoint written
# by 2 ranks continued on 3 gives the uninterrupted run's results. Every output file is compared
# byte for byte (rank 0 writes them whole, in the layout of one process), summary.json without
# its timings and run id. Tolerance: none. Every value is computed by one rank with one rank's
# arithmetic and every sum runs in the model's order on every rank (parallel/ranks.hpp).
#
# Skipped (77) without mpirun or in a build without MPI. Runs as root in CI: Open MPI's root
# guard is lifted with its two environment variables; 3 and 4 ranks on 2 cores need
# --oversubscribe.
source "$(dirname "$0")/../script_preamble.sh" "$@"
command -v mpirun > /dev/null || { echo "SKIP: no mpirun (install openmpi-bin)"; exit 77; }
"$BIN" --version | grep -q "MPI: yes" || { echo "SKIP: cdemblast built without MPI"; exit 77; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
MPIRUN=(mpirun --oversubscribe --bind-to none)

# run NRANKS OUT CASE ARGS...: one process for 1, mpirun for more; 1 thread per rank.
run() {
  local n=$1 out=$2
  shift 2
  if [ "$n" -eq 1 ]; then
    "$BIN" run "$@" -o "$out" -t 1 --fixed-threads -q
  else
    "${MPIRUN[@]}" -np "$n" "$BIN" run "$@" -o "$out" -t 1 --fixed-threads -q
  fi
}

# same A B: every output of run A equals run B's (files byte for byte, summary.json's physics).
same() {
  local a=$1 b=$2
  (cd "$a" && find . -type f ! -name summary.json ! -path './checkpoints/*' ! -name '.lock' ! -name partition.vtu | sort) > "$TMP/files_a"
  (cd "$b" && find . -type f ! -name summary.json ! -path './checkpoints/*' ! -name '.lock' ! -name partition.vtu | sort) > "$TMP/files_b"
  cmp -s "$TMP/files_a" "$TMP/files_b" || fail "$b: not the same files as $a: $(diff "$TMP/files_a" "$TMP/files_b" | head -5)"
  [ "$(wc -l < "$TMP/files_a")" -gt 8 ] || fail "$a: too few outputs to compare"
  while read -r f; do
    if [[ "$f" == *.toml || "$f" == *.pvd ]]; then  # these name the run's id
      cmp -s <(grep -v run_id "$a/$f") <(grep -v run_id "$b/$f") || fail "$b/$f differs from $a/$f"
    else
      cmp -s "$a/$f" "$b/$f" || fail "$b/$f differs from $a/$f"
    fi
  done < "$TMP/files_a"
  "$PY" - "$a/summary.json" "$b/summary.json" <<'EOF' || fail "$b/summary.json differs from $a's"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:])
# timings, the run's id, the rank count and the ranks' division, the restart point
skip = {"run_id", "wall_time_s", "loop_time_s", "threads_step_seconds", "block_steps_per_s",
        "spring_steps_per_s", "checkpoint_write_time_s", "checkpoint_bytes", "checkpoints_written",
        "kernel_time_s", "ranks", "ranks_imbalance", "ranks_charges_split", "restarted_at_step",
        "threads_switches", "threads_final", "ranks_mode"}
bad = [k for k in a if k not in skip and a[k] != b.get(k)]
if bad:
    sys.exit(f"keys differ: {bad[:8]}")
EOF
}

# 2D: SPEC 5.1's bar case to 0.4 ms (cracks around the hole by then).
C2=("$ROOT/examples/single_hole_2d/bar.toml" --set simulation.end_time=4e-4)
for n in 1 2 3 4; do run "$n" "$TMP/2d_$n" "${C2[@]}" 2> "$TMP/log_2d_$n" || { cat "$TMP/log_2d_$n"; fail "2D on $n ranks"; }; done
for n in 2 3 4; do same "$TMP/2d_1" "$TMP/2d_$n"; done
"$PY" -c "import json,sys; s=json.load(open('$TMP/2d_1/summary.json')); sys.exit(0 if s['fracture_degree'] > 0 else 'no cracking in the 2D run')" || fail "2D: nothing to compare"
echo "2D: 1, 2, 3, 4 ranks identical"
# the method paper's form (every interface a spring: the spring kernel divided over all of them)
for n in 1 3; do
  run "$n" "$TMP/2ds_$n" "${C2[@]}" --set 'simulation.interfaces="springs"' 2> "$TMP/log_2ds_$n" ||
    { cat "$TMP/log_2ds_$n"; fail "2D springs mode on $n ranks"; }
done
same "$TMP/2ds_1" "$TMP/2ds_3"
echo "2D springs mode: 1, 3 ranks identical"

# 3D: the coarse SPEC 5.3 cylinder, all holes at once, to 0.3 ms: cracking, contact, 12 bars.
C3=("$ROOT/examples/pile_pit_3d/case.toml" --set mesh.generate.element_size=0.2
    --set mesh.generate.ring_element_size=0.25 --set mesh.generate.refine.0.size=0.03
    --set mesh.generate.refine.0.radius=0.04 --set delays.1=0.0 --set delays.2=0.0
    --set delays.3=0.0 --set simulation.end_time=3e-4)
for n in 1 2 3 4; do run "$n" "$TMP/3d_$n" "${C3[@]}" 2> "$TMP/log_3d_$n" || { cat "$TMP/log_3d_$n"; fail "3D on $n ranks"; }; done
for n in 2 3 4; do same "$TMP/3d_1" "$TMP/3d_$n"; done
"$PY" - "$TMP/3d_1/summary.json" "$TMP/3d_3/summary.json" "$TMP/3d_4/summary.json" <<'EOF' || fail "3D: the run does not exercise what it should"
import json, sys
s = json.load(open(sys.argv[1]))
assert s["fracture_degree"] > 0.1, s["fracture_degree"]
assert s["contact_pairs_max"] > 0 and s["contact_rebuilds"] > 0, "no contact"
assert s["bar_segments"] > 0
# a bar whose blocks lie on more than one rank (its loads reach blocks of several ranks)
assert max(json.load(open(p))["ranks_charges_split"] for p in sys.argv[2:]) > 0, "no bar across ranks"
EOF
echo "3D: 1, 2, 3, 4 ranks identical"

# Restart across rank counts: 2 ranks to 0.3 ms with a checkpoint at 0.16 ms; a copy without
# the final checkpoint continued on 3 ranks.
run 2 "$TMP/3d_c" "${C3[@]}" --set simulation.checkpoint_interval=1.6e-4 2> "$TMP/log_c" ||
  { cat "$TMP/log_c"; fail "3D, 2 ranks with a checkpoint"; }
cp -r "$TMP/3d_c" "$TMP/3d_r"
[ "$(ls "$TMP/3d_r/checkpoints" | wc -l)" = 2 ] || fail "expected a middle and a final checkpoint"
rm "$(ls -d "$TMP/3d_r"/checkpoints/* | tail -1)"
"${MPIRUN[@]}" -np 3 "$BIN" run "${C3[@]}" --set simulation.checkpoint_interval=1.6e-4 \
  --restart "$TMP/3d_r" -t 1 --fixed-threads -q 2> "$TMP/log_r" || { cat "$TMP/log_r"; fail "3D, continued on 3 ranks"; }
grep -q '"restarted_at_step": [1-9]' "$TMP/3d_r/summary.json" || fail "not restarted mid-run"
for d in 3d_c 3d_r; do
  for f in energy.csv monitors.csv fracture.csv charges.csv grading.csv reactions.csv; do
    [ -f "$TMP/3d_1/$f" ] || continue
    cmp -s "$TMP/3d_1/$f" "$TMP/$d/$f" || fail "$d: $f differs from the 1-rank run's"
  done
done
same "$TMP/3d_c" "$TMP/3d_r"
echo "restart: written by 2 ranks, continued on 3: identical to 1 rank uninterrupted"

# The halo stage (parallel/halo.hpp): a case without general contact is stepped
# by parts, each rank its own and a ghost zone, the ghosts' motion received from their owners.
# The 2D plate with a pressurised hole (tied, and the springs mode), a 3D box with a
# pressurised blind hole and a fixed base (tied: constrained clusters, reactions), a 3D
# cylinder with a damping zone, and a 3D box with a bar charge along its axis, across the parts
# (its state stepped on every rank, solver/halo_charges.hpp; its gas fills cracks between parts).
# mode DIR: the summary's ranks_mode
mode() { "$PY" -c "import json,sys; print(json.load(open(sys.argv[1]))['ranks_mode'])" "$1/summary.json"; }
P2=("$ROOT/examples/plate_with_hole_2d/case.toml" --set mesh.generate.element_size=0.1
    --set mesh.generate.refine.0.size=0.04 --set simulation.end_time=6e-4 --set contact.enabled=false)
H3=("$ROOT/tests/verification/cases/hole_box_3d.toml")
# a cylinder with an absorbing ring (a damping zone graded over the whole ring) and a pressurised hole
R3=("$ROOT/tests/verification/cases/ring_cylinder_3d.toml")
B3=("$ROOT/tests/verification/cases/bar_box_3d.toml")
# solid charges: SPEC 5.1's solid case without contact (an explosive block collapses at 0.55 ms),
# and a 3D box with a solid charge along its axis (3 collapse in the tied mode, 33 in the springs
# mode), their explosive blocks and gas across the parts
S2=("$ROOT/examples/single_hole_2d/solid.toml" --set simulation.end_time=6e-4 --set contact.enabled=false)
S3=("$ROOT/tests/verification/cases/solid_box_3d.toml")
for c in P2 H3 R3 B3 S2 S3; do
  declare -n args=$c
  for n in 1 2 3 4; do
    run "$n" "$TMP/h_${c}_$n" "${args[@]}" 2> "$TMP/log_h" || { cat "$TMP/log_h"; fail "$c on $n ranks"; }
    [ "$n" = 1 ] || [ "$(mode "$TMP/h_${c}_$n")" = halo ] || fail "$c on $n ranks: not the halo stage"
  done
  for n in 2 3 4; do same "$TMP/h_${c}_1" "$TMP/h_${c}_$n"; done
  "$PY" -c "import json,sys; s=json.load(open(sys.argv[1])); sys.exit(0 if s['fracture_degree'] > 0.05 else 'too little cracking')" \
    "$TMP/h_${c}_1/summary.json" || fail "$c: nothing to compare"
  unset -n args
done
"$PY" -c "import json,sys; sys.exit(0 if all(json.load(open(p))['collapsed_explosive_blocks'] > 0 for p in sys.argv[1:]) else 'no collapse')" \
  "$TMP/h_S2_1/summary.json" "$TMP/h_S3_1/summary.json" || fail "the solid charges: no explosive block collapsed"
# the springs mode (the 3D box: with velocity constraints at its base, their reactions' work)
for c in P2 H3 B3 S3; do
  declare -n args=$c
  for n in 1 3; do
    run "$n" "$TMP/h_${c}s_$n" "${args[@]}" --set 'simulation.interfaces="springs"' 2> "$TMP/log_h" ||
      { cat "$TMP/log_h"; fail "$c in the springs mode, halo, on $n ranks"; }
  done
  same "$TMP/h_${c}s_1" "$TMP/h_${c}s_3"
  [ "$(mode "$TMP/h_${c}s_3")" = halo ] || fail "$c in the springs mode on 3 ranks: not the halo stage"
  unset -n args
done
# stiffness-proportional damping (its work: per block and per node terms in the step's exact sums)
for n in 1 3; do
  run "$n" "$TMP/h_H3d_$n" "${H3[@]}" --set material.0.stiffness_damping=2e-7 2> "$TMP/log_h" ||
    { cat "$TMP/log_h"; fail "3D box with stiffness damping, halo, on $n ranks"; }
done
same "$TMP/h_H3d_1" "$TMP/h_H3d_3"
[ "$(mode "$TMP/h_H3d_3")" = halo ] || fail "stiffness damping on 3 ranks: not the halo stage"
"$PY" - "$TMP/h_H3_1/energy.csv" "$TMP/h_H3d_1/energy.csv" <<'EOF' || fail "stiffness damping: no work booked"
import csv, sys
last = [list(csv.DictReader(open(p)))[-1] for p in sys.argv[1:]]
assert float(last[1]["damping"]) > float(last[0]["damping"]) + 1e-3 * abs(float(last[0]["damping"])), last
EOF
# ... and with only a corner plug damped: parts without a damped block book the work the others sum
for n in 1 3; do
  run "$n" "$TMP/h_PL_$n" "$ROOT/tests/verification/cases/plug_box_3d.toml" 2> "$TMP/log_h" ||
    { cat "$TMP/log_h"; fail "the plug box (damping in one region), halo, on $n ranks"; }
done
same "$TMP/h_PL_1" "$TMP/h_PL_3"
[ "$(mode "$TMP/h_PL_3")" = halo ] || fail "the plug box on 3 ranks: not the halo stage"
# a run that goes unstable in the halo stage (the base's pressure overflowing) stops at the same
# step as one process, with its diagnosis (found from the reduced sums and counts, worded from the
# whole state gathered then) and the same outputs kept
for n in 1 2; do
  rc=0
  run "$n" "$TMP/h_U_$n" "${H3[@]}" --set boundary.0.pressure=1e300 2> "$TMP/log_h" || rc=$?
  [ "$rc" = 3 ] || { cat "$TMP/log_h"; fail "an unstable halo run on $n ranks: exit $rc, not 3"; }
done
same "$TMP/h_U_1" "$TMP/h_U_2"
[ "$(mode "$TMP/h_U_2")" = halo ] || fail "the unstable run on 2 ranks: not the halo stage"
# the replicated stage asked for: the same bits
"${MPIRUN[@]}" -np 2 "$BIN" run "${H3[@]}" -o "$TMP/h_rep" -t 1 --fixed-threads -q --ranks-mode replicated 2> "$TMP/log_h" ||
  { cat "$TMP/log_h"; fail "3D box, --ranks-mode replicated"; }
[ "$(mode "$TMP/h_rep")" = replicated ] || fail "--ranks-mode replicated not taken"
same "$TMP/h_H3_1" "$TMP/h_rep"
# continued NAME CASE DIR: a checkpoint of a halo run on 2 ranks (the whole state, gathered; the
# bars' state every rank stepped) continued on 3 ranks (replicated) from its last checkpoint but
# one: its histories are the uninterrupted 1-rank run's (in DIR), and its outputs the 2-rank run's
continued() {
  local what=$1 case=$2 ref=$3
  local -n args=$case
  run 2 "$TMP/${case}_c0" "${args[@]}" --set simulation.checkpoint_interval=1e-4 2> "$TMP/log_h" ||
    { cat "$TMP/log_h"; fail "$what with a checkpoint"; }
  cp -r "$TMP/${case}_c0" "$TMP/${case}_c"
  rm "$(ls -d "$TMP/${case}_c"/checkpoints/* | tail -1)"
  "${MPIRUN[@]}" -np 3 "$BIN" run "${args[@]}" --set simulation.checkpoint_interval=1e-4 --restart "$TMP/${case}_c" \
    -t 1 --fixed-threads -q 2> "$TMP/log_h" || { cat "$TMP/log_h"; fail "$what continued on 3 ranks"; }
  grep -q '"restarted_at_step": [1-9]' "$TMP/${case}_c/summary.json" || fail "$what: not restarted mid-run"
  for f in energy.csv monitors.csv fracture.csv charges.csv grading.csv reactions.csv; do
    [ -f "$ref/$f" ] || continue
    cmp -s "$ref/$f" "$TMP/${case}_c/$f" || fail "$what continued: $f differs from the 1-rank run's"
  done
  same "$TMP/${case}_c0" "$TMP/${case}_c"
}
continued "3D box" H3 "$TMP/h_H3_1"
continued "bar box" B3 "$TMP/h_B3_1"
continued "2D solid charge" S2 "$TMP/h_S2_1"
# partition.vtu: each block's rank, as many parts as ranks (read with the package's VTU reader)
PYTHONPATH="$ROOT/python" "$PY" - "$TMP/h_H3_3/partition.vtu" "$TMP/h_H3_1/summary.json" <<'EOF' || fail "partition.vtu of the 3-rank run"
import json, sys
from cdemblast.vtu import read_vtu
part = read_vtu(sys.argv[1]).cell_array("part")
assert sorted(set(int(p) for p in part)) == [0, 1, 2], sorted(set(part))
assert len(part) == json.load(open(sys.argv[2]))["blocks"]
EOF
[ ! -e "$TMP/h_H3_1/partition.vtu" ] || fail "one process wrote a partition.vtu"
# check --parts says which stage a run on that many ranks takes, and why not the halo stage
"$BIN" check "${H3[@]}" --parts 3 | grep -q "mpirun -np 3: the halo stage" || fail "check --parts: the 3D box's stage"
"$BIN" check "${B3[@]}" --parts 3 | grep -q "mpirun -np 3: the halo stage" || fail "check --parts: the bar box's stage"
"$BIN" check "${S3[@]}" --parts 3 | grep -q "mpirun -np 3: the halo stage" || fail "check --parts: the solid box's stage"
# ... and prints the partition the run steps: the bar box's imbalance and split charges on 3 ranks
"$BIN" check "${B3[@]}" --parts 3 > "$TMP/check_b3"
"$PY" - "$TMP/check_b3" "$TMP/h_B3_3/summary.json" <<'EOF' || fail "check --parts 3 does not print the 3-rank run's partition"
import json, re, sys
text, s = open(sys.argv[1]).read(), json.load(open(sys.argv[2]))
m = re.search(r"^partition .*load imbalance ([0-9.]+).*; (\d+) of the charges split", text, re.M)
assert m, text
assert m.group(1) == f"{s['ranks_imbalance']:.3f}" and int(m.group(2)) == s["ranks_charges_split"], (m.groups(), s["ranks_imbalance"], s["ranks_charges_split"])
EOF
"$BIN" check "${C2[@]}" --parts 3 | grep -q "the replicated stage (the halo stage does not step general contact" ||
  fail "check --parts: the 2D bar case's stage (contact)"
echo "halo stage: 2D (tied, springs), 3D (tied; springs on 3; stiffness damping, everywhere or in one region, on 3; unstable on 2), a 3D bar and 2D and 3D solid charges across the parts, on 1-4 ranks identical; replicated the same; halo checkpoints (the 3D box, the bar box, the 2D solid charge) continued on 3 ranks"

# Errors end every rank (no hang: each under a time bound) with exit code 2 and the message:
# a missing case (every rank meets it), a run directory holding another run (rank 0 alone meets
# it, the others are already in the first exchange), a command that does not run on ranks.
expect_refused() {
  local what=$1 pattern=$2 rc=0
  shift 2
  timeout 120 "${MPIRUN[@]}" -np 2 "$BIN" "$@" > "$TMP/err.out" 2> "$TMP/err.log" || rc=$?
  [ "$rc" = 2 ] || { cat "$TMP/err.log"; fail "$what: exit $rc, expected 2 (124: it hung)"; }
  grep -q -- "$pattern" "$TMP/err.log" || { cat "$TMP/err.log"; fail "$what: no message '$pattern'"; }
}
expect_refused "a missing case" "cannot open case file" run "$TMP/missing.toml" -o "$TMP/x" -q
expect_refused "an occupied run directory" "holds the results of another run" run "${C2[@]}" -o "$TMP/2d_1" -q
expect_refused "report on ranks" "only run, resume and check" report "$TMP/2d_1"
expect_refused "the halo stage of a case with contact" "the halo stage does not step general contact" run "${C2[@]}" -o "$TMP/h_x" -q --ranks-mode halo
echo "errors on 2 ranks: exit 2 with the message, no hang"
