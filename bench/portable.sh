#!/usr/bin/env bash
# The speed checks on another machine that has no compiler or libyaml (a bare host, such as
# the 16-core Intel Xeon of performance pass P21, in the git history):
#   bash bench/portable.sh build DIR   here: static sabodem, bench_scale, bench_flume and the
#                                      C test programs (DIR/tests) into DIR, with a settled bed
#                                      for bench_scale (bench/settle.sh, as bench/run.sh makes
#                                      it; skipped if DIR has one)
#   bash bench/portable.sh check DIR [OUT] [--no-run] [--no-scale]   there: the C tests (each at every SIMD
#                                      level that CPU has: AVX-512 is not on the development VM),
#                                      the paper's run on 2 pinned threads, the state hash of a
#                                      short paper run on 1, 2, 4 and 16 threads (all must
#                                      agree), and bench_scale on 1, 2 and 16 threads; logs and
#                                      summaries into OUT (default DIR/out); --no-run: the tests
#                                      only; --no-scale: no bench_scale
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-}
dir=${2:-}
if [ -z "$mode" ] || [ -z "$dir" ]; then
    echo "usage: bash bench/portable.sh build|check DIR [OUT]" >&2
    exit 2
fi

if [ "$mode" = build ]; then
    cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
    cmake --build build -j "$(nproc)" >/dev/null
    mkdir -p "$dir/tests"
    gomp=$(gcc -print-file-name=libgomp.a)
    yaml=/usr/lib/x86_64-linux-gnu/libyaml.a
    for f in "$gomp" "$yaml"; do
        [ -f "$f" ] || { echo "portable.sh: $f is missing (libyaml-dev, gcc)" >&2; exit 1; }
    done
    # a static link (libgomp.a's offloading code names dlopen: a warning, never called; the
    # linker's messages are shown only when the link fails)
    link() {
        local out=$1
        shift
        gcc -O3 -static -fopenmp "$@" -o "$out" build/libsabodem.a "$yaml" -lm 2>"$dir/link.log" ||
            { cat "$dir/link.log" >&2; echo "portable.sh: linking $out failed" >&2; exit 1; }
    }
    for t in sabodem bench_scale bench_flume; do
        link "$dir/$t" $(find "build/CMakeFiles/$t.dir" -name '*.o')
    done
    for d in build/CMakeFiles/test_*.dir; do
        link "$dir/tests/$(basename "$d" .dir)" $(find "$d" -name '*.o')
    done
    rm -f "$dir/link.log"
    if [ ! -f "$dir/settled.data" ]; then
        bash scripts/setup.sh --bench >/dev/null
        bash bench/settle.sh "$dir/settled.data"
    fi
    echo "portable.sh: static binaries and settled.data in $dir"
    exit 0
fi

[ "$mode" = check ] || { echo "portable.sh: unknown mode '$mode' (build or check)" >&2; exit 2; }
out=$dir/out
norun=0
noscale=0
for a in "${@:3}"; do
    case $a in
    --no-run) norun=1 ;;
    --no-scale) noscale=1 ;;
    *) out=$a ;;
    esac
done
mkdir -p "$out"
{ lscpu; nproc; free -g; uname -a; } >"$out/machine.txt" 2>&1 || true
grep -E "Model name|^CPU\(s\)|Thread|Core|Socket|L3" "$out/machine.txt" || true
ms() { echo $(( ($(date +%s%N) - $1) / 1000000 )); }
# the C tests as ctest runs them (from the source tree, one thread unless they ask for more;
# test_neighbor again with the scalar scan), all at once
if [ -d "$dir/tests" ]; then
    s=$(date +%s%N)
    pids=()
    names=()
    for t in "$dir"/tests/test_*; do
        n=$(basename "$t")
        OMP_NUM_THREADS=1 OMP_WAIT_POLICY=passive "$t" >"$out/$n.log" 2>&1 &
        pids+=($!) names+=("$n")
    done
    OMP_NUM_THREADS=1 OMP_WAIT_POLICY=passive "$dir/tests/test_neighbor" scalar >"$out/test_neighbor_scalar.log" 2>&1 &
    pids+=($!) names+=(test_neighbor_scalar)
    bad=0
    for k in "${!pids[@]}"; do
        wait "${pids[$k]}" || { echo "FAILED ${names[$k]} (log: $out/${names[$k]}.log)"; tail -5 "$out/${names[$k]}.log"; bad=1; }
    done
    echo "C tests: ${#pids[@]} programs, $([ $bad = 0 ] && echo 'all passed' || echo 'FAILURES'), $(ms "$s") ms"
    [ $bad = 0 ] || exit 1
fi
[ $norun = 1 ] && exit 0
hash_of() { grep -o '"state_hash":[[:space:]]*"[0-9a-f]*"' "$1/summary.json" | cut -d'"' -f4; }
off=(--set output.vtk=false --set output.png=false)
s=$(date +%s%N)
OMP_PROC_BIND=true OMP_PLACES=cores "$dir/sabodem" run examples/shibuya2009.yaml --threads 2 -o "$out/full" --overwrite \
    "${off[@]}" >"$out/full.log" 2>&1
echo "paper run, 2 threads: $(ms "$s") ms, hash $(hash_of "$out/full")"
tail -1 "$out/full.log"
ref=
for T in 1 2 4 16; do
    s=$(date +%s%N)
    "$dir/sabodem" run examples/shibuya2009.yaml --threads "$T" -o "$out/short$T" --overwrite --set phases.packing_time=0.3 \
        --set phases.flow_limit=0.1 --set phases.capture_limit=0.05 "${off[@]}" >"$out/short$T.log" 2>&1
    h=$(hash_of "$out/short$T")
    echo "short paper run, $T threads: $(ms "$s") ms, hash $h"
    ref=${ref:-$h}
    [ "$h" = "$ref" ] || { echo "portable.sh: $T threads gave $h, 1 thread $ref" >&2; exit 1; }
done
[ $noscale = 1 ] && exit 0
for T in 1 2 16; do
    OMP_PROC_BIND=true OMP_PLACES=cores "$dir/bench_scale" "$dir/settled.data" 2000 --big --threads "$T" |
        tee "$out/scale$T.txt"
done
