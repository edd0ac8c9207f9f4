#!/usr/bin/env bash
# Checkpoints and restart (docs/checkpoint.md), tried as a user would:
#  - bitwise restart: a run to T with a checkpoint at about T/2, and the same run continued from
#    that checkpoint, give identical outputs (every history, every VTU and fragment table, the PVD
#    series, grading.csv, summary.json apart from its timings and thread count), in 2D (bar,
#    cracks gas, tied mode), 2D in springs mode with a solid charge, and 3D (cracks, bars,
#    contact and gas active); 1 thread before the checkpoint, 2 after;
#  - SIGTERM mid-run: exit 143, summary.json says "interrupted", `report` works on the directory,
#    and `resume` completes it with the outputs of the uninterrupted run; SIGINT gives 130;
#  - a corrupted (one byte flipped) or truncated newest checkpoint is refused with a message and
#    the one before it is used; none readable: a clear error;
#  - a changed case is refused, a longer end_time is accepted;
#  - run directories: a second run into a locked directory is refused, a directory with another
#    run's results is refused without --overwrite and cleared with it; `report` refuses a
#    directory whose outputs carry different run ids.
#
#   bash test_restart.sh <cdemblast-binary> <repo-root>
set -uo pipefail
BIN=${1:?usage: test_restart.sh <cdemblast-binary> <repo-root>}
ROOT=${2:?usage: test_restart.sh <cdemblast-binary> <repo-root>}
TMP=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null; rm -rf "$TMP"' EXIT
export OMP_WAIT_POLICY=PASSIVE
fail() { echo "FAIL: $*" >&2; exit 1; }

# same_outputs A B: every output of run A is byte-identical in run B (the run id lines of the PVD
# files aside when the ids differ; summary.json without the timing and thread keys).
same_outputs() {
  local a=$1 b=$2 f
  for f in energy.csv monitors.csv fracture.csv charges.csv reactions.csv grading.csv; do
    if [ -f "$a/$f" ]; then cmp -s "$a/$f" "$b/$f" || fail "$f differs between $a and $b"; fi
  done
  for f in fields.pvd cracks.pvd; do
    cmp -s <(grep -v run_id "$a/$f") <(grep -v run_id "$b/$f") || fail "$f differs between $a and $b"
  done
  local n=0
  for f in "$a"/fields/*.vtu "$a"/cracks/*.vtu "$a"/fragments/*.csv; do
    cmp -s "$f" "$b/${f#"$a"/}" || fail "${f#"$a"/} differs between $a and $b"
    n=$((n + 1))
  done
  [ "$n" -ge 3 ] || fail "only $n field files in $a"
  local drop='time_s|checkpoint|threads|restarted_at_step|steps_per_s|run_id|"wall|"loop|kernel'
  cmp -s <(grep -Ev "$drop" "$a/summary.json") <(grep -Ev "$drop" "$b/summary.json") ||
    { diff <(grep -Ev "$drop" "$a/summary.json") <(grep -Ev "$drop" "$b/summary.json") | head; fail "summary.json differs between $a and $b"; }
}

# bitwise NAME CASE ARGS...: full run (1 thread, checkpoint every T/2), then a copy continued with
# 2 threads from the middle checkpoint (the final one removed).
bitwise() {
  local name=$1 case_file=$2
  shift 2
  "$BIN" run "$case_file" --out "$TMP/$name.full" -q --threads 1 "$@" >"$TMP/$name.log" 2>&1 ||
    { cat "$TMP/$name.log"; fail "$name: the full run"; }
  local n
  n=$(ls "$TMP/$name.full/checkpoints" | wc -l)
  [ "$n" = 2 ] || fail "$name: $n checkpoints kept, expected 2 (the middle one and the final one)"
  cp -r "$TMP/$name.full" "$TMP/$name.half"
  rm "$(ls -d "$TMP/$name.half"/checkpoints/* | tail -1)"
  "$BIN" run "$case_file" --restart "$TMP/$name.half" -q --threads 2 "$@" >"$TMP/$name.r.log" 2>&1 ||
    { cat "$TMP/$name.r.log"; fail "$name: the restart"; }
  grep -q '"restarted_at_step": [1-9]' "$TMP/$name.half/summary.json" || fail "$name: not restarted mid-run"
  same_outputs "$TMP/$name.full" "$TMP/$name.half"
  echo "ok: bitwise restart, $name"
}

C2=$ROOT/examples/single_hole_2d/bar.toml
S2=$ROOT/examples/single_hole_2d/solid.toml
C3=$ROOT/examples/multihole_3d/bar.toml
q2=(--set mesh.generate.element_size=0.08 --set simulation.end_time=1e-3
    --set 'simulation.output_times=[2.5e-4,7.5e-4]' --set simulation.checkpoint_interval=5.5e-4)
q3=(--set mesh.generate.element_size=0.2 --set simulation.end_time=1.5e-3
    --set 'simulation.output_times=[5e-4,1e-3]' --set simulation.history_interval=1e-5
    --set simulation.checkpoint_interval=0.9e-3)
bitwise 2d_bar "$C2" "${q2[@]}"
bitwise 2d_solid_springs "$S2" "${q2[@]}" --set 'simulation.interfaces="springs"'
bitwise 3d_bar "$C3" "${q3[@]}"
grep -q '"contact_pairs_max": [1-9]' "$TMP/3d_bar.full/summary.json" || fail "3d_bar: no contact was active"
grep -q '"fracture_degree": 0\.[1-9]' "$TMP/3d_bar.full/summary.json" || fail "3d_bar: not cracked"
# old_default NAME SET LINE HINT: a run made with a key's value of before 7 Dec 2026 (SET, which
# the resolved case writes as LINE) keeps the bitwise restart; continued without the --set
# (today's default) it is refused, and the message gives the --set that continues it (HINT)
old_default() {
  local name=$1 set_=$2 line=$3 hint=$4
  bitwise "$name" "$C3" "${q3[@]}" --set "$set_"
  grep -qxF -- "$line" "$TMP/$name.full/case.resolved.toml" || fail "$name: '$line' not resolved"
  "$BIN" run "$C3" --restart "$TMP/$name.full" -q "${q3[@]}" >"$TMP/$name.refused.log" 2>&1
  local rc=$?
  [ "$rc" = 2 ] && grep -q "differs" "$TMP/$name.refused.log" && grep -qF -- "$hint" "$TMP/$name.refused.log" ||
    { cat "$TMP/$name.refused.log"; fail "$name: continued with today's default, not refused with the hint (rc $rc)"; }
  echo "ok: a run with $set_ continues only with it, and the message says how"
}
# contact with the released faces only as candidates (contact.candidates, "cracked" since 7 Dec
# 2026), and without passivity (contact.passivity, the plain penalty: the code before 7 Dec 2026)
grep -q 'candidates = "cracked"' "$TMP/3d_bar.full/case.resolved.toml" || fail "the default candidates not resolved"
old_default 3d_bar_released 'contact.candidates="released"' 'candidates = "released"' \
  "--set 'contact.candidates=\"released\"'"
old_default 3d_bar_plain contact.passivity=false 'passivity = false' "--set contact.passivity=false"

# ---- SIGTERM and SIGINT mid-run, then resume ----
# interrupt SIGNAL DIR ARGS...: starts the 3D run, signals it once its history has 40 rows.
interrupt() {
  local sig=$1 dir=$2
  shift 2
  "$BIN" run "$C3" --out "$dir" -q --threads 1 "$@" >"$dir.log" 2>&1 &
  local pid=$! k
  for k in $(seq 1 600); do
    [ "$(cat "$dir/energy.csv" 2>/dev/null | wc -l)" -ge 40 ] && break
    sleep 0.05
  done
  kill -"$sig" "$pid"
  wait "$pid"
}
slow=(--set mesh.generate.element_size=0.15 --set simulation.end_time=1.5e-3
      --set 'simulation.output_times=[5e-4,1e-3]' --set simulation.history_interval=1e-5)
"$BIN" run "$C3" --out "$TMP/term.full" -q --threads 2 "${slow[@]}" >"$TMP/term.full.log" 2>&1 ||
  fail "the uninterrupted 3D run"
interrupt TERM "$TMP/term" "${slow[@]}"
rc=$?
[ "$rc" = 143 ] || { cat "$TMP/term.log"; fail "SIGTERM: exit code $rc, expected 143"; }
grep -q '"status": "interrupted"' "$TMP/term/summary.json" || fail "SIGTERM: summary.json not 'interrupted'"
grep -q 'interrupted by SIGTERM' "$TMP/term.log" || fail "SIGTERM: no message"
[ -n "$(ls "$TMP/term/checkpoints")" ] || fail "SIGTERM: no checkpoint"
tail -c 1 "$TMP/term/energy.csv" | od -c | grep -q '\\n' || fail "SIGTERM: energy.csv cut mid-line"
if /usr/bin/python3 -c 'import matplotlib' 2>/dev/null; then
  "$BIN" report "$TMP/term" >"$TMP/term.report.log" 2>&1 || { cat "$TMP/term.report.log"; fail "report on the interrupted run"; }
fi
"$BIN" resume "$TMP/term" -q --threads 2 >"$TMP/term.resume.log" 2>&1 || { cat "$TMP/term.resume.log"; fail "resume"; }
grep -q '"status": "finished"' "$TMP/term/summary.json" || fail "resume: not finished"
same_outputs "$TMP/term.full" "$TMP/term"
echo "ok: SIGTERM, report, resume: identical to the uninterrupted run"
interrupt INT "$TMP/int" "${slow[@]}"
rc=$?
[ "$rc" = 130 ] || fail "SIGINT: exit code $rc, expected 130"
echo "ok: SIGINT exits 130"

# ---- corrupted checkpoints: the one before is used ----
d=$TMP/3d_bar.corrupt
cp -r "$TMP/3d_bar.full" "$d"
newest=$(ls -d "$d"/checkpoints/* | tail -1)
size=$(stat -c %s "$newest")
printf '\x55' | dd of="$newest" bs=1 seek=$((size / 2)) conv=notrunc status=none
"$BIN" run "$C3" --restart "$d" -q --threads 2 "${q3[@]}" >"$TMP/corrupt.log" 2>&1 || { cat "$TMP/corrupt.log"; fail "restart past a corrupted checkpoint"; }
grep -q "checksum of record" "$TMP/corrupt.log" || { cat "$TMP/corrupt.log"; fail "corrupted checkpoint: no message"; }
same_outputs "$TMP/3d_bar.full" "$d"
echo "ok: a corrupted checkpoint is refused, the previous one used"
d=$TMP/3d_bar.trunc
cp -r "$TMP/3d_bar.full" "$d"
for f in "$d"/checkpoints/*; do truncate -s $(($(stat -c %s "$f") - 100)) "$f"; done
"$BIN" run "$C3" --restart "$d" -q "${q3[@]}" >"$TMP/trunc.log" 2>&1
rc=$?
[ "$rc" = 2 ] || fail "no readable checkpoint: exit code $rc, expected 2"
grep -q "truncated" "$TMP/trunc.log" && grep -q "no readable checkpoint" "$TMP/trunc.log" ||
  { cat "$TMP/trunc.log"; fail "truncated checkpoints: message"; }
echo "ok: truncated checkpoints are refused with a message"

# ---- changed case, longer end time ----
"$BIN" run "$C3" --restart "$TMP/3d_bar.full" -q "${q3[@]}" --set material.0.youngs_modulus=60e9 >"$TMP/changed.log" 2>&1
rc=$?
[ "$rc" = 2 ] && grep -q "differs" "$TMP/changed.log" || { cat "$TMP/changed.log"; fail "a changed case was not refused (rc $rc)"; }
"$BIN" run "$C3" --restart "$TMP/3d_bar.full" -q "${q3[@]}" --set simulation.end_time=1.7e-3 >"$TMP/longer.log" 2>&1 ||
  { cat "$TMP/longer.log"; fail "restart with a longer end_time"; }
grep -q '"end_time": 0.0017' "$TMP/3d_bar.full/summary.json" || fail "the longer run did not reach 1.7e-3 s"
echo "ok: a changed case is refused, a longer end_time continues the run"

# ---- run directories ----
"$BIN" run "$C3" --out "$TMP/3d_bar.full" -q "${q3[@]}" >"$TMP/stale.log" 2>&1
rc=$?
[ "$rc" = 2 ] && grep -q "holds the results of another run" "$TMP/stale.log" ||
  { cat "$TMP/stale.log"; fail "a directory with results was not refused (rc $rc)"; }
touch "$TMP/3d_bar.full/fields/fields_0099.vtu"
"$BIN" run "$C3" --out "$TMP/3d_bar.full" -q "${q3[@]}" --overwrite >"$TMP/over.log" 2>&1 || fail "--overwrite"
[ ! -e "$TMP/3d_bar.full/fields/fields_0099.vtu" ] || fail "--overwrite left an old field file"
echo "ok: results of another run: refused, or removed with --overwrite"
"$BIN" run "$C3" --out "$TMP/lock" -q --threads 1 "${slow[@]}" >"$TMP/lock1.log" 2>&1 &
pid=$!
for k in $(seq 1 600); do [ -s "$TMP/lock/energy.csv" ] && break; sleep 0.05; done
"$BIN" run "$C3" --out "$TMP/lock" -q "${slow[@]}" --overwrite >"$TMP/lock2.log" 2>&1
rc=$?
kill -TERM $pid 2>/dev/null
wait $pid
[ "$rc" = 2 ] && grep -q "in use by another cdemblast run" "$TMP/lock2.log" ||
  { cat "$TMP/lock2.log"; fail "a second run into a locked directory was not refused (rc $rc)"; }
echo "ok: a second run into a directory in use is refused"
if /usr/bin/python3 -c 'import matplotlib' 2>/dev/null; then
  sed -i 's/"run_id": "[0-9a-f]*"/"run_id": "0123456789abcdef"/' "$TMP/2d_bar.full/summary.json"
  "$BIN" report "$TMP/2d_bar.full" >"$TMP/mixed.log" 2>&1
  rc=$?
  [ "$rc" = 2 ] && grep -q "belong to different runs" "$TMP/mixed.log" ||
    { cat "$TMP/mixed.log"; fail "report did not refuse mixed run ids (rc $rc)"; }
  echo "ok: report refuses outputs of different runs"
fi
# ---- a write error (a file-size limit, as a full disk): a clear message, no half checkpoint ----
(ulimit -f 200; trap '' XFSZ; exec "$BIN" run "$C3" --out "$TMP/full" -q "${q3[@]}") >"$TMP/full.log" 2>&1
rc=$?
[ "$rc" = 1 ] && grep -q "cannot write '$TMP/full/.*File too large" "$TMP/full.log" ||
  { cat "$TMP/full.log"; fail "a write error: rc $rc, expected 1 and a message naming the file"; }
[ -z "$(find "$TMP/full" -name '*.tmp')" ] || fail "a write error left a partial file"
echo "ok: a write error stops the run with a message naming the file, and no partial checkpoint"
echo "PASS"
