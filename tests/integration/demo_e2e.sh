#!/usr/bin/env bash
# End-to-end: `idrig demo` inside a private network namespace (udpm, ttl=0), then the
# catalogue is checked with the sqlite3 shell: five models (four identifications and one gap
# diagnosis), one per request, each with its lineage (experiment and its signal, data hash,
# method, options, software version, time), and the diagnosis report.
# Usage: demo_e2e.sh path/to/idrig   (needs root for unshare -n; exits 77 = skipped otherwise)
set -euo pipefail
idrig=$(readlink -f "$1")
if [ "$(id -u)" -ne 0 ] || ! command -v unshare >/dev/null || ! command -v sqlite3 >/dev/null; then
  echo "skipped: needs root, unshare and sqlite3"; exit 77
fi
if ! unshare -n sh -c 'ip link set lo up multicast on && ip route add 224.0.0.0/4 dev lo' 2>/dev/null; then
  echo "skipped: cannot create a network namespace here (unshare -n)"; exit 77
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
unshare -n sh -c 'ip link set lo up multicast on && ip route add 224.0.0.0/4 dev lo && exec "$0" demo --no-netns --dir "$1" --speed 100' "$idrig" "$dir/demo" > "$dir/out.txt" 2>&1 || { cat "$dir/out.txt"; exit 1; }
db="$dir/demo/catalog.db"
q() { sqlite3 -batch -noheader -cmd ".timeout 5000" "$db" "$1"; }
fail() { echo "FAIL: $*"; cat "$dir/out.txt"; exit 1; }

[ "$(q 'PRAGMA integrity_check')" = ok ] || fail "integrity_check"
[ "$(q 'PRAGMA journal_mode')" = wal ] || fail "not WAL"
[ "$(q 'SELECT count(*) FROM models')" = 5 ] || fail "expected 5 models, got $(q 'SELECT count(*) FROM models')"
[ "$(q 'SELECT count(DISTINCT request_id) FROM models')" = 5 ] || fail "a request stored twice"
[ "$(q "SELECT group_concat(method, ',') FROM (SELECT DISTINCT method FROM models ORDER BY method)")" = "arx,arx-oe,finite-frequency,gap-diagnose" ] \
  || fail "methods: $(q 'SELECT group_concat(method) FROM models')"
# Lineage: every model joins its experiment, which names its signal; hashes and versions set.
[ "$(q "SELECT count(*) FROM models m JOIN experiments e USING (rig_id, experiment_id)
        WHERE e.state = 'done' AND e.signal_spec <> '' AND length(m.data_hash) = 64
          AND m.software_version <> '' AND m.options_json LIKE '{%' AND m.created_utime > 0
          AND m.n_samples = e.samples_total")" = 5 ] || fail "lineage incomplete: $(q 'SELECT * FROM experiments')"
[ "$(q "SELECT count(*) FROM experiments WHERE signal_spec LIKE 'step:%' OR signal_spec LIKE 'multisine:%' OR signal_spec LIKE 'diagnose:%'")" = 3 ] || fail "experiments"
# Two models of the same experiment identified the same data.
[ "$(q 'SELECT count(DISTINCT data_hash) FROM models')" = 3 ] || fail "data hashes"
[ "$(q "SELECT count(*) FROM jobs WHERE state = 'done'")" = 5 ] || fail "jobs not done"
# The gap diagnosis of the demo's mis-set sim model (slow pole 20 % off): a parameter mismatch,
# stored with its lineage, rendered again by `idrig gap report`.
[ "$(q "SELECT count(*) FROM diagnosis_reports d JOIN models m USING (model_id)
        WHERE m.method = 'gap-diagnose' AND d.request_id = m.request_id
          AND d.experiment_id = m.experiment_id")" = 1 ] || fail "diagnosis report lineage"
"$idrig" gap report 1 --db "$db" --plots "$dir/gap" | grep -q "^verdict: parameter_mismatch" || fail "gap report"
grep -q "</svg>" "$dir/gap/gap_frequency.svg" || fail "gap plots"
# The multisine arx-oe model finds the plant's slow pole -0.5 within 5 %.
[ "$(q "SELECT count(*) FROM metrics x JOIN models m USING (model_id) JOIN experiments e USING (rig_id, experiment_id)
        WHERE m.method = 'arx-oe' AND e.signal_spec LIKE 'multisine:%' AND x.name = 'wn_1'
          AND abs(x.value - 0.5) < 0.025")" = 1 ] || fail "slow pole"
# The command line reads the same catalogue.
"$idrig" models list --db "$db" | grep -q finite-frequency || fail "models list"
"$idrig" models show 1 --db "$db" --json | grep -q '"data_hash"' || fail "models show"
"$idrig" models history --db "$db" --rig sim1 --param wn_1 --svg "$dir/h.svg" | grep -q "model" || fail "models history"
grep -q "<polyline" "$dir/h.svg" || fail "history plot"
# The history plot: axes with units, ticks, a legend entry per method (4 methods have wn_1).
[ "$(grep -c 'class="legend"' "$dir/h.svg")" = 4 ] || fail "history legend: $(grep -c 'class="legend"' "$dir/h.svg") entries"
grep -q 'wn_1 \[rad/s\]' "$dir/h.svg" || fail "history y axis label"
[ "$(grep -o 'class="tick"' "$dir/h.svg" | wc -l)" -ge 6 ] || fail "history ticks"
# The demo's last lines: the dashboard command with this run's paths, and no build/bin hint
# (it names the running binary).
grep -q "serve --db $dir/demo/catalog.db --experiments $dir/demo/experiments.db" "$dir/out.txt" || fail "dashboard command"
hint=$(sed -n 's/^next: \([^ ]*\) models list.*/\1/p' "$dir/out.txt")
[ -x "$hint" ] && [ "$(readlink -f "$hint")" = "$idrig" ] || fail "next: hint '$hint' is not the running binary from here"
# models compare: aligned, with a difference column; export: the whole lineage.
"$idrig" models compare 1 2 --db "$db" > "$dir/cmp.txt"
grep -q "difference (b - a)" "$dir/cmp.txt" && grep -Eq "^samples +300 +300 +0$" "$dir/cmp.txt" || fail "models compare: $(cat "$dir/cmp.txt")"
"$idrig" models export 2 --db "$db" > "$dir/m2.json"
for key in worker_id n_samples sample_time_s compute_s data_hash signal_spec record_fit_percent; do
  jq -e ".identification | has(\"$key\")" "$dir/m2.json" >/dev/null || fail "export lacks $key"
done
# Experiments: list, export as CSV and .mat; the .mat identified again gives the stored model's
# poles (same data, same method and options -> the same slow pole to 1e-6).
"$idrig" experiment list --db "$db" --experiments "$dir/demo/experiments.db" | grep -q "multisine:.* *" || fail "experiment list"
ms=$(q "SELECT experiment_id FROM experiments WHERE signal_spec LIKE 'multisine:%'")
"$idrig" experiment export "$ms" --experiments "$dir/demo/experiments.db" --out "$dir/ms.csv" 2>/dev/null
[ "$(wc -l < "$dir/ms.csv")" = "$(( $(q "SELECT samples_total FROM experiments WHERE experiment_id = $ms") + 1 ))" ] || fail "CSV export length"
"$idrig" experiment export "$ms" --experiments "$dir/demo/experiments.db" --out "$dir/ms.mat" 2>/dev/null
stored=$(q "SELECT printf('%.6f', x.value) FROM metrics x JOIN models m USING (model_id) WHERE m.method = 'arx-oe' AND m.experiment_id = $ms AND x.name = 'wn_1'")
again=$("$idrig" identify --data "$dir/ms.mat" --u u --y y --method arx-oe --order 3 --json | jq -r '.identification.details.continuous_poles | map(.[0]*.[0] + .[1]*.[1] | sqrt) | min | . * 1e6 | round / 1e6')
[ "$(printf '%.6f' "$again")" = "$stored" ] || fail "the .mat export identified again: wn_1 $again, stored $stored"
"$idrig" models export 2 --db "$db" --out "$dir/m2.mat" 2>/dev/null && [ -s "$dir/m2.mat" ] || fail "models export .mat"
# Bad input is named and exits 2.
expect2() { local what=$1 rc=0; shift; "$@" > /dev/null 2> "$dir/err.txt" || rc=$?
  [ $rc -eq 2 ] && grep -q "$what" "$dir/err.txt" || fail "$what (exit $rc): $(cat "$dir/err.txt")"; }
expect2 "no experiment 42" "$idrig" experiment export 42 --experiments "$dir/demo/experiments.db" --out "$dir/x.csv"
expect2 "must end in .csv or .mat" "$idrig" experiment export "$ms" --experiments "$dir/demo/experiments.db" --out "$dir/x.txt"
expect2 "variable 'speed' not found" "$idrig" identify --data "$dir/ms.mat" --u u --y speed
expect2 "name the input and output variables" "$idrig" identify --data "$dir/ms.mat"
expect2 "no model 99" "$idrig" models compare 1 99 --db "$db"
expect2 "has metric 'wn_9'" "$idrig" models history --db "$db" --rig sim1 --param wn_9 --svg "$dir/x.svg"
expect2 "does not exist" "$idrig" serve --db "$dir/none.db"
expect2 "has no index.html" "$idrig" serve --db "$db" --web-dir "$dir"
# The dashboard's API: read-only, on 127.0.0.1, JSON errors.
"$idrig" serve --db "$db" --experiments "$dir/demo/experiments.db" --port 0 > "$dir/serve.txt" 2>&1 &
server=$!
for _ in $(seq 50); do grep -q "http://" "$dir/serve.txt" && break; sleep 0.1; done
url=$(grep -o 'http://127.0.0.1:[0-9]*' "$dir/serve.txt" | head -1)
[ -n "$url" ] || fail "idrig serve: $(cat "$dir/serve.txt")"
[ "$(curl -s "$url/api/models" | jq length)" = 5 ] || fail "api/models"
[ "$(curl -s -o /dev/null -w '%{http_code}' -X POST -d x=1 "$url/api/models")" = 405 ] || fail "POST is not refused"
[ "$(curl -s -o /dev/null -w '%{http_code}' "$url/api/models/99")" = 404 ] || fail "missing model is not 404"
# The arx model's id: the two step jobs are stored in whichever order the workers finish.
arx_id=$(curl -s "$url/api/models?method=arx" | jq -r '[.[] | select(.method == "arx")][0].model_id')
curl -s "$url/api/models/$arx_id/bode" | jq -e '.band.mag_db_lo | length > 100' >/dev/null || fail "Bode band of the arx model"
cmp -s <(curl -s "$url/api/experiments/sim1/$ms/export.csv") "$dir/ms.csv" || fail "CSV export over HTTP differs from the CLI's"
kill "$server"
grep -q "\[4/4\]" "$dir/out.txt" || fail "demo output"
echo "demo end-to-end: ok"
