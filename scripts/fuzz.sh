#!/usr/bin/env bash
# Coverage-guided fuzzing of the readers (libFuzzer, clang, ASan + UBSan); docs/reliability.md.
#
#   scripts/fuzz.sh                          every harness for 30 s (scripts/test.sh runs this)
#   scripts/fuzz.sh --time 600 iges obj      chosen harnesses, 10 minutes each
#   scripts/fuzz.sh --runs 10000000 --soak   the long check: 10^7 executions per harness, one
#                                            after the other, then the soak test (hours)
#   --timeout S                              a unit slower than S seconds fails (default 10; on
#                                            a loaded machine at nice 19, 30: docs/reliability.md)
#   --jobs N                                 N fuzzing processes on one corpus (libFuzzer's fork
#                                            mode; --runs counts all of them; a crash, timeout or
#                                            out-of-memory still stops the run)
#   --keep                                   after a run that found nothing, pack the corpus into
#                                            fuzz/long/NAME.tar.xz (committed: the long runs'
#                                            corpus, which a run with --runs starts from)
#
# Harnesses: iges, obj, scene, cache (fuzz/fuzz_NAME.c). Seeds: fuzz/corpus/NAME plus, when
# present, the shared models of the right kind (SEM_SHARED_MODELS, default ../shared/models)
# no larger than --max-len, and for a run with --runs the long runs' corpus
# fuzz/long/NAME.tar.xz. What libFuzzer finds is kept in build-fuzz/corpus/NAME; a crash, leak,
# timeout (> 10 s) or memory use above 1 GB is saved in build-fuzz/crashes/NAME/ and makes the
# script fail: copy the input into fuzz/regressions/NAME/ once it is fixed, where the test
# suite replays it for ever. The last lines of every run are in build-fuzz/logs/NAME.log.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=30
runs=0
soak=0
max_len=65536
timeout=10
jobs=1
keep=0
names=()
while [ $# -gt 0 ]; do
  case "$1" in
    --time) seconds="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --max-len) max_len="$2"; shift 2 ;;
    --timeout) timeout="$2"; shift 2 ;;
    --jobs) jobs="$2"; shift 2 ;;
    --soak) soak=1; shift ;;
    --keep) keep=1; shift ;;
    -h|--help) sed -n '2,23p' "$0"; exit 0 ;;
    iges|obj|scene|cache) names+=("$1"); shift ;;
    *) echo "fuzz.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ ${#names[@]} -gt 0 ] || names=(iges obj scene cache)
for value in "--time $seconds" "--runs $runs" "--max-len $max_len" "--timeout $timeout" "--jobs $jobs"; do
  [[ "${value#* }" =~ ^[0-9]+$ ]] || { echo "fuzz.sh: ${value% *} needs a whole number, not '${value#* }'" >&2; exit 2; }
done

build="${SEM_FUZZ_BUILD:-build-fuzz}"
bash scripts/setup.sh --fuzz
# (STEP is not fuzzed: Open CASCADE is C++, built by the system compiler, not clang)
CC=clang cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSEM_FUZZ=ON \
  -DSEM_WITH_OCCT=OFF >/dev/null
targets=()
for n in "${names[@]}"; do targets+=("fuzz_$n"); done
cmake --build "$build" -j"$(nproc)" --target "${targets[@]}" >/dev/null

shared="${SEM_SHARED_MODELS:-../shared/models}"
failed=0
for n in "${names[@]}"; do
  corpus="$build/corpus/$n"
  seeds="$build/seeds/$n"
  crashes="$build/crashes/$n"
  mkdir -p "$corpus" "$seeds" "$crashes" "$build/logs"
  if [ "$runs" != 0 ] && [ -f "fuzz/long/$n.tar.xz" ]; then
    tar xJf "fuzz/long/$n.tar.xz" -C "$build/corpus"
  fi
  case "$n" in
    iges) pattern='.*\.(igs|iges)$' ;;
    obj) pattern='.*\.obj$' ;;
    *) pattern='' ;;
  esac
  if [ -n "$pattern" ] && [ -d "$shared" ]; then
    find "$shared" -type f -size -"$((max_len / 1024))"k -regextype posix-extended \
         -regex "$pattern" -exec cp -f {} "$seeds/" \; 2>/dev/null || true
  fi
  limit=(-max_total_time="$seconds")
  [ "$runs" != 0 ] && limit=(-runs="$runs")
  [ "$jobs" -gt 1 ] && limit+=(-fork="$jobs" -ignore_crashes=0 -ignore_timeouts=0 -ignore_ooms=0)
  log="$build/logs/$n.log"
  echo "fuzz: $n: ${limit[*]}, corpus $corpus" >&2
  set +e
  ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1 OMP_NUM_THREADS=1 \
    "$build/fuzz_$n" "$corpus" "fuzz/corpus/$n" "$seeds" "${limit[@]}" \
      -dict="fuzz/dict/$n.dict" -max_len="$max_len" -timeout="$timeout" -rss_limit_mb=1024 \
      -malloc_limit_mb=1024 -print_final_stats=1 -artifact_prefix="$crashes/" \
      >"$log" 2>&1
  rc=$?
  set -e
  grep -E '^#[0-9]+ +DONE|stat::number_of_executed_units|stat::peak_rss_mb|fuzzed for' "$log" >&2 || true
  if [ $rc -ne 0 ]; then
    echo "fuzz: $n FAILED (exit $rc); input saved in $crashes/, log in $log:" >&2
    grep -E 'ERROR|SUMMARY|fuzz:' "$log" | head -5 >&2 || true
    failed=1
  elif [ "$keep" = 1 ]; then
    mkdir -p fuzz/long
    tar cf - -C "$build/corpus" "$n" | xz -9 > "fuzz/long/$n.tar.xz.tmp"
    mv "fuzz/long/$n.tar.xz.tmp" "fuzz/long/$n.tar.xz"
    echo "fuzz: $n: corpus kept in fuzz/long/$n.tar.xz ($(ls "$corpus" | wc -l) units)" >&2
  fi
done

if [ "$soak" = 1 ]; then
  # the soak test measures memory, so it runs in the optimised build without sanitizers
  echo "fuzz: soak test (10,000 steps)" >&2
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build build -j"$(nproc)" --target test_soak >/dev/null
  SEM_SOAK_STEPS=10000 OMP_NUM_THREADS=2 build/test_soak || failed=1
fi
exit $failed
