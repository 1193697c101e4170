#!/usr/bin/env bash
# Same records, same run: idrig `modal-polyref` (seed 002 section 5, FIR-estimated G(kT)) against
# Octave's subspace methods `moesp` and `n4sid` (octave-control) at the same state dimension
# (2 × the number of modes idrig found; the order is always passed: octave-control's automatic
# order selection needs a terminal). Estimation on the first half of each record, simulation
# fit 100(1 − NRMSE) from zero state on the held-out second half, per output.
# Records: a simulated 3-DOF chain (2 forces, 3 displacements, 1 % output noise) and, when
# ../shared/data is present, DaISy robot_arm.dat (1 in, 1 out) and CD_player_arm.dat (2 in,
# 2 out); their sample time is not given, so Ts = 1 and frequencies are in cycles/sample.
# Usage: tests/benchmarks/modal_vs_octave.sh [build dir]
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$root/build}
idrig=$build/bin/idrig
bash "$root/deploy/install-bench-deps.sh"
dir=$(mktemp -d); trap 'rm -rf "$dir"' EXIT
daisy=$root/../shared/data/daisy
# Options for measured data: modes drift more between orders than in simulation.
real_options=(--option fir_length=100 --option frequency_tolerance=0.02 --option damping_tolerance=0.3
              --option min_stable_fraction=0.3)

# fit VAL SIM NU NY: per-output 100(1 − |y − ŷ|/|y − mean y|) of SIM against VAL (CSV t,u..,y..).
fit() {
  paste -d, "$1" "$2" | awk -F, -v nu="$3" -v ny="$4" 'NR > 1 {
      n++; for (o = 1; o <= ny; ++o) { y = $(1 + nu + o); s = $(2 + 2 * nu + ny + o);
        sy[o] += y; syy[o] += y * y; e[o] += (y - s) ^ 2 } }
    END { for (o = 1; o <= ny; ++o) { v = syy[o] - sy[o] ^ 2 / n; printf "%s%.1f", (o > 1 ? " " : ""), 100 * (1 - sqrt(e[o] / v)) } }'
}

# split FILE.csv: first half -> est.csv, second half (time restarted) -> val.csv
split_half() {
  local n; n=$(($(wc -l < "$1") - 1))
  awk -F, -v half=$((n / 2)) -v out="$2" 'BEGIN { OFS = "," } NR == 1 { print > (out "_est.csv"); print > (out "_val.csv"); next }
    { if (NR - 1 <= half) print > (out "_est.csv"); else { t0 = (t0 == "" ? $1 : t0); $1 = $1 - t0; print > (out "_val.csv") } }' "$1"
}

run_record() {  # name csv Ts nu ny [idrig options…]
  local name=$1 csv=$2 ts=$3 nu=$4 ny=$5; shift 5
  split_half "$csv" "$dir/$name"
  echo "== $name: $(($(wc -l < "$csv") - 1)) samples, $nu in, $ny out (estimation: first half, validation: second half)"
  local start end
  start=$(date +%s.%N)
  "$idrig" identify --data "$dir/${name}_est.csv" --method modal-polyref "$@" > "$dir/$name.txt"
  end=$(date +%s.%N)
  "$idrig" identify --data "$dir/${name}_est.csv" --method modal-polyref "$@" --json > "$dir/$name.json"
  "$idrig" simulate --model "$dir/$name.json" --data "$dir/${name}_val.csv" --out "$dir/${name}_sim.csv"
  local modes; modes=$(awk '/^ *[0-9]+ +[0-9.e+-]+ +[0-9.e+-]+ +[0-9]+ /' "$dir/$name.txt" | wc -l)
  printf "idrig modal-polyref: %.3f s wall; %s modes (f, zeta):" "$(echo "$end - $start" | bc)" "$modes"
  awk '/^ *[0-9]+ +[0-9.e+-]+ +[0-9.e+-]+ +[0-9]+ / { printf " (%.4g, %.3g)", $2, $3 }' "$dir/$name.txt"
  echo "; validation fit % per output: $(fit "$dir/${name}_val.csv" "$dir/${name}_sim.csv" "$nu" "$ny")"
  local order=$((2 * modes)); ((order > 0)) || order=2
  cat > "$dir/$name.m" <<OCT
pkg load control
warning('off', 'all');
e = dlmread('$dir/${name}_est.csv', ',', 1, 0); v = dlmread('$dir/${name}_val.csv', ',', 1, 0);
ue = e(:, 2:1+$nu); ye = e(:, 2+$nu:1+$nu+$ny); uv = v(:, 2:1+$nu); yv = v(:, 2+$nu:1+$nu+$ny);
dat = iddata(ye, ue, $ts);
names = {'moesp', 'n4sid'};
for i = 1:2
  f = str2func(names{i});
  try
    sys = f(dat, $order);  % warm-up (with an output: no singular-value plot)
    tic; sys = f(dat, $order); t = toc;
  catch err
    printf('octave %s (order %d): failed: %s\n', names{i}, $order, err.message); continue;
  end
  ys = lsim(sys, uv);
  fits = 100 * (1 - sqrt(sum((yv - ys).^2)) ./ sqrt(sum((yv - mean(yv)).^2)));
  z = eig(sys.a); s = log(z) / $ts; s = s(imag(s) > 0); [~, k] = sort(abs(s)); s = s(k);
  printf('octave %s (order %d): %.3f s; %d modes (f, zeta):', names{i}, $order, t, numel(s));
  printf(' (%.4g, %.3g)', [abs(s) / (2 * pi), -real(s) ./ abs(s)]');
  printf('; validation fit %% per output: %s\n', sprintf('%.1f ', fits));
end
OCT
  octave-cli -q "$dir/$name.m" 2>&1 | grep -v "ignoring const execution_exception" || true
}

# Simulated 3-DOF chain (the unit tests' plant), uniform random forces, 1 % output noise.
cat > "$dir/chain.json" <<'JSON'
{"format":"idrig.model/1","kind":"ss","domain":"continuous","Ts":0,"delay_s":0,
 "A":[[0,0,0,1,0,0],[0,0,0,0,1,0],[0,0,0,0,0,1],[-2000,1000,0,-1.5,0.5,0],[1000,-2000,1000,0.5,-1.5,0.5],[0,1000,-1000,0,0.5,-1]],
 "B":[[0,0],[0,0],[0,0],[1,0],[0,0],[0,1]],
 "C":[[1,0,0,0,0,0],[0,1,0,0,0,0],[0,0,1,0,0,0]],
 "D":[[0,0],[0,0],[0,0]]}
JSON
awk 'BEGIN { srand(1); print "t,u1,u2,y1,y2,y3";
             for (k = 0; k < 8000; k++) printf "%.6f,%.6f,%.6f,0,0,0\n", k * 0.02, 2 * rand() - 1, 2 * rand() - 1 }' \
  > "$dir/chain_u.csv"
"$idrig" simulate --model "$dir/chain.json" --data "$dir/chain_u.csv" --out "$dir/chain_clean.csv"
awk -F, 'BEGIN { srand(2) } NR == 1 { print; next }
  NR == 2 { for (o = 4; o <= 6; ++o) r[o] = 0 } { n++; for (o = 4; o <= 6; ++o) { ss[o] += $o * $o; y[n, o] = $o }; line[n] = $1 "," $2 "," $3 }
  END { for (i = 1; i <= n; ++i) { printf "%s", line[i];
          for (o = 4; o <= 6; ++o) { g = sqrt(-2 * log(1 - rand())) * cos(6.283185307 * rand());
                                     printf ",%.9g", y[i, o] + 0.01 * sqrt(ss[o] / n) * g }
          printf "\n" } }' "$dir/chain_clean.csv" > "$dir/chain.csv"
echo "true chain modes (Hz, zeta): (2.23986, 0.02128) (6.27595, 0.01620) (9.06901, 0.01863)"
run_record chain "$dir/chain.csv" 0.02 2 3 --option modes=3 --option fir_length=400

if [[ -f $daisy/robot_arm.dat ]]; then
  awk 'BEGIN { print "t,u,y" } NF >= 2 { printf "%d,%s,%s\n", n++, $1, $2 }' "$daisy/robot_arm.dat" > "$dir/robot_arm.csv"
  run_record robot_arm "$dir/robot_arm.csv" 1 1 1 "${real_options[@]}"
else
  echo "== robot_arm: skipped ($daisy/robot_arm.dat absent)"
fi
if [[ -f $daisy/CD_player_arm.dat ]]; then
  awk 'BEGIN { print "t,u1,u2,y1,y2" } NF >= 4 { printf "%d,%s,%s,%s,%s\n", n++, $1, $2, $3, $4 }' \
    "$daisy/CD_player_arm.dat" > "$dir/cd_player_arm.csv"
  run_record cd_player_arm "$dir/cd_player_arm.csv" 1 2 2 "${real_options[@]}"
else
  echo "== CD_player_arm: skipped ($daisy/CD_player_arm.dat absent)"
fi
