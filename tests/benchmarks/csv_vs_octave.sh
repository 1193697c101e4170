#!/usr/bin/env bash
# End to end on the same file, same run (issue 15): `idrig identify --method arx --order 3` on a
# 2·10^5-sample CSV (process start to exit: reading, ARX with all five forms, validation, the
# report) against Octave's dlmread + arx on that file (inside Octave, after `pkg load control`;
# Octave's own start-up is reported separately and not counted).
# Usage: tests/benchmarks/csv_vs_octave.sh [build dir]   (installs Octave if missing)
set -euo pipefail
build=${1:-build}
bash "$(dirname "$0")/../../deploy/install-bench-deps.sh"
dir=$(mktemp -d); trap 'rm -rf "$dir"' EXIT
"$build/bin/idrig" example --out "$dir/rec.csv" --samples 200000 --noise 0.01 --seed 3 > /dev/null
echo "file: $(wc -l < "$dir/rec.csv") lines, $(du -k "$dir/rec.csv" | cut -f1) kB"
times=()
for i in 1 2 3 4 5 6 7; do
  s=$(date +%s.%N)
  "$build/bin/idrig" identify --data "$dir/rec.csv" --method arx --order 3 > /dev/null
  e=$(date +%s.%N)
  times+=("$(echo "$e - $s" | bc -l)")
done
idrig_median=$(printf '%s\n' "${times[@]}" | sort -g | sed -n 4p)
printf 'idrig identify --method arx --order 3, 7 runs: median %.4f s (all: %s)\n' "$idrig_median" "${times[*]}"
cat > "$dir/run.m" <<OCT
pkg load control
t = zeros(1, 5);
for i = 1:5
  tic;
  d = dlmread('$dir/rec.csv', ',', 1, 0);
  m = arx(iddata(d(:,3), d(:,2), 0.2), 'na', 3, 'nb', 3, 'nk', 1);
  t(i) = toc;
end
printf('%.6f\n', median(t));
OCT
octave_median=$(octave-cli -q "$dir/run.m" | tail -1)
printf 'octave dlmread + arx (na = nb = 3, nk = 1), 5 runs inside Octave: median %.4f s\n' "$octave_median"
printf 'ratio octave / idrig end to end: %.1f\n' "$(echo "$octave_median / $idrig_median" | bc -l)"
