#!/usr/bin/env bash
# Builds the fuzz targets and runs them, JOBS at a time, SECONDS each, from the committed seeds
# (fuzz/corpus/T) plus the corpus earlier runs grew (fuzz/work/corpus/T, where new inputs go), then
# prints one line per target: its status, executions, coverage and, on a finding, the reproducer.
#
#   fuzz/run-all.sh [--check-seeds] [--no-build] SECONDS [JOBS [TARGET...]]
#
#   --check-seeds  first run every seed (but regress-*) with SHAPEUP_FUZZ_EXPECT_VALID=1: a seed
#                  that no longer reads (or a scene that no longer loads) fails the run
#   --no-build     use the binaries already built
#   JOBS           targets run at the same time (default 1); TARGET... default every target
#
# Exit status 1 when a target crashed, hung (-timeout, or the watchdog past the run), ran out of memory (-rss_limit_mb) or a
# seed check failed. Environment: FUZZ_RSS_MB (2048), FUZZ_TIMEOUT (10 s per input),
# FUZZ_SANITIZER (none; or address), FUZZ_ARGS (more libFuzzer flags).
set -euo pipefail
cd "$(dirname "$0")"

check_seeds=0 build=1
while [[ $# -gt 0 && $1 == --* ]]; do
  case $1 in
    --check-seeds) check_seeds=1 ;;
    --no-build) build=0 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
if [[ $# -lt 1 ]]; then
  sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
fi
seconds=$1 jobs=${2:-1}
shift $(($# < 2 ? $# : 2))
all=(obj ply stl off msh tetgen attribute_roundtrip scene_toml scene_json)
if (($#)); then targets=("$@"); else targets=("${all[@]}"); fi
sanitizer=${FUZZ_SANITIZER:-none}
rss=${FUZZ_RSS_MB:-2048}
timeout=${FUZZ_TIMEOUT:-10}
triple=$(rustc +nightly -vV | sed -n 's/^host: //p')
bin=target/$triple/release

if ((build)); then
  # As --locked: fuzz/Cargo.lock must be committed up to date (cargo fuzz build has no --locked).
  if ! cargo +nightly metadata --locked --format-version 1 >/dev/null; then
    echo "fuzz/Cargo.lock is out of date (shapeup-core's dependencies changed?): run" >&2
    echo "  cargo +nightly metadata --manifest-path fuzz/Cargo.toml --format-version 1 >/dev/null" >&2
    echo "and commit fuzz/Cargo.lock" >&2
    exit 1
  fi
  start=$SECONDS
  cargo +nightly fuzz build -s "$sanitizer"
  echo "== built in $((SECONDS - start)) s (sanitizer $sanitizer)"
fi

mkdir -p work/logs work/dicts
cat dicts/obj.dict dicts/ply.dict dicts/off.dict >work/dicts/attribute_roundtrip.dict
dict() {
  case $1 in
    scene_*) echo dicts/scene.dict ;;
    attribute_roundtrip) echo work/dicts/attribute_roundtrip.dict ;;
    *) echo "dicts/$1.dict" ;;
  esac
}

failed=0
if ((check_seeds)); then
  for t in "${targets[@]}"; do
    seeds=()
    for f in corpus/"$t"/*; do [[ $(basename "$f") == regress-* ]] || seeds+=("$f"); done
    ((${#seeds[@]})) || continue
    if ! SHAPEUP_FUZZ_EXPECT_VALID=1 "$bin/$t" "${seeds[@]}" >"work/logs/$t.seeds.log" 2>&1; then
      echo "!! $t: a seed no longer reads: $(grep -a -m1 'SHAPEUP_FUZZ_EXPECT_VALID\|panicked' -A1 "work/logs/$t.seeds.log" | tail -1)"
      echo "   (log: fuzz/work/logs/$t.seeds.log)"
      failed=1
    fi
  done
  ((failed)) || echo "== every seed reads"
fi

run() {
  local t=$1
  mkdir -p "work/corpus/$t" "work/artifacts/$t"
  # A watchdog past the run's end: libFuzzer's timeout handler allocates inside a signal
  # handler and can deadlock when the slow input was itself in malloc; then this ends the run
  # (status HUNG) instead of waiting forever.
  # shellcheck disable=SC2086  # FUZZ_ARGS is a list of flags
  timeout --kill-after=10 $((seconds + 4 * timeout + 60)) "$bin/$t" "work/corpus/$t" "corpus/$t" -dict="$(dict "$t")" -max_total_time="$seconds" \
    -rss_limit_mb="$rss" -timeout="$timeout" -artifact_prefix="work/artifacts/$t/" \
    -print_final_stats=1 ${FUZZ_ARGS:-} >"work/logs/$t.log" 2>&1
}

start=$SECONDS
pids=()
for t in "${targets[@]}"; do
  while (($(jobs -rp | wc -l) >= jobs)); do wait -n || true; done
  echo "== $t: ${seconds} s"
  run "$t" &
  pids+=("$!")
done
statuses=()
for p in "${pids[@]}"; do
  if wait "$p"; then statuses+=(0); else statuses+=($?); fi
done

printf '\n%-20s %-8s %12s %9s %7s %7s %7s\n' target status execs exec/s cov ft corpus
for i in "${!targets[@]}"; do
  t=${targets[$i]} log=work/logs/${targets[$i]}.log
  stat() { sed -n "s/^stat::$1: *//p" "$log" | tail -1; }
  last=$(grep -a -E '^#[0-9]+' "$log" | tail -1 || true)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
  corp=$(sed -n 's/.* corp: \([0-9]*\)\/.*/\1/p' <<<"$last")
  status=ok
  if ((statuses[i])); then
    failed=1
    status=CRASH
    grep -a -q 'ERROR: libFuzzer: timeout' "$log" && status=TIMEOUT
    grep -a -q 'ERROR: libFuzzer: out-of-memory' "$log" && status=OOM
    grep -a -q 'LeakSanitizer' "$log" && status=LEAK
    if ((statuses[i] == 124 || statuses[i] == 137)); then status=HUNG; fi
  fi
  printf '%-20s %-8s %12s %9s %7s %7s %7s\n' "$t" "$status" "$(stat number_of_executed_units)" \
    "$(stat average_exec_per_sec)" "${cov:-?}" "${ft:-?}" "${corp:-?}"
  if [[ $status != ok ]]; then
    artifact=$(sed -n 's/.*Test unit written to \(.*\)$/\1/p' "$log" | tail -1)
    echo "   reproducer: fuzz/${artifact:-work/artifacts/$t/ (none written)}"
    echo "   log: fuzz/$log; rerun: cd fuzz && cargo +nightly fuzz run -s $sanitizer $t ${artifact:-}"
    grep -a -m1 -A2 'panicked at\|ERROR: libFuzzer\|ALARM' "$log" | sed 's/^/   | /' | cut -c1-300 || true
  fi
done
echo "== fuzzed ${#targets[@]} targets in $((SECONDS - start)) s ($jobs at a time)"
exit "$failed"
