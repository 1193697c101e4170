#!/usr/bin/env bash
# Packages needed only by the benchmarks: Octave with its control and signal packages (the
# comparison benchmarks) and clang (libFuzzer for tests/fuzz/run_fuzz.sh).
set -euo pipefail
need=()
for p in octave octave-control octave-signal time clang bc; do  # octave-signal: invfreqs (frequency_vs_octave.sh)
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || need+=("$p")
done
if ((${#need[@]})); then
  DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${need[@]}"
fi
