#!/usr/bin/env bash
# README command 2: install what is missing, build, and run every test tier. `.ci/run` calls
# exactly this. Tiers (docs/testing.md):
#   ctest   release build: unit (GoogleTest), differential vs Reelay, CLI, multi-process DDS/Zenoh,
#           perf sanity, containers
#   asan    ASan+UBSan over unit, CLI and networked DDS runs      (scripts/sanitize.sh asan)
#   tsan    ThreadSanitizer over the threaded monitor             (scripts/sanitize.sh tsan)
#   fuzz    every libFuzzer harness, RVC_FUZZ_SECONDS (30) each     (scripts/fuzz.sh)
# Every tier runs even when an earlier one failed; the table at the end gives each one's result
# and wall time, and the exit status is non-zero if any failed.
#   scripts/test.sh                   everything
#   RVC_TIERS="ctest fuzz" scripts/test.sh    some tiers
#   scripts/test.sh -L unit           extra arguments go to ctest (here: only the unit label)
set -uo pipefail
cd "$(dirname "$0")/.."

tiers=(${RVC_TIERS:-ctest asan tsan fuzz})
declare -A result seconds

bash scripts/install-deps.sh || { echo "test.sh: installing dependencies failed" >&2; exit 1; }

run_tier() {
  local name=$1; shift
  echo
  echo "######## tier $name: $*"
  local t0=$SECONDS
  if "$@"; then result[$name]=passed; else result[$name]=FAILED; fi
  seconds[$name]=$((SECONDS - t0))
  echo "######## tier $name: ${result[$name]} in ${seconds[$name]} s"
}

ctest_tier() {
  bash scripts/build.sh && ctest --preset release --timeout 900 "$@"
}

for t in "${tiers[@]}"; do
  case "$t" in
    ctest) run_tier ctest ctest_tier "$@" ;;
    asan) run_tier asan bash scripts/sanitize.sh asan ;;
    tsan) run_tier tsan bash scripts/sanitize.sh tsan ;;
    fuzz) run_tier fuzz bash scripts/fuzz.sh --seconds "${RVC_FUZZ_SECONDS:-30}" ;;
    *) echo "test.sh: unknown tier '$t' (ctest asan tsan fuzz)" >&2; exit 2 ;;
  esac
done

passed=0; failed=0
echo
echo "| tier | result | wall time |"
echo "|------|--------|-----------|"
for t in "${tiers[@]}"; do
  printf '| %s | %s | %d min %02d s |\n' "$t" "${result[$t]}" $((seconds[$t] / 60)) $((seconds[$t] % 60))
  if [ "${result[$t]}" = passed ]; then passed=$((passed + 1)); else failed=$((failed + 1)); fi
done
echo "tiers: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
