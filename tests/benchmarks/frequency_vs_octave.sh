#!/usr/bin/env bash
# Frequency-domain fits ([Balda] section 2) against Octave's invfreqs (octave-signal), on the
# same files in the same run, plus the real-data runs (skipped when ../shared/data is absent).
# Usage: tests/benchmarks/frequency_vs_octave.sh [build dir]   (installs octave-signal if missing)
set -euo pipefail
build=${1:-build}
bash "$(dirname "$0")/../../deploy/install-bench-deps.sh"
dir=$(mktemp -d); trap 'rm -rf "$dir"' EXIT
bench="$build/bin/frequency_benchmark"

echo "== speed: 10^4 lines, order 10 (numerator 8)"
"$bench" speed "$dir/speed.csv"
echo "== bias: seed 001 plant, 1 % noise"
"$bench" bias "$dir/bias.csv"

cat > "$dir/run.m" <<OCT
pkg load signal
function e = pole_error(truth, est)
  e = 0;
  for i = 1:numel(truth), e = max(e, min(abs(truth(i) - est))); end
end
function [H, w, p] = load_case(file)
  d = dlmread(file, ',', 1, 0);
  H = d(:,2) + 1i * d(:,3); w = 2 * pi * d(:,1);
  q = dlmread([file '.poles'], ','); p = q(:,1) + 1i * q(:,2);
end
[H, w, p] = load_case('$dir/speed.csv');
[B, A] = invfreqs(H, w, 8, 10);  % warm-up
t = zeros(1, 5);
for i = 1:5, tic; [B, A] = invfreqs(H, w, 8, 10); t(i) = toc; end
printf('octave invfreqs (nB = 8, nA = 10) on the same 10^4 lines: median %.4f s (min %.4f s), max pole error %.3g\n', ...
       median(t), min(t), pole_error(p, roots(A)));
[H, w, p] = load_case('$dir/bias.csv');
[B, A] = invfreqs(H, w, 1, 3);
[B2, A2] = invfreqs(H, w, 1, 3, [], 30);  % iter: accepted but not implemented (plain Levy)
printf('octave invfreqs on the bias file (seed 1): max pole error %.4g; with iter = 30: %.4g\n', ...
       pole_error(p, roots(A)), pole_error(p, roots(A2)));
OCT
octave-cli -q "$dir/run.m" 2>&1 | grep -v "^warning: \|^warning: called from\|^    \|execution_exception"

echo "== pole-residue on Balda's table: Cramer-Rao bound (Octave), then the fits"
octave-cli -q "$(dirname "$0")/pole_residue_crb.m" 2>&1 | grep -v "execution_exception"
"$bench" balda
echo "== real data"
"$bench" real "${2:-$(cd "$(dirname "$0")/../../.." && pwd)/shared}"
