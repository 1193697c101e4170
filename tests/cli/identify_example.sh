#!/usr/bin/env bash
# idrig example | identify: the continuous plant comes back (noise-free) and the JSON model
# written by --json is readable again by `idrig simulate`.
set -euo pipefail
idrig=$1
dir=$(mktemp -d); trap 'rm -rf "$dir"' EXIT
"$idrig" example --out "$dir/rec.csv" --model-out "$dir/plant.json" --noise 0 --samples 500
"$idrig" identify --data "$dir/rec.csv" --method arx --order 3 > "$dir/report.txt"
grep -q "5. W(p)" "$dir/report.txt"
# Noise-free: the recovered denominator is the plant's s^3 + 2.5 s^2 + 4 s + 1.5.
grep -E "\(1 s\^3 \+ 2\.5 s\^2 \+ 4 s \+ 1\.5\)" "$dir/report.txt"
"$idrig" identify --data "$dir/rec.csv" --method arx --order 3 --json > "$dir/model.json"
grep -q '"format": "idrig.model/1"' "$dir/model.json"
"$idrig" simulate --model "$dir/model.json" --data "$dir/rec.csv" --out "$dir/sim.csv"
"$idrig" simulate --model "$dir/plant.json" --data "$dir/rec.csv" --out "$dir/truth.csv"
# The identified model's simulation equals the recorded output to 1e-6.
paste -d, "$dir/rec.csv" "$dir/sim.csv" | awk -F, 'NR > 1 { d = $3 - $6; if (d < 0) d = -d; if (d > m) m = d }
  END { printf "max |y - y_sim| = %g\n", m; exit (m < 1e-6 ? 0 : 1) }'
echo "cli.identify_example: ok"
