#!/usr/bin/env bash
# Builds tools/ros2dds-bridge (rvc-ros2dds-bridge: a Zenoh router with the crates.io
# zenoh-plugin-ros2dds 1.10.2 linked in, the stand-in for Eclipse's zenoh-bridge-ros2dds, which is
# not on crates.io) and prints the binary's path on stdout. Used by the bridge test tier
# (tests/integration/bridge); docs/zenoh.md, "The real zenoh-bridge-ros2dds".
#
# Heavy the first time (full Zenoh with its default transports + CycloneDDS's C sources through
# cmake and bindgen: see docs/zenoh.md for the measured time), so the cargo target lives under
# ~/.cache/rvc keyed by the tool's own Cargo.lock, beside rvc's (scripts/cache-env.sh): a second run
# on the same machine is a no-op check. RVC_NO_CACHE=1 builds in tools/ros2dds-bridge/target.
#   scripts/build-ros2dds-bridge.sh          build (if needed), print the path
#   scripts/build-ros2dds-bridge.sh --path   only print where the binary is (or would be)
set -euo pipefail
cd "$(dirname "$0")/.."
dir=tools/ros2dds-bridge
if [ -z "${RVC_NO_CACHE:-}" ]; then
  cache=${RVC_CACHE:-$HOME/.cache/rvc}
  export CARGO_TARGET_DIR="$cache/cargo-ros2dds-bridge-$(sha256sum "$dir/Cargo.lock" | cut -c1-16)"
else
  export CARGO_TARGET_DIR="$PWD/$dir/target"
fi
if [ "${1:-}" = "--path" ]; then
  echo "$CARGO_TARGET_DIR/release/rvc-ros2dds-bridge"
  exit 0
elif [ -n "${1:-}" ]; then
  echo "build-ros2dds-bridge: unknown option '$1' (--path: print the binary's path only)" >&2
  exit 2
fi
# 2 jobs: the machine is shared (CI runs this once per lockfile).
cargo build --release --locked -j "${RVC_BRIDGE_JOBS:-2}" --manifest-path "$dir/Cargo.toml" >&2
echo "$CARGO_TARGET_DIR/release/rvc-ros2dds-bridge"
