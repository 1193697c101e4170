#!/usr/bin/env bash
# Builds the dashboard's front end (idrig serve) into build/web/: installs the npm packages
# pinned by tools/idrig/web/package-lock.json (`npm ci`: uPlot, and playwright-core for the
# browser test) and copies the pages with uPlot's ES module beside them. Nothing is bundled:
# the pages are plain ES modules. Usage: deploy/build-web.sh [OUT_DIR]   (default build/web)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-build/web}
src=tools/idrig/web
if ! command -v npm >/dev/null; then
  echo "build-web: npm is missing (bash deploy/bootstrap.sh installs Debian's nodejs and npm)" >&2
  exit 1
fi
lock_stamp="$src/node_modules/.idrig-lock-sha256"
want=$(sha256sum "$src/package-lock.json" | cut -d' ' -f1)
if [ ! -f "$lock_stamp" ] || [ "$(cat "$lock_stamp")" != "$want" ]; then
  (cd "$src" && npm ci --no-audit --no-fund --loglevel=error)
  echo "$want" > "$lock_stamp"
fi
mkdir -p "$out"
cp "$src"/index.html "$src"/app.js "$src"/plots.js "$src"/style.css "$out"/
cp "$src"/node_modules/uplot/dist/uPlot.esm.js "$src"/node_modules/uplot/dist/uPlot.min.css "$out"/
echo "build-web: front end in $out ($(ls "$out" | wc -l) files)"
