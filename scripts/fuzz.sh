#!/usr/bin/env bash
# Fuzz the case parser and the MSH reader (libFuzzer targets of tests/fuzz, built by
# `make fuzz` into build-fuzz/), then replay every kept crash regression through both.
#   scripts/fuzz.sh [-b BUILD] [-t SECONDS] [-o LOGDIR] [case|msh]...
# -t: seconds per target (default 45: the CI smoke run); -o: where logs and any crashing
# inputs go (default: a temporary directory, removed unless something was found). The seed
# corpora in tests/fuzz (and the minimised corpus of the last campaign,
# corpus_<target>_campaign.tar.gz) are copied first: a run never writes into the source tree
# (add new crashers to tests/fuzz/regressions by hand, with a test that names them).
# Exit status 1 when a target crashed, hung, ran out of memory or reported a sanitizer error.
set -uo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=$ROOT/build-fuzz
SECONDS_EACH=45
LOGDIR=""
while getopts "b:t:o:" opt; do
  case $opt in
    b) BUILD=$(cd "$OPTARG" && pwd) ;;
    t) SECONDS_EACH=$OPTARG ;;
    o) LOGDIR=$OPTARG ;;
    *) echo "usage: $0 [-b BUILD] [-t SECONDS] [-o LOGDIR] [case|msh]..." >&2; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
targets=("$@")
[[ ${#targets[@]} -eq 0 ]] && targets=(case msh)
keep=1
if [[ -z $LOGDIR ]]; then LOGDIR=$(mktemp -d); keep=0; fi
mkdir -p "$LOGDIR"
# malloc_context_size=2: twice the executions per second (toml11 allocates much); reports
# still show where an allocation happened, two frames deep.
export ASAN_OPTIONS=${ASAN_OPTIONS:-malloc_context_size=2}
status=0
for t in "${targets[@]}"; do
  bin=$BUILD/fuzz_$t
  [[ -x $bin ]] || { echo "fuzz.sh: no $bin (run: make fuzz)" >&2; exit 2; }
  work=$LOGDIR/work_$t
  mkdir -p "$work" "$LOGDIR/crashes_$t"
  cp "$ROOT"/tests/fuzz/corpus_"$t"/* "$work"/
  # The minimised corpus of the last campaign (docs/input_safety.md), when there is one.
  archive=$ROOT/tests/fuzz/corpus_${t}_campaign.tar.gz
  [[ -f $archive ]] && tar -C "$work" -xzf "$archive"
  dict=$ROOT/tests/fuzz/$([[ $t == case ]] && echo toml || echo msh).dict
  echo "fuzz.sh: $t for $SECONDS_EACH s (log $LOGDIR/fuzz_$t.log)"
  "$bin" "$work" -dict="$dict" -max_total_time="$SECONDS_EACH" -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="$LOGDIR/crashes_$t/" >"$LOGDIR/fuzz_$t.log" 2>&1
  rc=$?
  grep -E '^(Done|stat::number_of_executed_units|stat::average_exec_per_sec|stat::peak_rss_mb)' \
    "$LOGDIR/fuzz_$t.log" | sed 's/^/  /'
  grep -E '^#[0-9]+.*(DONE|cov:)' "$LOGDIR/fuzz_$t.log" | tail -1 | sed 's/^/  last: /'
  if [[ $rc -ne 0 ]] || compgen -G "$LOGDIR/crashes_$t/*" >/dev/null; then
    echo "fuzz.sh: $t FAILED (exit $rc); inputs in $LOGDIR/crashes_$t, log $LOGDIR/fuzz_$t.log" >&2
    grep -E 'ERROR|SUMMARY|==[0-9]+==' "$LOGDIR/fuzz_$t.log" | head -5 >&2
    status=1
    keep=1
  fi
  # The kept regressions (inputs that once crashed something), run once each.
  regs=("$ROOT"/tests/fuzz/regressions/"$t"/*)
  if [[ -e ${regs[0]} ]]; then
    if ! "$bin" -runs=1 "${regs[@]}" >"$LOGDIR/regressions_$t.log" 2>&1; then
      echo "fuzz.sh: a $t regression input fails again (log $LOGDIR/regressions_$t.log)" >&2
      status=1
      keep=1
    else
      echo "  regressions: ${#regs[@]} inputs pass"
    fi
  fi
done
if [[ $keep -eq 0 ]]; then rm -rf "$LOGDIR"; fi
exit $status
