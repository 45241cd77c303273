#!/usr/bin/env bash
# The work of a particle-step at each size, counted instead of timed (issue 6, deliverable 4):
# bench_scale's timed steps run under callgrind, which counts the instructions they execute (the
# bed's set-up and warm-up are not instrumented), one thread, the front prefetch forced on (so
# that no timed trial decides which instructions run). The count does not depend on the hour or
# on what else the machine runs. With --cache, callgrind also simulates a two-level cache (the
# Zen 5 core's 48 KiB L1d and a last-level cache of LL_BYTES; the CCX's 32 MiB by default) and
# reports the lines the timed steps miss in each, per particle-step.
# Writes bench/results/work.txt (or OUT); takes 5-10 minutes without --cache (1e6 dominates).
#   usage: bash bench/work.sh [--cache [LL_BYTES]] [--same] [--settled FILE] [--out FILE]
#   (--settled: a settled bed from bench/settle.sh; made here with LAMMPS when not given)
set -euo pipefail
cd "$(dirname "$0")/.."
cache=0 ll=$((32 << 20)) same="" settled="" out=bench/results/work.txt
while [ $# -gt 0 ]; do
  case "$1" in
    --cache)
      cache=1
      if [[ "${2:-}" =~ ^[0-9]+$ ]]; then ll=$2; shift; fi
      ;;
    --same) same="--same" ;;
    --settled) settled=${2:?--settled needs a file}; shift ;;
    --out) out=${2:?--out needs a file}; shift ;;
    *) echo "bench/work.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
  shift
done
if [ "$ll" -lt 65536 ] || [ $((ll & (ll - 1))) -ne 0 ]; then
  echo "bench/work.sh: --cache $ll: the last-level cache must be a power of two of 64 KiB or more" >&2
  exit 2
fi
if [ -n "$settled" ] && [ ! -r "$settled" ]; then
  echo "bench/work.sh: --settled: cannot read '$settled'" >&2
  exit 2
fi
bash scripts/setup.sh --work
# a plain Release build of its own (no profile: build-bench may hold the profile-guided flags)
cmake -S . -B build-work -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build-work -j "$(nproc)" --target bench_scale >/dev/null
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
if [ -z "$settled" ]; then
  bash scripts/setup.sh --bench
  settled=$work/settled.data
  bash bench/settle.sh "$settled"
fi
opts=(--tool=callgrind --instr-atstart=no)
# the L1d of a Zen 5 core (48 KiB, 12 ways); the last level 16 ways
[ "$cache" = 1 ] && opts+=(--cache-sim=yes --I1=32768,8,64 --D1=49152,12,64 --LL="$ll,16,64")
mkdir -p "$(dirname "$out")"
{
  echo "# bench/work.sh ${same:-(tiled bed)}: one thread, instructions counted by callgrind over the timed steps"
  [ "$cache" = 1 ] && echo "# simulated caches: L1d 48 KiB, last level $((ll >> 20)) MiB ($ll bytes); misses are lines, reads and writes"
  echo "# $(date -u '+%Y-%m-%d %H:%M UTC'), $(git rev-parse --short HEAD 2>/dev/null || echo '?')"
  printf '%-8s %6s %9s %10s %10s' N steps contacts Ir/p-step Ir/c-step
  [ "$cache" = 1 ] && printf ' %11s %11s' L1miss/p-s LLmiss/p-s
  printf '\n'
} >"$work/table"
# sizes and steps: a multiple of 100 steps each (one candidate rebuild every 100), 1e6 last
for cfg in "1000 1000" "10000 200" "100000 100" "1000000 100"; do
  set -- $cfg
  cg=$work/cg.$1
  line=$(SD_PREFETCH=on valgrind "${opts[@]}" --callgrind-out-file="$cg" ./build-work/bench_scale "$settled" "$2" \
    --threads 1 --only "$1" $same 2>/dev/null | grep '^N ')
  # N, steps and contacts per sphere from bench_scale's line; the counts from callgrind's totals
  awk -v cache="$cache" -v line="$line" '
    /^events:/ { for (i = 2; i <= NF; i++) ev[$i] = i }
    /^totals:/ { for (k in ev) tot[k] = $(ev[k]) }
    END {
      n = split(line, f, " ")
      for (i = 1; i <= n; i++) {
        if (f[i] == "N") N = f[i + 1]
        if (f[i] == "steps") S = f[i + 1]
        if (f[i] == "contacts/sphere") C = f[i + 1]
      }
      ps = N * S
      printf "%-8d %6d %9.2f %10.1f %10.1f", N, S, C, tot["Ir"] / ps, tot["Ir"] / (ps * C / 2)
      if (cache == 1)
        printf " %11.2f %11.2f", (tot["D1mr"] + tot["D1mw"]) / ps, (tot["DLmr"] + tot["DLmw"]) / ps
      printf "\n"
    }' "$cg" >>"$work/table"
  tail -1 "$work/table"
done
cp "$work/table" "$out"
echo "bench/work.sh: $out"
