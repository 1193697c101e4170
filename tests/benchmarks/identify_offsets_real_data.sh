#!/usr/bin/env bash
# identify on real records as recorded, at their operating points (DaISy, shared/data/daisy):
# estimated on the first half, the model simulates the whole record from rest (about its
# operating point when it has one) and is scored on the second half, 100(1 − NRMSE). Three ways:
#   as-is     identify --offsets none   (the record as it is: y = G u)
#   detrended the first half's means removed by hand before identify, added back after (what a
#             MATLAB user does with detrend; the peer for the default)
#   default   identify (auto, offsets=auto: fitted both ways when the means stand out, chosen
#             on the folds)
# Usage: bash tests/benchmarks/identify_offsets_real_data.sh BUILD_DIR SHARED_DIR
set -euo pipefail
idrig=$(realpath "${1:-build}")/bin/idrig
daisy=$(realpath "${2:-../shared}")/data/daisy
[ -d "$daisy" ] || { echo "skip: $daisy not found"; exit 0; }
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT

# whole.csv (t,u,y as recorded), est.csv (first half) and detrended copies of both.
prepare() {  # prepare FILE UCOL YCOL TS
  awk -v uc="$2" -v yc="$3" -v ts="$4" -v w="$work" '
    BEGIN { n = 0 }
    NF > 0 { u[n] = $uc; y[n] = $yc; n++ }
    END {
      h = int(n / 2)
      for (i = 0; i < h; i++) { um += u[i]; ym += y[i] } um /= h; ym /= h
      print um, ym > (w "/means")
      print "t,u,y" > (w "/whole.csv"); print "t,u,y" > (w "/est.csv")
      print "t,u,y" > (w "/whole-d.csv"); print "t,u,y" > (w "/est-d.csv")
      for (i = 0; i < n; i++) {
        printf "%.10g,%s,%s\n", i * ts, u[i], y[i] > (w "/whole.csv")
        printf "%.10g,%.12g,%.12g\n", i * ts, u[i] - um, y[i] - ym > (w "/whole-d.csv")
        if (i < h) {
          printf "%.10g,%s,%s\n", i * ts, u[i], y[i] > (w "/est.csv")
          printf "%.10g,%.12g,%.12g\n", i * ts, u[i] - um, y[i] - ym > (w "/est-d.csv")
        }
      }
    }' "$1"
}

# fit MEASURED SIMULATED SHIFT: 100(1 − NRMSE) on the second half, SHIFT added to the simulation.
fit() {
  paste -d, "$1" "$2" | awk -F, -v shift="$3" 'BEGIN { n = 0 } NR > 1 { y[n] = $3; s[n] = $6 + shift; n++ }
    END { h = int(n / 2); for (k = h; k < n; k++) m += y[k]; m /= n - h
          for (k = h; k < n; k++) { e += (y[k] - s[k])^2; d += (y[k] - m)^2 }
          printf "%.1f", 100 * (1 - sqrt(e / d)) }'
}

run() {  # run NAME FILE UCOL YCOL TS
  [ -f "$daisy/$2" ] || return 0
  prepare "$daisy/$2" "$3" "$4" "$5"
  "$idrig" identify --data "$work/est.csv" --offsets none --json > "$work/m-none.json"
  "$idrig" identify --data "$work/est-d.csv" --json > "$work/m-d.json"
  "$idrig" identify --data "$work/est.csv" --json > "$work/m-auto.json"
  "$idrig" simulate --model "$work/m-none.json" --data "$work/whole.csv" --out "$work/s-none.csv"
  "$idrig" simulate --model "$work/m-d.json" --data "$work/whole-d.csv" --out "$work/s-d.csv"
  "$idrig" simulate --model "$work/m-auto.json" --data "$work/whole.csv" --out "$work/s-auto.csv"
  local ym chosen
  ym=$(awk '{ print $2 }' "$work/means")
  chosen=$(grep -o '"chosen": {[^}]*"candidate": "[^"]*"' "$work/m-auto.json" | sed 's/.*"candidate": "//; s/"$//' || true)
  [ -n "$chosen" ] || chosen=$(python3 -c 'import json,sys; c=json.load(open(sys.argv[1]))["identification"]["selection"]["chosen"]; print(c["candidate"], c["order"])' "$work/m-auto.json")
  printf "%-12s as-is %6s   detrended %6s   default %6s   (default chose %s)\n" "$1" \
    "$(fit "$work/whole.csv" "$work/s-none.csv" 0)" "$(fit "$work/whole.csv" "$work/s-d.csv" "$ym")" \
    "$(fit "$work/whole.csv" "$work/s-auto.csv" 0)" "$chosen"
}

# fit_of METHOD TAG [ARGS…]: identify on the first half, simulate the whole record, fit on the
# second half ("fail" when either step fails); the model is left in $work/e-TAG.json.
fit_of() {
  local m="$1" tag="$2"
  shift 2
  if "$idrig" identify --data "$work/est.csv" --method "$m" "$@" --json > "$work/e-$tag.json" 2>/dev/null &&
     "$idrig" simulate --model "$work/e-$tag.json" --data "$work/whole.csv" --out "$work/es-$tag.csv" 2>/dev/null; then
    fit "$work/whole.csv" "$work/es-$tag.csv" 0
  else
    echo fail
  fi
}

# explicit NAME FILE UCOL YCOL TS: each black-box method named explicitly, as-is (--offsets none)
# and given no offsets (chosen among none, mean and initial when the means stand out).
explicit() {
  [ -f "$daisy/$2" ] || return 0
  prepare "$daisy/$2" "$3" "$4" "$5"
  local line="$1" m
  for m in arx arx-oe oe n4sid armax bj; do
    local as_is given chosen
    as_is=$(fit_of "$m" none --offsets none)
    given=$(fit_of "$m" def)
    chosen=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["identification"].get("offsets", {}).get("chosen", "-"))' "$work/e-def.json" 2>/dev/null || echo "-")
    line+=$(printf "  %s %s→%s (%s)" "$m" "$as_is" "$given" "$chosen")
  done
  echo "$line"
}

records=("dryer dryer.dat 1 2 0.08" "ballbeam ballbeam.dat 1 2 0.1" "exchanger exchanger.dat 2 3 1"
         "robot_arm robot_arm.dat 1 2 1" "flutter flutter.dat 1 2 1" "cd_player CD_player_arm.dat 1 3 1")
for r in "${records[@]}"; do run $r; done
echo "explicit methods: as-is (--offsets none) → given no offsets (chosen)"
for r in "${records[@]}"; do explicit $r; done
