#!/usr/bin/env bash
# Fuzz tier (part of scripts/test.sh; docs/testing.md): builds the libFuzzer harnesses
# (preset fuzz: clang, ASan+UBSan) and runs each one for a while on a scratch copy of its seed
# corpus in tests/fuzz/corpus/<name> (the seeds in the repo stay as they are).
#
#   scripts/fuzz.sh                      every harness, 30 s each
#   scripts/fuzz.sh --seconds 3600       the long run (docs/testing.md has its figures)
#   scripts/fuzz.sh --only spec          one harness (fuzz_spec)
#   scripts/fuzz.sh --merge              afterwards, merge new coverage into the repo's corpus
#
# Any crash, leak, timeout or sanitizer finding fails the tier; the input that caused it is
# copied to build/fuzz/crashes/ and named in the output (rerun: build/fuzz/fuzz/fuzz_X FILE).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/cache-env.sh  # ~/.cache/rvc: cargo target keyed by Cargo.lock, ccache
ROOT=$PWD
seconds=30
only=""
merge=0
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds=$2; shift 2 ;;
    --only) only=$2; shift 2 ;;
    --merge) merge=1; shift ;;
    -h|--help) sed -n '2,14p' "$0"; exit 0 ;;
    *) echo "fuzz.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
done

harnesses=()
for src in tests/fuzz/fuzz_*.cpp; do
  name=$(basename "$src" .cpp); name=${name#fuzz_}
  if [ -z "$only" ] || [ "$only" = "$name" ]; then harnesses+=("$name"); fi
done
if [ ${#harnesses[@]} -eq 0 ]; then
  echo "fuzz.sh: no harness matches '${only}' (tests/fuzz/fuzz_*.cpp)" >&2
  exit 1
fi

# Only the harnesses (and the libraries they link): the rvc binary and the CLI are not fuzzed here,
# and leaving them out saves CI a few minutes of compiling.
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz --target "${harnesses[@]/#/fuzz_}"

crashes=$ROOT/build/fuzz/crashes
mkdir -p "$crashes"
failed=0
for name in "${harnesses[@]}"; do
  bin=$ROOT/build/fuzz/fuzz/fuzz_$name
  seeds=$ROOT/tests/fuzz/corpus/$name
  [ -x "$bin" ] || { echo "fuzz.sh: $bin was not built" >&2; failed=1; continue; }
  [ -d "$seeds" ] || { echo "fuzz.sh: no seed corpus $seeds" >&2; failed=1; continue; }
  work=$(mktemp -d)
  mkdir -p "$work/corpus" "$work/art"
  cp "$seeds"/* "$work/corpus/"
  echo "== fuzz_$name: ${seconds} s from $(ls "$seeds" | wc -l) seeds"
  rc=0
  # A harness's own libFuzzer flags, if it has some (fuzz_mcap: a malloc limit).
  read -r -a flags < <(cat "tests/fuzz/fuzz_$name.flags" 2>/dev/null || true) || true
  "$bin" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 -print_final_stats=1 "${flags[@]}" \
    -artifact_prefix="$work/art/" "$work/corpus" >"$work/log" 2>&1 || rc=$?
  grep -E '^stat::(number_of_executed_units|peak_rss_mb|new_units_added)' "$work/log" | tr '\n' ' ' || true
  echo
  arts=$(ls "$work/art" 2>/dev/null || true)
  if [ "$rc" -ne 0 ] || [ -n "$arts" ]; then
    failed=1
    echo "fuzz_$name FAILED (exit $rc); last lines of its log:" >&2
    grep -v -E '^#[0-9]+' "$work/log" | tail -n 40 >&2
    for a in $arts; do
      cp "$work/art/$a" "$crashes/$name-$a"
      echo "  input: $crashes/$name-$a (rerun: $bin $crashes/$name-$a)" >&2
    done
  elif [ "$merge" = 1 ]; then
    "$bin" -merge=1 "$seeds" "$work/corpus" >/dev/null 2>&1
    echo "   merged: $(ls "$seeds" | wc -l) inputs in $seeds"
  fi
  rm -rf "$work"
done
exit $failed
