#!/usr/bin/env bash
# Configures and builds rvc with the release preset (2 parallel jobs).
# Extra arguments go to the configure step, e.g. -DRVC_WITH_ZENOH=OFF.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/cache-env.sh  # ~/.cache/rvc: cargo target keyed by Cargo.lock, ccache
cmake --preset release "$@" >/dev/null
cmake --build --preset release
