#!/usr/bin/env bash
# Subspace and prediction-error methods against Octave's n4sid/moesp (control 3.4, SLICOT IB01),
# same files, same run (docs/subspace_pem.md):
#   1. speed: N = 10^5, 2x2, order 8, s = i = 16 block rows;
#   2. Monte Carlo on seed 001's plant (N = 2000, Ts = 0.2 s, binary +-1 held 4 samples, 50
#      seeds, sigma = 0.01 and 0.05): RMS continuous-pole error against the Cramer-Rao bound;
#   3. DaISy records (estimate on the first half, simulate the whole record from rest, fit on
#      the second half): idrig's default (and the default with split=samples), n4sid and oe
#      against Octave's n4sid at the same order.
# Usage: tests/benchmarks/subspace_pem_vs_octave.sh [build dir] [shared dir] [seeds]
set -euo pipefail
build=${1:-build}
shared=${2:-$(cd "$(dirname "$0")/../../.." && pwd)/shared}
seeds=${3:-50}
bash "$(dirname "$0")/../../deploy/install-bench-deps.sh" > /dev/null
bench="$build/bin/subspace_pem_benchmark"
dir=$(mktemp -d); trap 'rm -rf "$dir"' EXIT

echo "== 1. speed (N = 1e5, 2x2, order 8); machine load: $(cut -d' ' -f1-3 /proc/loadavg)"
"$bench" speed "$dir/speed.csv"
cat > "$dir/speed.m" <<OCT
pkg load control
d = dlmread('$dir/speed.csv', ',', 1, 0);
dat = iddata(d(:,4:5), d(:,2:3), 1);
sys = n4sid(dat, 8);  % warm-up
for alg = {'n4sid', 'moesp'}
  t = zeros(1, 5); c = t;
  for i = 1:5, c0 = cputime; tic; sys = feval(alg{1}, dat, 8); t(i) = toc; c(i) = cputime - c0; end
  printf('octave %-5s (dat, 8) (s = 16, Cholesky), N = %d, 2x2: median %.4f s wall (min %.4f s), %.4f s CPU\n', ...
         alg{1}, rows(d), median(t), min(t), median(c));
end
OCT
octave-cli -q "$dir/speed.m" 2>&1 | grep '^octave'

for sigma in 0.01 0.05; do
  echo "== 2. Monte Carlo, sigma = $sigma"
  mkdir -p "$dir/mc$sigma"
  "$bench" montecarlo "$dir/mc$sigma" "$sigma" "$seeds"
  cat > "$dir/mc.m" <<OCT
pkg load control
d0 = '$dir/mc$sigma';
truth = load([d0 '/mc_truth.txt']); truth = truth(:,1) + 1i*truth(:,2);
bound = load([d0 '/mc_bound.txt']);
for alg = {'n4sid', 'moesp'}
  sq = 0; lost = 0;
  for s = 1:$seeds
    d = dlmread(sprintf('%s/mc_%d.csv', d0, s), ',', 1, 0);
    sys = feval(alg{1}, iddata(d(:,3), d(:,2), 0.2), 3);
    p = log(eig(sys.a)) / 0.2; used = false(size(p)); est = zeros(size(truth));
    for i = 1:numel(truth)
      dist = abs(p - truth(i)); dist(used) = inf; [~, j] = min(dist); used(j) = true; est(i) = p(j);
    end
    sq += sum(abs(est - truth).^2);
    lost += any(abs(imag(truth)) > 1e-9 & abs(imag(est)) < 1e-9);
  end
  rms = sqrt(sq / $seeds);
  printf('  octave %-7s order 3 RMS pole error %.5f = %.2f x bound; lost pair %d\n', alg{1}, rms, rms / bound, lost);
end
OCT
  octave-cli -q "$dir/mc.m" 2>&1 | grep 'octave'
done

echo "== 3. DaISy records, first half / second half (fit % on the second half)"
if [ ! -d "$shared/data/daisy" ]; then echo "skip: $shared/data/daisy not found"; exit 0; fi
"$bench" real "$shared" "$dir"
cat > "$dir/real.m" <<OCT
pkg load control
fid = fopen('$dir/real_list.txt'); L = textscan(fid, '%s %d %f %d'); fclose(fid);
function f = fitpct(y, yh)
  f = zeros(1, columns(y));
  for k = 1:columns(y), f(k) = 100 * (1 - norm(y(:,k) - yh(:,k)) / norm(y(:,k) - mean(y(:,k)))); end
end
for r = 1:numel(L{1})
  name = L{1}{r}; nu = double(L{4}(r));
  d = dlmread(['$dir/real_' name '.csv'], ',', 1, 0);
  ts = d(2,1) - d(1,1); u = d(:, 2:1+nu); y = d(:, 2+nu:end); split = floor(rows(d)/2);
  dat = iddata(y(1:split,:), u(1:split,:), ts);
  fid = fopen(['$dir/real_octave_' name '.txt'], 'w');
  for n = 1:8
    try
      sys = n4sid(dat, n);
      yh = lsim(sys, u, [], zeros(rows(sys.a), 1));
      fprintf(fid, '%s octave %d %.6f\n', name, n, mean(fitpct(y(split+1:end,:), yh(split+1:end,:))));
    catch
      fprintf(fid, '%s octave %d nan\n', name, n);
    end
  end
  fclose(fid);
end
OCT
octave-cli -q "$dir/real.m" > /dev/null 2>&1 || true
echo
printf "| %-13s | %-24s | %s | %s | %s | %s | %s | %s | %s |\n" record "idrig default (chosen)" "n4sid" "n4sid D" "oe" "oe nk=0" \
  "Octave n4sid" "default with split=samples: fit (chosen) / Octave at that n" "best over n = 1..8: n4sid D / oe nk=0 / Octave"
echo "|---|---|---|---|---|---|---|---|---|"
while read -r name order fit_default nu; do
  cat "$dir/real_idrig_$name.txt" "$dir/real_octave_$name.txt" 2>/dev/null | awk -v name="$name" -v n="$order" '
    $2 == "default" { def = $4; meth = $5; next }
    $2 == "bysamples" { sdef = $4; smeth = $5; sn = $3; next }
    { key = $2 " " $3; v[key] = $4 }
    $4 != "nan" && $4 != "-nan" { if (!($2 in best) || $4 + 0 > best[$2] + 0) { best[$2] = $4; bn[$2] = $3 } }
    END {
      printf "| %-13s | %5.1f %% (%s, n = %d) | %5.1f | %5.1f | %5.1f | %5.1f | %5.1f | %.1f (%s, n = %d) / %.1f | %.1f (n=%d) / %.1f (n=%d) / %.1f (n=%d) |\n",
        name, def, meth, n, v["n4sid " n], v["n4sid_D " n], v["oe " n], v["oe_nk0 " n], v["octave " n],
        sdef, smeth, sn, v["octave " sn],
        best["n4sid_D"], bn["n4sid_D"], best["oe_nk0"], bn["oe_nk0"], best["octave"], bn["octave"]
    }'
done < "$dir/real_list.txt"
