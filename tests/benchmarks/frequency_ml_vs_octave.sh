#!/usr/bin/env bash
# Frequency-domain ML against the Cramér–Rao bound, idrig and Octave on the same FRFs in the same
# run (issue 15): seed 001's plant, 200 lines, 1 % relative complex noise, SEEDS seeds (default
# 50). idrig: frequency_ml_benchmark (levy-sk, stable-nls, with and without 1/σ weights). Octave:
# invfreqs (octave-signal: weighted Levy; its `iter` argument is accepted but not used) with
# wt = 1/σ and 1/σ² on the same files.
# Usage: tests/benchmarks/frequency_ml_vs_octave.sh [build dir] [seeds]
set -euo pipefail
build=${1:-build}
seeds=${2:-50}
bash "$(dirname "$0")/../../deploy/install-bench-deps.sh"
dir=$(mktemp -d); trap 'rm -rf "$dir"' EXIT
"$build/bin/frequency_ml_benchmark" "$seeds" "$dir"
cat > "$dir/run.m" <<OCT
pkg load signal
truth = dlmread('$dir/poles.csv', ','); truth = truth(:,1) + 1i * truth(:,2);
crb = dlmread('$dir/crb.txt');
names = {'none', '1/sigma', '1/sigma^2'};
sq = zeros(1, 3);
for seed = 1:$seeds
  d = dlmread(sprintf('$dir/frf_%d.csv', seed), ',', 1, 0);
  H = d(:,2) + 1i * d(:,3); w = 2 * pi * d(:,1); s = d(:,4);
  wts = {ones(size(s)), 1 ./ s, 1 ./ s.^2};
  for v = 1:3
    [B, A] = invfreqs(H, w, 1, 3, wts{v});
    p = roots(A); e = 0;
    for i = 1:numel(truth), e = e + min(abs(truth(i) - p))^2; end
    sq(v) = sq(v) + e / $seeds;
  end
end
for v = 1:3
  printf('| octave invfreqs | %s | %.4g | %.2f |\n', names{v}, sqrt(sq(v)), sqrt(sq(v)) / crb);
end
OCT
octave-cli -q "$dir/run.m" 2>&1 | grep -v "^warning: \|^warning: called from\|^    \|execution_exception"
