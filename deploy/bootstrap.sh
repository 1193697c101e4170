#!/usr/bin/env bash
# Installs every Debian package idrig needs to build, test and run. Idempotent and
# non-interactive; run as root on Debian 12. Later features add their packages to PACKAGES.
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake pkg-config git
  # messaging (LCM 1.3.1; lcm.pc needs glib, lcm-spy needs jchart2d and a JDK for our types jar)
  liblcm-dev liblcm-bin liblcm-java libglib2.0-dev default-jdk-headless libjchart2d-java
  # numerics, storage, CLI, logging, tests
  libeigen3-dev libsqlite3-dev sqlite3 libspdlog-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev libssl-dev
  # network namespaces for the multicast tests
  iproute2 util-linux
  # JSON checks in the command-line tests
  jq
  # the dashboard (idrig serve): HTTP server; MATLAB .mat files; the browser test's Chromium
  libcpp-httplib-dev libmatio-dev chromium chromium-driver curl
)
# The dashboard's front end is built with npm (deploy/build-web.sh): Debian's nodejs and npm
# unless a node with npm is already installed.
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  PACKAGES+=(nodejs npm)
fi

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  if [ "$(id -u)" -ne 0 ]; then
    echo "bootstrap: missing packages ${missing[*]}; run this script as root" >&2
    exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -q
  apt-get install -y -q --no-install-recommends "${missing[@]}"
fi
echo "bootstrap: all ${#PACKAGES[@]} packages present"
