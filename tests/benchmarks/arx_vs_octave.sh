#!/usr/bin/env bash
# Same data, same run: idrig's ARX against Octave's `arx` (octave-control), N = 2·10^5, order 3.
# Usage: tests/benchmarks/arx_vs_octave.sh [build dir]   (installs octave-control if missing)
set -euo pipefail
build=${1:-build}
bash "$(dirname "$0")/../../deploy/install-bench-deps.sh"
dir=$(mktemp -d); trap 'rm -rf "$dir"' EXIT
"$build/bin/idrig" example --out "$dir/rec.csv" --samples 200000 --noise 0.01 --seed 3
echo "idrig arx (order 3, ε by GCV, all five forms), 5 runs:"
for i in 1 2 3 4 5; do
  /usr/bin/time -f "  %e s wall, %M kB peak RSS" "$build/bin/idrig" identify --data "$dir/rec.csv" --method arx --order 3 > /dev/null
done
echo "  (wall time includes reading the 200k-line CSV text; the solver alone on the same plant and N:)"
"$build/bin/arx_benchmark" --benchmark_filter='N:200000/order:3/' --benchmark_counters_tabular=true 2>/dev/null | grep BM_
cat > "$dir/run.m" <<OCT
pkg load control
d = dlmread('$dir/rec.csv', ',', 1, 0);
dat = iddata(d(:,3), d(:,2), 0.2);
arx(dat, 'na', 3, 'nb', 3, 'nk', 1);  % warm-up
t = zeros(1, 5);
for i = 1:5, tic; m = arx(dat, 'na', 3, 'nb', 3, 'nk', 1); t(i) = toc; end
printf('octave arx (na = nb = 3, nk = 1), 5 runs: median %.4f s (min %.4f s)\n', median(t), min(t));
OCT
octave-cli -q "$dir/run.m"
