#!/usr/bin/env bash
# MATLAB .mat files between idrig and Octave, in one run (Octave is not a test dependency):
#  1. idrig writes: `idrig demo` records and identifies; `idrig experiment export --out FILE.mat`
#     and `idrig models export --out FILE.mat`; Octave's `load` reads both, rebuilds the model
#     with tf(num, den, Ts), and simulates it (lsim) on the exported input: its fit must equal
#     the catalogue's record_fit_percent (computed by idrig's own simulation), its poles the
#     catalogue's.
#  2. Octave writes: the seed-001 plant W(p) = (0.5p + 1)/(p^3 + 2.5p^2 + 4p + 1.5), ZOH at
#     Ts = 0.05 s, driven by a seeded random binary input, output noise σ = 0.005, saved with
#     `save -v7` (compressed) and `-v6`; `idrig identify --data FILE.mat --u u --y y` finds the
#     plant's poles -0.5, -1 ± 1.414j.
# Usage: tests/benchmarks/mat_octave.sh [build dir]
set -euo pipefail
build=$(readlink -f "${1:-build}")
bash "$(dirname "$0")/../../deploy/install-bench-deps.sh"
idrig="$build/bin/idrig"
dir=$(mktemp -d); trap 'rm -rf "$dir"' EXIT
cd "$dir"
"$idrig" demo --dir demo --speed 100 > demo.txt 2>&1 || { tail -20 demo.txt; exit 1; }
db=demo/catalog.db
ok=0; bad=0
check() { if [ "$1" = 1 ]; then ok=$((ok + 1)); echo "ok: $2"; else bad=$((bad + 1)); echo "FAIL: $2"; fi; }

echo "== 1. idrig writes, Octave loads"
for pair in arx:step arx-oe:multisine finite-frequency:multisine; do
  method=${pair%%:*} signal=${pair##*:}
  row=$(sqlite3 -separator ' ' "$db" "SELECT m.model_id, m.experiment_id, x.value FROM models m JOIN metrics x USING (model_id)
        JOIN experiments e USING (rig_id, experiment_id) WHERE m.method = '$method' AND e.signal_spec LIKE '$signal:%' AND x.name = 'record_fit_percent'")
  [ -n "$row" ] || { check 0 "no $method model of a $signal experiment in the demo"; continue; }
  read -r model experiment fit <<< "$row"
  "$idrig" experiment export "$experiment" --experiments demo/experiments.db --out "rec_$model.mat" 2>/dev/null
  "$idrig" models export "$model" --db "$db" --out "model_$model.mat" 2>/dev/null
  poles=$(sqlite3 "$db" "SELECT group_concat(printf('%.6f %.6f', a.value, b.value), ' ') FROM metrics a JOIN metrics b
          ON a.model_id = b.model_id AND b.name = replace(a.name, '_re', '_im') WHERE a.model_id = $model AND a.name LIKE 'pole_%_re' ORDER BY a.name")
  cat > "check_$model.m" <<OCT
pkg load control
r = load('rec_$model.mat'); m = load('model_$model.mat');
if strcmp(m.kind, 'tf'), G = tf(m.num, m.den, m.Ts); else, G = ss(m.A, m.B, m.C, m.D, m.Ts); end
if m.Ts == 0, Gd = c2d(G, r.Ts, 'zoh'); else, Gd = G; end
yhat = lsim(Gd, r.u, r.t);
fit = 100 * (1 - norm(r.y - yhat) / norm(r.y - mean(r.y)));
p = pole(G); if m.Ts > 0, p = log(p) / m.Ts; end
ref = reshape([$poles], 2, [])'; ref = ref(:,1) + 1i * ref(:,2);
perr = max(arrayfun(@(q) min(abs(ref - q)), p)) / max(abs(ref));
printf('%s model %d (%s, Ts %g): %d samples at Ts %g, lineage: %s/%s, worker %s, %d samples\n', m.kind, $model, m.domain, m.Ts, rows(r.u), r.Ts, m.lineage.rig_id, m.lineage.method, m.lineage.worker_id, m.lineage.n_samples);
printf('  Octave lsim fit %.4f %% vs the catalogue record_fit_percent %.4f %%; poles max relative difference %.2e\n', fit, $fit, perr);
exit(double(abs(fit - $fit) > 0.05 || perr > 1e-6 || rows(r.u) != m.lineage.n_samples));
OCT
  if octave-cli -q "check_$model.m"; then check 1 "$method model $model read by Octave, fit and poles agree"; else check 0 "$method model $model"; fi
done

echo "== 2. Octave writes, idrig identifies"
cat > make.m <<'OCT'
pkg load control
rand('seed', 1); randn('seed', 1);
Ts = 0.05; N = 4000;
G = c2d(tf([0.5 1], [1 2.5 4 1.5]), Ts, 'zoh');
u = sign(rand(N, 1) - 0.5); u = kron(u(1:N/10), ones(10, 1));   % random binary, held 10 samples
t = (0:N-1)' * Ts;
y = lsim(G, u, t) + 0.005 * randn(N, 1);
save('-v7', 'octave_v7.mat', 'u', 'y', 'Ts', 't');
save('-v6', 'octave_v6.mat', 'u', 'y', 'Ts');
printf('Octave wrote %d samples (v7 compressed: %d bytes, v6: %d bytes)\n', N, stat('octave_v7.mat').size, stat('octave_v6.mat').size);
OCT
octave-cli -q make.m
for f in octave_v7.mat octave_v6.mat; do
  start=$(date +%s.%N)
  "$idrig" identify --data "$f" --u u --y y --method arx-oe --order 3 --json > "$f.json"
  took=$(echo "$(date +%s.%N) - $start" | bc)
  read -r err text <<< "$(jq -r '.identification.details.continuous_poles as $p
     | [[-0.5, 0], [-1, 1.4142135623730951], [-1, -1.4142135623730951]]
     | map(. as $t | $p | map(((.[0] - $t[0]) * (.[0] - $t[0]) + (.[1] - $t[1]) * (.[1] - $t[1])) | sqrt) | min) | max as $e
     | "\($e) \($p | map("\(.[0] * 1e4 | round / 1e4)\(if .[1] >= 0 then "+" else "" end)\(.[1] * 1e4 | round / 1e4)j") | join(", "))"' "$f.json")"
  echo "  $f: idrig arx-oe poles $text (max distance to the true poles $err rad/s), ${took} s"
  check "$(echo "$err < 0.05" | bc)" "$f identified (poles within 0.05 rad/s of -0.5, -1±1.414j)"
done
echo "$ok passed, $bad failed"
[ "$bad" = 0 ]
