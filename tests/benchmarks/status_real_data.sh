#!/usr/bin/env bash
# Issue 15, "a status that tells the truth", on real records: arx and arx-oe at orders 2, 4, 6, 8
# on the first half of five DaISy records (means removed), status and fit of each; the issue
# measured "ok" on all 40 with 18 unstable models. Skips when ../shared/data is absent.
# Usage: tests/benchmarks/status_real_data.sh [build-dir] [shared-dir]
set -euo pipefail
build=${1:-build}
shared=${2:-$(cd "$(dirname "$0")/../../.." && pwd)/shared}
data="$shared/data/daisy"
if [ ! -d "$data" ]; then echo "skip: $data not found"; exit 0; fi
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
# name ucol ycol Ts (columns 1-based in the .dat file)
while read -r name uc yc ts; do
  awk -v uc="$uc" -v yc="$yc" -v ts="$ts" 'BEGIN { n = 0 }
    NF { u[n] = $uc; y[n] = $yc; n++ }
    END { h = int(n / 2); for (i = 0; i < h; i++) { um += u[i]; ym += y[i] } um /= h; ym /= h
          print "t,u,y"; for (i = 0; i < h; i++) printf "%.10g,%.10g,%.10g\n", i * ts, u[i] - um, y[i] - ym }' \
    "$data/$name.dat" > "$work/$name.csv"
  for method in arx arx-oe; do
    for order in 2 4 6 8; do
      "$build/bin/idrig" identify --data "$work/$name.csv" --method "$method" --order "$order" --json |
        jq -r --arg n "$name $method $order" '[$n, .identification.status, (.identification.fit_percent * 10 | round / 10)] | @tsv'
    done
  done
done <<'LIST' | tee "$work/all.tsv"
dryer 1 2 0.08
robot_arm 1 2 1
flutter 1 2 1
ballbeam 1 2 0.1
exchanger 2 3 1
LIST
echo "statuses:"; cut -f2 "$work/all.tsv" | sort | uniq -c
