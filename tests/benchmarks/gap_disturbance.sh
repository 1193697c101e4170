#!/usr/bin/env bash
# Output disturbances that do not follow the input, added to bench cases (docs/gap.md, stop 27):
#   hum    a sinusoid at 0.23 of the sample rate, 3 noise sigmas, its own phase per record
#   drift  a ramp of 15 noise sigmas over 4000 samples
#   step   a sensor offset that jumps by 8 noise sigmas halfway through each record
# on the cases of `idrig gap bench --cases 14 --seed 31 --offsets --only none,coulomb_friction,
# time_delay` (written by --dump), then `idrig gap diagnose` on each. Prints per case the truth,
# the verdict, its effects, validation NRMSE before → after and the noise floor.
# Usage: bash tests/benchmarks/gap_disturbance.sh BUILD_DIR [hum|drift|step ...]
set -euo pipefail
build=${1:?usage: gap_disturbance.sh BUILD_DIR [hum|drift|step ...]}
shift
kinds=${*:-hum drift step}
idrig="$build/bin/idrig"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT

"$idrig" gap bench --cases 14 --seed 31 --offsets --jobs 2 --only none,coulomb_friction,time_delay \
  --dump "$dir/cases" > /dev/null 2>&1
for kind in $kinds; do
  for truth in "$dir"/cases/case*-truth.json; do
    c=$(basename "$truth" -truth.json)
    sigma=$(jq .noise_sigma "$truth")
    for part in est val; do
      awk -F, -v k="$kind" -v sg="$sigma" -v ph="$([ "$part" = est ] && echo 0.3 || echo 1.7)" '
        NR == 1 { print; next }
        { n = NR - 2
          if (k == "hum") d = 3 * sg * sin(2 * 3.14159265358979 * 0.23 * n + ph)
          else if (k == "drift") d = 15 * sg * n / 4000
          else d = (n > 2000 ? 8 * sg : 0)
          printf "%s,%s,%.10g\n", $1, $2, $3 + d }' "$dir/cases/$c-$part.csv" > "$dir/$kind-$c-$part.csv"
    done
    out=$("$idrig" gap diagnose --sim "$dir/cases/$c-sim.json" --data "$dir/$kind-$c-est.csv" \
          --validate "$dir/$kind-$c-val.csv" --json)
    printf "%-6s %-7s truth %-17s %s\n" "$kind" "$c" "$(jq -r .effect "$truth")" \
      "$(jq -r '"verdict \(.verdict.effect) [\(.verdict.effects | map(.effect) | join(" + "))]  NRMSE \(.verdict.nrmse_before * 1e4 | round / 1e4) -> \(.verdict.nrmse_after * 1e4 | round / 1e4), floor \(.verdict.noise_nrmse * 1e4 | round / 1e4)"' <<<"$out")"
  done
done
