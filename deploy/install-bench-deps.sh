#!/usr/bin/env bash
# Packages needed only by the comparison benchmarks (Octave, its control and signal packages).
set -euo pipefail
need=()
for p in octave octave-control octave-signal time; do  # octave-signal: invfreqs (frequency_vs_octave.sh)
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || need+=("$p")
done
if ((${#need[@]})); then
  DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${need[@]}"
fi
