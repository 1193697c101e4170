#!/usr/bin/env bash
# Configures and builds idrig into build/ (Release). Usage: deploy/build.sh [extra cmake args]
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build build -j"$(nproc)"
# The dashboard's front end (idrig serve finds it in build/web next to build/bin).
bash deploy/build-web.sh build/web
