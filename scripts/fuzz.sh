#!/usr/bin/env bash
# scripts/fuzz.sh BUILD_DIR SECONDS_PER_TARGET [TARGET...]
# Builds hbirl's libFuzzer targets (tests/fuzz; clang, HBIRL_FUZZ=ON, ASan + UBSan) in
# BUILD_DIR and runs each for SECONDS_PER_TARGET seconds on a temporary copy of its seed
# corpus (tests/fuzz/corpus/<target>: the repository's corpus is never written to). Fails
# on any crash, sanitizer report, leak, timeout (-timeout=10) or over-limit allocation,
# printing the reproducer's path and the first lines of the report. Prints each target's
# executions and coverage. Without TARGET arguments: every target.
# Environment: FUZZ_JOBS (parallel builds and targets run at once, default nproc), FUZZ_KEEP=DIR (keep the grown
# corpora and logs in DIR instead of deleting them), FUZZ_ARGS (more libFuzzer flags).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 2 ]; then
  echo "usage: scripts/fuzz.sh BUILD_DIR SECONDS_PER_TARGET [TARGET...]" >&2
  exit 2
fi
build="$1"
seconds="$2"
shift 2
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=(fuzz_problem_file fuzz_lcm_decoders fuzz_service_handlers fuzz_png_frame fuzz_dashboard_http fuzz_recording)
fi
jobs="${FUZZ_JOBS:-$(nproc)}"

start=$(date +%s)
# -O1 with line tables only (as the sanitizer build): fast to compile, file:line in reports.
# Ninja when there is one: it compiles a library's sources while the libraries it links
# are still compiling (Make waits for each library in turn), which keeps both cores busy.
if [ ! -f "$build/CMakeCache.txt" ]; then
  generator=()
  if command -v ninja >/dev/null 2>&1; then generator=(-G Ninja); fi
  CC=clang CXX=clang++ cmake -S . -B "$build" "${generator[@]}" -DHBIRL_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" >/dev/null
fi
cmake --build "$build" -j"$jobs" --target hbirl_fuzz
built=$(date +%s)
echo "fuzz: built in $((built - start)) s"

work="${FUZZ_KEEP:-}"
if [ -z "$work" ]; then
  work="$(mktemp -d /tmp/hbirl-fuzz.XXXXXX)"
  trap 'rm -rf "$work"' EXIT
fi
mkdir -p "$work"

# One target: its run, then its summary line (and, if it failed, its reproducers and report)
# into $work/$t.out, printed in the targets' order once all have run.
fuzz_one() {
  local t="$1" corpus="$work/corpus/$1" log="$work/$1.log" status=0 runs speed cov units first
  mkdir -p "$corpus" "$work/artifacts/$t"
  cp -r tests/fuzz/corpus/"$t"/. "$corpus"/ 2>/dev/null || true
  # -rss_limit_mb above -malloc_limit_mb: one allocation past 1 GB is reported as such
  # (with its stack) before the whole process would be. Leaks are checked (-detect_leaks
  # is libFuzzer's default with ASan).
  # shellcheck disable=SC2086  # FUZZ_ARGS: words on purpose
  ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=1:allocator_may_return_null=0" \
  UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" \
    "$build/tests/fuzz/$t" "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -malloc_limit_mb=1024 -print_final_stats=1 -artifact_prefix="$work/artifacts/$t/" \
      ${FUZZ_ARGS:-} >"$log" 2>&1 || status=$?
  runs=$(grep -a -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  speed=$(grep -a -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  cov=$(grep -a -E '^#[0-9]+' "$log" | grep -o 'cov: [0-9]* ft: [0-9]*' | tail -1 || true)
  units=$(find "$corpus" -type f | wc -l)
  echo "fuzz: $t: $runs executions ($speed/s), ${cov:-cov: ?}, corpus $units"
  if [ "$status" -ne 0 ]; then
    echo "fuzz: $t FAILED (exit $status); reproducer(s):"
    for a in "$work/artifacts/$t"/*; do
      [ -e "$a" ] || continue
      # Outside the temporary directory, which is deleted on exit.
      mkdir -p "$build/fuzz-findings"
      cp "$a" "$build/fuzz-findings/"
      echo "  $build/fuzz-findings/$(basename "$a")  (replay: $build/tests/fuzz/$t $build/fuzz-findings/$(basename "$a"))"
    done
    # The report: from its first line (sanitizer, libFuzzer's deadly signal, timeout or
    # out-of-memory), else the log's end.
    first=$(grep -a -m1 -n -E '==[0-9]+==ERROR|ERROR: libFuzzer|runtime error:|ALARM: working' "$log" | cut -d: -f1 || true)
    if [ -n "$first" ]; then
      sed -n "${first},$((first + 30))p" "$log"
    else
      tail -n 30 "$log"
    fi
    return 1
  fi
}

# The targets $jobs at a time (each is one process on one core): the same seconds each,
# in a fraction of the time.
# (Each writes its exit status to a file: a status reaped by `wait -n` is not asked again.)
for t in "${targets[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do wait -n || true; done
  { status=0; fuzz_one "$t" >"$work/$t.out" 2>&1 || status=$?; echo "$status" >"$work/$t.status"; } &
done
wait
failed=0
for t in "${targets[@]}"; do
  if [ "$(cat "$work/$t.status" 2>/dev/null)" = 0 ]; then
    cat "$work/$t.out"
  else
    failed=1
    cat "$work/$t.out" >&2
  fi
done
echo "fuzz: ${#targets[@]} targets in $(($(date +%s) - start)) s (build $((built - start)) s)"
exit "$failed"
