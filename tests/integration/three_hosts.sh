#!/usr/bin/env bash
# Three "hosts" in network namespaces on a bridge, LCM udpm with ttl=1 (deploy/netns_hosts.sh):
# rig (rig-sim + excite) | logger + catalogue | two workers. One step-free PRBS experiment and
# two identifications. With LOSS > 0 every service drops that fraction of what it receives
# (a lossy network): the experiment must still be stored complete (blocks re-sent by the rig,
# replays by the logger) and the catalogue must hold exactly one model per request.
# Usage: three_hosts.sh BIN_DIR LOSS   (root; exits 77 = skipped otherwise)
set -euo pipefail
bin=$(readlink -f "$1"); loss=${2:-0}
here=$(cd "$(dirname "$0")" && pwd)
script=$here/../../deploy/netns_hosts.sh
if [ "$(id -u)" -ne 0 ] || ! command -v ip >/dev/null || ! command -v sqlite3 >/dev/null; then
  echo "skipped: needs root, iproute2 and sqlite3"; exit 77
fi
if ! { ip netns add "idrig-probe$$" && ip netns del "idrig-probe$$"; } 2>/dev/null; then
  echo "skipped: cannot create network namespaces here (ip netns)"; exit 77
fi
name=idrig$$
dir=$(mktemp -d)
cleanup() { bash "$script" stop "$name" "$dir" || true; bash "$script" down "$name" || true; rm -rf "$dir"; }
trap cleanup EXIT
bash "$script" up "$name"
bash "$script" run "$name" "$bin" "$dir" "$loss" > "$dir/out.txt" 2>&1 || { cat "$dir/out.txt" "$dir"/logs/*.log; exit 1; }
# The workers may have heard every block while the logger lost some: give the logger's repair
# (RIG_REPLAY_REQ to the rig every 0.5 s) up to 10 s to complete its record before stopping.
for _ in $(seq 50); do
  total=$(sqlite3 -batch -noheader -cmd ".timeout 5000" "$dir/experiments.db" 'SELECT max(blocks_total) FROM experiments' 2>/dev/null || echo 0)
  have=$(sqlite3 -batch -noheader -cmd ".timeout 5000" "$dir/experiments.db" 'SELECT count(*) FROM blocks' 2>/dev/null || echo -1)
  [ -n "$total" ] && [ "$total" != 0 ] && [ "$have" = "$total" ] && break
  sleep 0.2
done
bash "$script" stop "$name" "$dir"
fail() { echo "FAIL: $*"; cat "$dir/out.txt"; exit 1; }
q() { sqlite3 -batch -noheader -cmd ".timeout 5000" "$dir/$1" "$2"; }
[ "$(q catalog.db 'SELECT count(*) FROM models')" = 2 ] || fail "models: $(q catalog.db 'SELECT count(*) FROM models')"
[ "$(q catalog.db 'SELECT count(DISTINCT request_id) FROM models')" = 2 ] || fail "duplicate request"
[ "$(q catalog.db 'SELECT count(DISTINCT worker_id) > 0 FROM models WHERE worker_id LIKE '\''h3-worker-%'\''')" = 1 ] || fail "workers"
[ "$(q catalog.db "SELECT count(*) FROM models m JOIN experiments e USING (rig_id, experiment_id)
                    WHERE m.n_samples = e.samples_total AND e.samples_total = 511")" = 2 ] || fail "lineage / sample count"
blocks_total=$(q catalog.db 'SELECT blocks_total FROM experiments')
[ "$(q experiments.db 'SELECT count(*) FROM blocks')" = "$blocks_total" ] || fail "logger holds $(q experiments.db 'SELECT count(*) FROM blocks') of $blocks_total blocks"
[ "$(q catalog.db 'PRAGMA integrity_check')" = ok ] || fail integrity
echo "three hosts (loss $loss): ok"; grep -h "done:" "$dir/out.txt" || true
