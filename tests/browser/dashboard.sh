#!/usr/bin/env bash
# Browser test of the dashboard: `idrig demo` makes a catalogue (inside a private network
# namespace, as tests/integration/demo_e2e.sh), `idrig serve` serves it on 127.0.0.1, and
# dashboard_test.mjs drives Debian's headless Chromium through playwright-core.
# Usage: dashboard.sh path/to/idrig [SCREENSHOT_DIR]   (exit 77 = skipped: no chromium, node,
# root/unshare or front end)
set -euo pipefail
idrig=$(readlink -f "$1")
here=$(cd "$(dirname "$0")" && pwd)
web_src="$here/../../tools/idrig/web"
web_dir="$(dirname "$idrig")/../web"
skip() { echo "skipped: $*"; exit 77; }
[ -x /usr/bin/chromium ] || skip "no /usr/bin/chromium (apt-get install chromium)"
command -v node >/dev/null || skip "no node"
[ -d "$web_src/node_modules/playwright-core" ] || skip "no playwright-core (bash deploy/build-web.sh)"
[ -f "$web_dir/index.html" ] || skip "front end not built in $web_dir (bash deploy/build-web.sh)"
command -v sqlite3 >/dev/null || skip "no sqlite3"
if [ "$(id -u)" -ne 0 ] || ! unshare -n sh -c 'ip link set lo up multicast on && ip route add 224.0.0.0/4 dev lo' 2>/dev/null; then
  skip "cannot create a network namespace for the demo (needs root and unshare -n)"
fi
dir=$(mktemp -d)
shots=${2:-$dir/shots}
mkdir -p "$shots"
server=
cleanup() { [ -n "$server" ] && kill "$server" 2>/dev/null; wait 2>/dev/null; rm -rf "$dir"; }
trap cleanup EXIT
unshare -n sh -c 'ip link set lo up multicast on && ip route add 224.0.0.0/4 dev lo && exec "$0" demo --no-netns --dir "$1" --speed 100' \
  "$idrig" "$dir/demo" > "$dir/demo.txt" 2>&1 || { cat "$dir/demo.txt"; exit 1; }
grep -q "idrig serve" "$dir/demo.txt" || { echo "FAIL: the demo does not print the dashboard command"; tail "$dir/demo.txt"; exit 1; }
expected=$(sqlite3 -batch -noheader "$dir/demo/catalog.db" "SELECT group_concat(model_id || ':' || method, ',') FROM (SELECT model_id, method FROM models ORDER BY model_id)")
"$idrig" serve --db "$dir/demo/catalog.db" --experiments "$dir/demo/experiments.db" --port 0 > "$dir/serve.txt" 2>&1 &
server=$!
for _ in $(seq 50); do grep -q "http://" "$dir/serve.txt" && break; sleep 0.1; done
url=$(grep -o 'http://127.0.0.1:[0-9]*' "$dir/serve.txt" | head -1)
[ -n "$url" ] || { echo "FAIL: idrig serve did not start"; cat "$dir/serve.txt"; exit 1; }
node "$here/dashboard_test.mjs" "$url" "$expected" "$shots" "$web_src"
