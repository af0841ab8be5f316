#!/usr/bin/env bash
# Builds the rvc Python wheel (python/, docs/python.md) into build/python/dist:
# scikit-build-core + nanobind from PyPI (scripts/install-deps.sh), no build
# isolation (nothing fetched at build time). The CMake tree is kept in
# build/python/cmake and the objects go through the shared ccache
# (scripts/cache-env.sh), so a rebuild after a small change is quick.
# Prints the wheel's path on the last line.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/cache-env.sh
PY=${PYTHON:-python3}
out=build/python/dist
mkdir -p "$out"
rm -f "$out"/rvc-*.whl  # only wheels this script wrote
export CMAKE_BUILD_PARALLEL_LEVEL=${CMAKE_BUILD_PARALLEL_LEVEL:-2}
# MCAP bags (rvc.check_bag) need the Rust library, which carries Foxglove's MCAP reader beside Zenoh:
# built in when cargo is there, as the main build requires it anyway (the crate comes from the shared
# cargo target: no Zenoh recompile). RVC_WHEEL_MCAP=0: without it (.db3 bags and bag folders only).
mcap=${RVC_WHEEL_MCAP:-auto}
if [ "$mcap" = auto ]; then
  if command -v cargo >/dev/null 2>&1 || [ -x "${CARGO_HOME:-$HOME/.cargo}/bin/cargo" ]; then mcap=1; else mcap=0; fi
fi
args=(-C cmake.args=-GNinja)
if [ "$mcap" = 1 ]; then
  args+=(-C cmake.define.RVC_WITH_ZENOH=ON -C build-dir="$PWD/build/python/cmake-mcap")
else
  args+=(-C build-dir="$PWD/build/python/cmake")
fi
"$PY" -m pip wheel --no-build-isolation --no-deps -q -w "$out" "${args[@]}" python/ >&2
ls "$out"/rvc-*.whl
