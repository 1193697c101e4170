#!/usr/bin/env bash
# A fractional delay made by another simulator, diagnosed by idrig gap (docs/gap.md, stop 23).
# The rig is G0 = 144/(s² + 12s + 144) with a delay of DELAY s (default 0.035, 3.5 samples at
# ts = 0.01 s), simulated by `idrig simulate` at 1 ms on the zero-order-held inputs of
# `idrig gap bench --seed 31` case 2 and decimated to 10 ms, with 30 dB of white noise (awk,
# fixed seeds). The sim model is G0 without the delay. Expected: time_delay, τ near DELAY.
# Usage: bash tests/benchmarks/gap_fractional_delay.sh BUILD_DIR [DELAY]
set -euo pipefail
build=${1:?usage: gap_fractional_delay.sh BUILD_DIR [DELAY]}
delay=${2:-0.035}
idrig="$build/bin/idrig"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT

"$idrig" gap bench --cases 3 --seed 31 --jobs 1 --dump "$dir/cases" > /dev/null 2>&1
echo '{"format":"idrig.model/1","kind":"tf","domain":"continuous","Ts":0,"delay_s":0,"num":[144],"den":[1,12,144]}' \
  > "$dir/sim.json"
sed "s/\"delay_s\":0/\"delay_s\":$delay/" "$dir/sim.json" > "$dir/rig.json"
for part in est val; do
  # Zero-order hold at 1 ms: each 10 ms input held for ten fine samples.
  awk -F, 'NR > 1 { for (j = 0; j < 10; j++) printf "%.4f,%s,0\n", ((NR - 2) * 10 + j) * 0.001, $2 }' \
    "$dir/cases/case2-$part.csv" | { echo t,u,y; cat; } > "$dir/fine-$part.csv"
  "$idrig" simulate --model "$dir/rig.json" --data "$dir/fine-$part.csv" --out "$dir/sim-$part.csv"
  seed=$([ "$part" = est ] && echo 11 || echo 12)
  # Every tenth sample, and white noise 30 dB below the output's RMS (Box–Muller).
  awk -F, -v seed="$seed" 'NR > 1 && (NR - 2) % 10 == 0 { n++; u[n] = $2; y[n] = $3; s += $3; ss += $3 * $3 }
    END { m = s / n; sig = sqrt(ss / n - m * m) * 10 ^ (-30 / 20); srand(seed); print "t,u,y"
          for (i = 1; i <= n; i++) { a = rand(); b = rand(); if (a < 1e-12) a = 1e-12
            printf "%.2f,%s,%.8f\n", (i - 1) * 0.01, u[i], y[i] + sig * sqrt(-2 * log(a)) * cos(6.283185307 * b) } }' \
    "$dir/sim-$part.csv" > "$dir/rig-$part.csv"
done
"$idrig" gap diagnose --sim "$dir/sim.json" --data "$dir/rig-est.csv" --validate "$dir/rig-val.csv" --json \
  | jq -r --arg d "$delay" '"true delay \($d) s: verdict \(.verdict.effect), tau \(.verdict.params.tau_s // "n/a") ± \(.verdict.params_std.tau_s // "n/a") s, validation NRMSE \(.verdict.nrmse_after) for a floor of \(.verdict.noise_nrmse)"'
