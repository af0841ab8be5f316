# Sourced by the build scripts (build.sh, sanitize.sh, fuzz.sh): caches that survive between runs
# on one machine, under ~/.cache/rvc, so a second CI run or a fresh clone does not recompile what
# did not change.
#   cargo-<hash of Cargo.lock>  the Rust crates (Zenoh, mcap): several minutes of compiling on 2
#                               cores; keyed by the lockfile so a dependency bump starts clean
#   ccache/                     C++ objects (only when ccache is installed); CCACHE_BASEDIR makes
#                               hits across clones at different paths
# Set RVC_NO_CACHE=1 to build without either (what a first run on a fresh machine does anyway).
# Expects to be sourced from the repository root.
if [ -z "${RVC_NO_CACHE:-}" ]; then
  RVC_CACHE=${RVC_CACHE:-$HOME/.cache/rvc}
  if [ -z "${RVC_CARGO_TARGET_DIR:-}" ] && [ -f rust/rvc-zenoh/Cargo.lock ]; then
    export RVC_CARGO_TARGET_DIR="$RVC_CACHE/cargo-$(sha256sum rust/rvc-zenoh/Cargo.lock | cut -c1-16)"
  fi
  if command -v ccache >/dev/null 2>&1; then
    export CCACHE_DIR=${CCACHE_DIR:-$RVC_CACHE/ccache}
    export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$PWD}
    export CCACHE_MAXSIZE=${CCACHE_MAXSIZE:-8G}
    export CCACHE_NOHASHDIR=1
    # CMake (>= 3.17) takes these as the default launcher of a new build tree.
    export CMAKE_C_COMPILER_LAUNCHER=${CMAKE_C_COMPILER_LAUNCHER:-ccache}
    export CMAKE_CXX_COMPILER_LAUNCHER=${CMAKE_CXX_COMPILER_LAUNCHER:-ccache}
  fi
fi
