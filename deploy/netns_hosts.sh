#!/usr/bin/env bash
# A multi-host idrig on one machine: three network namespaces ("hosts") on a bridge, LCM over
# udpm with ttl=1 between them (ttl=0 would stay inside each host).
#   h1: the rig (idrig-rig-sim, idrig-excite)   h2: idrig-logger, idrig-catalog   h3: two workers
# Usage (root):
#   deploy/netns_hosts.sh up NAME            create NAME-sw (bridge) and NAME-h1..h3
#   deploy/netns_hosts.sh run NAME BIN DIR [LOSS]
#                                            start the services (BIN = build/bin, files in DIR),
#                                            LOSS = fraction of received messages each service
#                                            drops (tc netem is not in every kernel; this is the
#                                            lossy-transport equivalent); runs a step experiment
#                                            and two identifications from h2; leaves the services up
#   deploy/netns_hosts.sh stop NAME DIR      stop the services started by run
#   deploy/netns_hosts.sh down NAME          delete the namespaces
# With tc netem available, `ip netns exec NAME-h1 tc qdisc add dev eth0 root netem loss 5%`
# gives real packet loss on a host's link instead.
set -euo pipefail
cmd=${1:?usage: netns_hosts.sh up|run|stop|down NAME ...}
name=${2:?name}
sw=$name-sw
URL="udpm://239.255.76.67:7667?ttl=1&recv_buf_size=4194304"

up() {
  ip netns add "$sw"
  ip -n "$sw" link set lo up
  ip -n "$sw" link add br0 type bridge
  ip -n "$sw" link set br0 type bridge mcast_snooping 0
  ip -n "$sw" link set br0 up
  for i in 1 2 3; do
    local h=$name-h$i
    ip netns add "$h"
    ip -n "$h" link set lo up
    ip -n "$sw" link add "p$i" type veth peer name eth0
    ip -n "$sw" link set eth0 netns "$h"
    ip -n "$sw" link set "p$i" master br0 up
    ip -n "$h" addr add "10.77.0.$i/24" dev eth0
    ip -n "$h" link set eth0 up multicast on
    ip -n "$h" route add 224.0.0.0/4 dev eth0
  done
}

down() {
  for i in 1 2 3; do ip netns del "$name-h$i" 2>/dev/null || true; done
  ip netns del "$sw" 2>/dev/null || true
}

start() {  # start HOST LOGNAME BINARY ARGS...
  local host=$1 log=$2; shift 2
  ip netns exec "$name-$host" "$@" --url "$URL" --loss "$loss" > "$dir/logs/$log.log" 2>&1 &
  echo $! >> "$dir/pids"
}

run() {
  bin=$(readlink -f "${3:?bin dir}"); dir=$(readlink -f "${4:?work dir}"); loss=${5:-0}
  mkdir -p "$dir/logs"
  : > "$dir/pids"
  "$bin/idrig" example --model-out "$dir/plant.json" --out "$dir/example.csv" --samples 10 2>/dev/null
  # The three deployment keys (docs/services.md, "Authentication"): commands (h1 only),
  # operator (the CLI on h2, excite, catalogue, workers), services (catalogue, workers).
  (umask 077
   for k in hmac operator service; do
     [ -f "$dir/$k.key" ] || head -c 32 /dev/urandom | od -v -An -tx1 | tr -d ' \n' > "$dir/$k.key"
   done)
  chmod 600 "$dir"/*.key
  local keys="\"operator_key_file\": \"$dir/operator.key\", \"service_key_file\": \"$dir/service.key\""
  cat > "$dir/rig.json" <<JSON
{"rig_id": "sim1", "model_file": "$dir/plant.json", "noise_std": 0.005, "key_file": "$dir/hmac.key",
 "max_abs": 5, "watchdog_s": 3, "block_samples": 50, "state_dir": "$dir/state-h1/rig"}
JSON
  cat > "$dir/excite.json" <<JSON
{"rig_id": "sim1", "key_file": "$dir/hmac.key", "block_samples": 20, "max_abs": 5,
 "operator_key_file": "$dir/operator.key", "state_dir": "$dir/state-h1"}
JSON
  cat > "$dir/catalog.json" <<JSON
{"db_path": "$dir/catalog.db", $keys, "state_dir": "$dir/state-h2"}
JSON
  cat > "$dir/worker.json" <<JSON
{$keys, "state_dir": "$dir/state-h3"}
JSON
  start h1 rig-sim "$bin/idrig-rig-sim" --config "$dir/rig.json"
  start h1 excite "$bin/idrig-excite" --config "$dir/excite.json"
  start h2 logger "$bin/idrig-logger" --db "$dir/experiments.db"
  start h2 catalog "$bin/idrig-catalog" --config "$dir/catalog.json"
  start h3 worker-1 "$bin/idrig-worker" --config "$dir/worker.json" --id h3-worker-1
  start h3 worker-2 "$bin/idrig-worker" --config "$dir/worker.json" --id h3-worker-2
  sleep 1.5
  local cli=(ip netns exec "$name-h2" env "IDRIG_KEY_FILE=$dir/operator.key" "$bin/idrig")
  exp=$("${cli[@]}" experiment start --url "$URL" --rig sim1 --signal "prbs:bits=9,amp=1" --fs 10 \
        --duration 51.1 --speed 20 --wait)
  echo "experiment $exp done"
  for method in arx-oe arx; do
    "${cli[@]}" models request --url "$URL" --rig sim1 --experiment "$exp" --method "$method" \
      --options '{"order":3}' --wait
  done
}

stop() {
  dir=$(readlink -f "${3:?work dir}")
  [ -f "$dir/pids" ] || return 0
  while read -r pid; do kill "$pid" 2>/dev/null || true; done < "$dir/pids"
  # They are not our children here: wait until they are gone (databases closed).
  for _ in $(seq 50); do
    alive=0
    while read -r pid; do kill -0 "$pid" 2>/dev/null && alive=1; done < "$dir/pids"
    [ "$alive" = 0 ] && break
    sleep 0.1
  done
}

case "$cmd" in
  up) up ;;
  down) down ;;
  run) run "$@" ;;
  stop) stop "$@" ;;
  *) echo "unknown command $cmd" >&2; exit 2 ;;
esac
