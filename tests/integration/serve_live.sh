#!/usr/bin/env bash
# The dashboard's live view: idrig-catalog and an idrig-worker run as processes on a private
# udpm URL inside a network namespace, `idrig serve --url` listens there, and /api/rigs shows
# both services from their periodic status messages (state, pid, counters).
# Usage: serve_live.sh path/to/idrig   (needs root for unshare -n; exits 77 = skipped otherwise)
set -euo pipefail
idrig=$(readlink -f "$1")
bin=$(dirname "$idrig")
if [ "$(id -u)" -ne 0 ] || ! unshare -n sh -c 'ip link set lo up multicast on && ip route add 224.0.0.0/4 dev lo' 2>/dev/null; then
  echo "skipped: needs root and unshare -n"; exit 77
fi
command -v curl >/dev/null && command -v jq >/dev/null || { echo "skipped: needs curl and jq"; exit 77; }
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
url='udpm://239.255.76.67:7695?ttl=0'
# The services refuse to start without their keys (docs/services.md): fresh ones, mode 600.
for k in operator service; do
  head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \n' > "$dir/$k.key"; chmod 600 "$dir/$k.key"
done
keys="\"operator_key_file\": \"$dir/operator.key\", \"service_key_file\": \"$dir/service.key\", \"state_dir\": \"$dir/state\""
echo "{\"db_path\": \"$dir/catalog.db\", $keys}" > "$dir/catalog.json"
echo "{$keys}" > "$dir/worker.json"
cat > "$dir/run.sh" <<SH
set -eu
ip link set lo up multicast on && ip route add 224.0.0.0/4 dev lo
"$bin/idrig-catalog" --config "$dir/catalog.json" --url '$url' > "$dir/catalog.log" 2>&1 &
c=\$!
"$bin/idrig-worker" --config "$dir/worker.json" --id w-live --url '$url' > "$dir/worker.log" 2>&1 &
w=\$!
for _ in \$(seq 50); do [ -f "$dir/catalog.db" ] && break; sleep 0.1; done
"$idrig" serve --db "$dir/catalog.db" --experiments "$dir/none.db" --url '$url' --port 0 > "$dir/serve.txt" 2>&1 &
s=\$!
for _ in \$(seq 50); do grep -q "http://" "$dir/serve.txt" && break; sleep 0.1; done
api=\$(grep -o 'http://127.0.0.1:[0-9]*' "$dir/serve.txt" | head -1)
n=0
for _ in \$(seq 60); do
  curl -s "\$api/api/rigs" > "$dir/rigs.json" || true
  n=\$(jq '.live.services | length' "$dir/rigs.json" 2>/dev/null || echo 0)
  [ "\$n" -ge 2 ] && break
  sleep 0.25
done
kill \$s \$w \$c
wait 2>/dev/null || true
SH
unshare -n sh "$dir/run.sh"
fail() { echo "FAIL: $*"; cat "$dir/rigs.json" "$dir/serve.txt" 2>/dev/null; exit 1; }
jq -e '.live.listening' "$dir/rigs.json" > /dev/null || fail "not listening"
jq -e '[.live.services[].service] | index("catalog") != null' "$dir/rigs.json" > /dev/null || fail "no catalog service"
jq -e '.live.services[] | select(.instance_id == "w-live") | .pid > 0 and .state != ""' "$dir/rigs.json" > /dev/null || fail "no worker w-live"
echo "serve live: ok ($(jq -c '[.live.services[] | .instance_id + ":" + .state]' "$dir/rigs.json"))"
