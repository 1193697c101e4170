#!/usr/bin/env bash
# Runs the service benchmarks inside a private network namespace (root). Results: docs/services.md.
# Usage: tests/integration/services_bench.sh build/bin
set -euo pipefail
bin=$(readlink -f "${1:-build/bin}")
unshare -n sh -c 'ip link set lo up multicast on && ip route add 224.0.0.0/4 dev lo &&
  "$0/services_bench" logger-rate "$0" 2 &&
  "$0/services_bench" latency "$0" 100000 &&
  "$0/services_bench" jobs "$0" 1 40 &&
  "$0/services_bench" jobs "$0" 2 40 &&
  "$0/services_bench" jobs "$0" 1 40 heavy &&
  "$0/services_bench" jobs "$0" 2 40 heavy' "$bin"
