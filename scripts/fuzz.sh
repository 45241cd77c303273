#!/usr/bin/env bash
# Build the libFuzzer harnesses of tests/fuzz/ with clang (ASan + UBSan) and run each target in
# turn for FUZZ_SECONDS (default 60), one worker, on a scratch copy of its seed corpus (the
# committed corpus stays small). A crash, hang or sanitizer report stops with the input saved
# under FUZZ_OUT/<target>/ (default build-fuzz/findings): copy it to tests/fuzz/regressions/<target>/
# once fixed. Warnings are not errors here (clang warns of what gcc, the build of record, does
# not). The last lines of each target's log (executions, cov, ft) are printed.
#   usage: scripts/fuzz.sh [TARGET...]     (default: scenario checkpoint sweep stl)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${FUZZ_BUILD:-$root/build-fuzz}"
secs="${FUZZ_SECONDS:-60}"
out="${FUZZ_OUT:-$build/findings}"
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(scenario checkpoint sweep stl)
cmake -S "$root" -B "$build" -DCMAKE_C_COMPILER=clang -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSD_SANITIZE=ON \
  -DSD_FUZZ=ON -DSD_WERROR=OFF >/dev/null
cmake --build "$build" -j "${JOBS:-2}" --target $(printf 'fuzz_%s ' "${targets[@]}")
status=0
for t in "${targets[@]}"; do
  work="$build/corpus/$t"
  mkdir -p "$work" "$out/$t"
  cp -n "$root/tests/fuzz/corpus/$t"/* "$work"/ 2>/dev/null || true
  echo "== fuzz_$t for $secs s"
  # -rss_limit_mb: a scene the harness builds stays far below; -timeout: a hang is a finding
  if ! (cd "$out/$t" && OMP_NUM_THREADS=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
        "$build/fuzz_$t" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
        -print_final_stats=1 "$work" "$root/tests/fuzz/regressions/$t" >"$out/$t/fuzz.log" 2>&1); then
    echo "fuzz_$t: a finding, see $out/$t/ (crash-*, timeout-*, leak-*) and $out/$t/fuzz.log"
    status=1
  fi
  grep -E '^#[0-9]+ +(DONE|pulse|NEW|REDUCE)' "$out/$t/fuzz.log" | tail -n 1 || true
  grep -E '^stat::' "$out/$t/fuzz.log" || true
done
exit $status
