#!/usr/bin/env bash
# `cdemblast bench` as a user drives it (docs/performance.md): the built-in model with each
# interface law and mode, a user's own case (--case, set-up timed by part), the same case from a
# run's checkpoint (--from: a late state), and the options that do not go together. Only the
# report's structure and counts are checked: timings are never asserted (a shared machine).
#
#   bash test_bench_cli.sh <cdemblast-binary> <repo-root>
source "$(dirname "$0")/../script_preamble.sh" "$@"
CASE="$ROOT/examples/single_hole_2d/bar.toml"

# json FILE KEY=VALUE...: every key holds the value (a string compared as such, else a number).
json() {
  "$PY" - "$@" <<'EOT'
import json, sys
d = json.load(open(sys.argv[1]))
for kv in sys.argv[2:]:
    k, v = kv.split("=", 1)
    got = d
    for part in k.split("."):
        got = got[part]
    ok = str(got) == v if isinstance(got, str) else float(got) == float(v)
    if not ok:
        sys.exit(f"{k}: {got!r}, expected {v}")
for k in ("ns_per_block_step", "ns_per_block_step_1_thread", "bytes_per_block"):
    if not d[k] > 0:
        sys.exit(f"{k}: {d[k]!r} is not positive")
if not 0.99 < sum(v["share"] for v in d["kernels"].values()) < 1.01:
    sys.exit("kernel shares do not add up to 1")
# the roofline: a measured peak; the tet kernel's flops from the mean Newton iterations (the JSON's
# 3 and 4 significant digits: within 0.1 %), none for a model that is not all tets
if not d["peak_gflops"] > 0:
    sys.exit(f"peak_gflops: {d['peak_gflops']!r}")
tets = d["tet_flops_per_block"] > 0
want = 344 + 72 * d["polar_iterations"] if tets else 0
if abs(d["tet_flops_per_block"] - want) > 1e-3 * want:
    sys.exit(f"tet_flops_per_block {d['tet_flops_per_block']} against {want}")
if tets and not (d["block_kernel_bytes_per_block"] > 0 and d["block_kernel_gflops"] > 0):
    sys.exit("block kernel's bytes or GFlop/s missing")
EOT
}

# 1. The built-in box: both laws, both interface modes.
for law in mohr_coulomb fracture_energy; do
  for mode in tied springs; do
    "$BIN" bench --blocks 600 --steps 3 --law $law --interfaces $mode --json >"$TMP/box.json" 2>"$TMP/err" ||
      fail "bench --law $law --interfaces $mode: $(tail -3 "$TMP/err")"
    json "$TMP/box.json" steps=3 interface_mode=$mode || fail "bench --law $law --interfaces $mode: report"
  done
done
echo "box: both laws, both modes"

# 2. A case: set-up by part, the case's own size, --set applied, the interface mode overridden.
"$BIN" bench --case "$CASE" --steps 4 --set simulation.dt_safety=0.4 --json >"$TMP/case.json" 2>"$TMP/err" ||
  fail "bench --case: $(tail -3 "$TMP/err")"
"$BIN" check "$CASE" --set simulation.dt_safety=0.4 >"$TMP/check.txt"
blocks=$(awk '/^blocks/ {print $2}' "$TMP/check.txt")
json "$TMP/case.json" blocks="$blocks" steps=4 warmup_steps=0 interface_mode=tied || fail "bench --case: report"
"$PY" - "$TMP/case.json" "$TMP/check.txt" <<'EOT' || fail "bench --case: set-up parts or dt"
import json, re, sys
d = json.load(open(sys.argv[1]))
s = d["setup_s"]
parts = s["mesh"] + s["topology"] + s["charges"] + s["simulation"]
# (the JSON holds 4 significant digits: each figure is off by up to 5e-4 of itself, so the parts
# may sum to a little more than the rounded total; seen: 0.12132 against 0.1213)
assert all(s[k] >= 0 for k in s) and parts <= s["total"] * (1 + 1e-3) + 1e-6, s
dt = float(re.search(r"^dt\s+(\S+)", open(sys.argv[2]).read(), re.M).group(1))
assert abs(d["dt"] - dt) <= 1e-3 * dt, (d["dt"], dt)   # check prints 4 digits
EOT
"$BIN" bench --case "$CASE" --steps 2 --interfaces springs --warmup-steps 3 --json >"$TMP/springs.json" 2>"$TMP/err" ||
  fail "bench --case --interfaces springs: $(tail -3 "$TMP/err")"
json "$TMP/springs.json" interface_mode=springs warmup_steps=3 || fail "bench --case --interfaces springs"
echo "case: $blocks blocks, set-up parts, --set, --interfaces, --warmup-steps"

# 3. From a run's checkpoint: the timed steps start at the checkpoint's time.
"$BIN" run "$CASE" --out "$TMP/run" -q --set simulation.end_time=2e-4 >/dev/null 2>"$TMP/err" ||
  fail "run for --from: $(tail -3 "$TMP/err")"
"$BIN" bench --case "$CASE" --from "$TMP/run" --steps 2 --set simulation.end_time=1e-3 >"$TMP/from.txt" 2>"$TMP/err" ||
  fail "bench --from: $(tail -3 "$TMP/err")"
grep -q "state: the newest checkpoint of '$TMP/run' (t = 0.0002" "$TMP/from.txt" || fail "bench --from: no state line: $(cat "$TMP/from.txt")"
echo "from a checkpoint:$(grep 'state:' "$TMP/from.txt")"

# 4. What does not go together, or does not exist: exit 2 with a message naming it.
expect_error() {
  local what=$1 pattern=$2
  shift 2
  local rc=0
  "$BIN" bench "$@" >"$TMP/out" 2>"$TMP/err" || rc=$?
  [ $rc = 2 ] || fail "$what: exit $rc, expected 2"
  grep -q -- "$pattern" "$TMP/err" || fail "$what: message '$(cat "$TMP/err")' lacks '$pattern'"
}
expect_error "--set without --case" "go with --case" --set simulation.end_time=1
expect_error "--from without --case" "go with --case" --from "$TMP/run"
expect_error "--law with --case" "built-in model" --case "$CASE" --law fracture_energy
expect_error "an unknown law" "--law" --law granite
expect_error "an unknown mode" "--interfaces" --interfaces glued
expect_error "--from a directory without checkpoints" "--from $TMP: no checkpoint" --case "$CASE" --from "$TMP"
expect_error "--from another case's run" "differs from the one of the checkpointed run" \
  --case "$ROOT/examples/single_hole_2d/solid.toml" --from "$TMP/run"
expect_error "a missing case" "missing.toml" --case "$TMP/missing.toml"
expect_error "--export with --case" "does not go with --case" --case "$CASE" --export "$TMP/box"
echo "bad options: 9 refused with exit 2"

# --export: the box as a case that `check` and `run` take (the same model as the bench's: its
# block count), and that reads back with its mesh next to it.
"$BIN" bench --export "$TMP/box" --blocks 3000 > "$TMP/export.out" || fail "bench --export"
[ -s "$TMP/box/bench.msh" ] && [ -s "$TMP/box/case.toml" ] || fail "bench --export wrote no case"
n=$(sed -n 's/^bench box: \([0-9]*\) tetrahedra.*/\1/p' "$TMP/export.out")
[ -n "$n" ] || fail "bench --export: no block count in '$(cat "$TMP/export.out")'"
"$BIN" check "$TMP/box/case.toml" > "$TMP/check.out" 2>&1 || { cat "$TMP/check.out"; fail "check of the exported box"; }
grep -q "^blocks *$n\$" "$TMP/check.out" || fail "exported box: not $n blocks ($(grep ^blocks "$TMP/check.out"))"
"$BIN" run "$TMP/box/case.toml" -o "$TMP/box_run" -q -t 1 --set simulation.end_time=2e-5 ||
  fail "run of the exported box"
echo "export: the box as a case, $n blocks, checked and run"
echo "1 passed, 0 failed"
