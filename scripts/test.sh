#!/usr/bin/env bash
# README command 2: install what is missing, build, and run every test tier:
# unit (GoogleTest), differential vs Reelay (pytest), and the integration
# tiers (multi-process over loopback). `.ci/run` calls exactly this.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
ctest --preset release --timeout 900 "$@"
