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
"$PY" -m pip wheel --no-build-isolation --no-deps -q -w "$out" \
  -C build-dir="$PWD/build/python/cmake" -C cmake.args=-GNinja python/ >&2
ls "$out"/rvc-*.whl
