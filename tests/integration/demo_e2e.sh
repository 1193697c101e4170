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
grep -q "\[4/4\]" "$dir/out.txt" || fail "demo output"
echo "demo end-to-end: ok"
