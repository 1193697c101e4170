#!/usr/bin/env bash
# The service commands of `idrig` reject bad input with a message naming the problem.
# Usage: cli_services_bad_input.sh path/to/idrig
set -uo pipefail
idrig=$1
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
expect() {  # expect CODE PATTERN -- command...
  local code=$1 pattern=$2; shift 3
  out=$("$@" 2>&1); rc=$?
  if [ "$rc" -ne "$code" ] || ! grep -q -- "$pattern" <<<"$out"; then
    echo "FAIL: $* -> rc $rc, output: $out (wanted rc $code and '$pattern')"; exit 1
  fi
}
expect 1 "cannot open SQLite database '$dir/none.db'" -- "$idrig" models list --db "$dir/none.db"
sqlite3 "$dir/empty.db" 'CREATE TABLE x(a)'
expect 1 "is not an idrig catalogue" -- "$idrig" models list --db "$dir/empty.db"
expect 2 "rig id 'bad rig' may only use" -- "$idrig" experiment start --rig "bad rig" --signal step
expect 2 "must be a JSON object" -- "$idrig" models request --rig sim1 --experiment 1 --method arx --options '{oops'
expect 105 "" -- "$idrig" demo --port 80
echo "service commands reject bad input: ok"
