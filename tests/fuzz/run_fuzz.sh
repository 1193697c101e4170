#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan, coverage) in build-fuzz/ and runs each
# for RUNS executions (default 10^6) from its committed seed corpus (tests/fuzz/corpus/<target>;
# new inputs go to build-fuzz/corpus/<target>). A crash leaves build-fuzz/crash-* and stops.
# A benchmark, not a test: figures in docs/services.md ("Fuzzing").
# Usage: tests/fuzz/run_fuzz.sh [RUNS] [TARGET...]   (needs clang: deploy/install-bench-deps.sh)
# FUZZ_NO_BUILD=1 runs the binaries already in build-fuzz/bin (e.g. while another target builds).
set -euo pipefail
cd "$(dirname "$0")/../.."
runs=${1:-1000000}; shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_messages fuzz_excitation_spec fuzz_model_json fuzz_csv fuzz_frf_csv fuzz_effect_json
                                      fuzz_config fuzz_handlers fuzz_worker_logger)
flags="-O1 -g -fno-omit-frame-pointer -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined"
[ "${FUZZ_NO_BUILD:-0}" = 1 ] || cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DIDRIG_FUZZ=ON \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
for t in "${targets[@]}"; do
  [ "${FUZZ_NO_BUILD:-0}" = 1 ] || cmake --build build-fuzz -j2 --target "$t" >/dev/null
  mkdir -p "build-fuzz/corpus/$t"
  before=$(ls "build-fuzz/corpus/$t" | wc -l)
  start=$(date +%s.%N)
  # fuzz_worker_logger makes a memq:// LCM per input; liblcm keeps 40 bytes of each (the
  # GStaticRecMutex of lcm_handle, never freed by lcm_destroy), which made libFuzzer's per-input
  # leak check (a full LSan scan) run after every input: 16 exec/s. Leaks are checked at exit.
  # Its inputs are capped at 1.5 KB (about 60 samples of a SISO record, with the job's messages):
  # the worker runs the method on them; 4 KB inputs gave 150 exec/s on a shared core, 2 KB 230.
  max_len=4096; extra=()
  [ "$t" != fuzz_worker_logger ] || { max_len=1536; extra=(-detect_leaks=0); }
  (cd build-fuzz && "bin/$t" -runs="$runs" -max_len=$max_len -timeout=10 -rss_limit_mb=2048 \
     -print_final_stats=1 "${extra[@]}" "corpus/$t" "../tests/fuzz/corpus/$t" 2> "fuzz-$t.log") \
    || { echo "$t: CRASH (build-fuzz/fuzz-$t.log)"; tail -40 "build-fuzz/fuzz-$t.log"; exit 1; }
  end=$(date +%s.%N)
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "build-fuzz/fuzz-$t.log" | grep -o '[0-9]*$')
  cov=$(grep -o 'cov: [0-9]*' "build-fuzz/fuzz-$t.log" | tail -1 | grep -o '[0-9]*$')
  rss=$(grep -o 'stat::peak_rss_mb: *[0-9]*' "build-fuzz/fuzz-$t.log" | grep -o '[0-9]*$')
  added=$(( $(ls "build-fuzz/corpus/$t" | wc -l) - before ))
  secs=$(echo "$end - $start" | bc)
  printf '%-22s %10s executions in %7.1f s (%6.0f/s), cov %5s edges, %5s new inputs, peak RSS %s MB, no crash\n' \
    "$t" "$execs" "$secs" "$(echo "$execs / $secs" | bc -l)" "$cov" "$added" "$rss"
done
