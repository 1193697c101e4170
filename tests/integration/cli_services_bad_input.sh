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
expect 2 "" -- "$idrig" demo --port 80
expect 2 "unknown method 'nope'" -- "$idrig" models request --rig sim1 --experiment 1 --method nope
expect 2 "order" -- "$idrig" identify --data "$dir/none.csv" --method arx --order -3
expect 2 "must be a JSON object" -- "$idrig" identify --data "$dir/none.csv" --method arx --options-json '[1]'
# A command that changes state without the operator key says how to give one.
expect 2 "needs the operator key: --key-file FILE or IDRIG_KEY_FILE" -- env -u IDRIG_KEY_FILE "$idrig" experiment stop --rig sim1 --experiment 1
printf "%064d\n" 0 > "$dir/zero.key"; chmod 600 "$dir/zero.key"
expect 2 "repeats a 1-byte pattern" -- "$idrig" experiment stop --rig sim1 --experiment 1 --key-file "$dir/zero.key"
head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \n' > "$dir/open.key"; chmod 644 "$dir/open.key"
expect 2 "chmod 600 $dir/open.key" -- "$idrig" experiment stop --rig sim1 --experiment 1 --key-file "$dir/open.key"
# lcm-spy without a display and without xvfb-run: a sentence, not a Java stack trace.
expect 1 "idrig spy needs a display" -- env -u DISPLAY PATH=/nonexistent "$idrig" spy
echo "service commands reject bad input: ok"
