#!/usr/bin/env bash
# The SPEC 5.3 example stays runnable: examples/pile_pit_3d/case.toml with each variant's
# overrides of study.toml passes `cdemblast check` (35 000-tet cylinder, 12 bar holes, delay
# groups, two decks per cut hole in scheme C), the decks start when the scheme says, and
# scheme C runs 20 steps to the end (the full 0.05 s runs are docs/pile_pit_3d.md's, not CI's).
#
#   bash test_pile_pit_example.sh <cdemblast-binary> <repo-root>
source "$(dirname "$0")/../script_preamble.sh" "$@"
EX="$ROOT/examples/pile_pit_3d"

# One line per variant: name, then its --set arguments (NUL-free, one per line in a file).
"$PY" - "$EX/study.toml" "$TMP" <<'EOT'
import sys, tomllib, pathlib
study = tomllib.load(open(sys.argv[1], "rb"))
out = pathlib.Path(sys.argv[2])
for v in study["variant"]:
    (out / f"sets_{v['name']}").write_text("\n".join(v.get("set", [])) + "\n")
EOT

for name in A B C; do
  [ -f "$TMP/sets_$name" ] || fail "study.toml has no variant $name"
  args=()
  while IFS= read -r s; do [ -n "$s" ] && args+=(--set "$s"); done <"$TMP/sets_$name"
  "$BIN" check "$EX/case.toml" "${args[@]}" >"$TMP/check_$name.txt" 2>"$TMP/check_$name.err" ||
    fail "scheme $name: check failed: $(tail -3 "$TMP/check_$name.err")"
  grep -q "^check       OK" "$TMP/check_$name.txt" || fail "scheme $name: no 'check OK'"
  n=$(grep -c "^bar         hole" "$TMP/check_$name.txt")
  echo "scheme $name: $n decks"
  case $name in
    A) [ "$n" = 12 ] || fail "A: expected 12 decks, got $n"
       grep -q "hole 'e1' deck 1: .* starts at t = 0 s" "$TMP/check_$name.txt" || fail "A: e1 not at 0" ;;
    B) grep -q "hole 'e1' deck 1: .* starts at t = 0.02 s" "$TMP/check_$name.txt" || fail "B: e1 not at 20 ms"
       grep -q "hole 'e3' deck 1: .* starts at t = 0.03 s" "$TMP/check_$name.txt" || fail "B: e3 not at 30 ms" ;;
    C) [ "$n" = 16 ] || fail "C: expected 16 decks (two per cut hole), got $n"
       grep -q "hole 'c1' deck 1: .* starts at t = 0.01 s" "$TMP/check_$name.txt" || fail "C: lower deck not at 10 ms"
       grep -q "hole 'c1' deck 2: .* starts at t = 0 s" "$TMP/check_$name.txt" || fail "C: upper deck not at 0" ;;
  esac
  cp "$TMP/sets_$name" "$TMP/last_sets"
done

# Scheme C (the last) for 20 steps: it must finish and write its summary.
args=()
while IFS= read -r s; do [ -n "$s" ] && args+=(--set "$s"); done <"$TMP/last_sets"
"$BIN" run "$EX/case.toml" "${args[@]}" --set simulation.max_steps=20 --out "$TMP/run_C" -q \
  2>"$TMP/run_C.err" || fail "scheme C: 20 steps failed: $(tail -3 "$TMP/run_C.err")"
grep -q '"status": "finished"' "$TMP/run_C/summary.json" || fail "scheme C: not finished"
echo "PASS: three schemes check, scheme C runs"
