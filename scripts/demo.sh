#!/usr/bin/env bash
# README command 1: install what is missing, build, and run the main job on
# the embedded default (no containers, loopback only): generate a Timescales
# trace and check its property, printing the verdicts.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
RVC=build/release/rvc
OUT=build/demo
mkdir -p "$OUT"

FAMILY=AlwaysBQR BOUND=100 STEPS=1000000
echo
echo "== rvc timescales $FAMILY --ubound $BOUND --duration $STEPS --seed 7"
"$RVC" timescales "$FAMILY" --ubound $BOUND --duration $STEPS --seed 7 -o "$OUT/trace.jsonl" \
  --properties-out "$OUT/properties.yaml"
head -n 3 "$OUT/trace.jsonl"
echo "...   ($(wc -l < "$OUT/trace.jsonl") messages)"
cat "$OUT/properties.yaml"

# A second property that the trace violates, so there is something to see.
cat >> "$OUT/properties.yaml" <<'YAML'
  - name: q_answered_quickly
    spec: "historically({r} -> once[:20]{q})"
YAML
echo
echo "== rvc check --properties $OUT/properties.yaml $OUT/trace.jsonl --summary   (verdict changes only)"
set +e
"$RVC" check --properties "$OUT/properties.yaml" "$OUT/trace.jsonl" --summary -o "$OUT/verdicts.jsonl"
status=$?
head -n 12 "$OUT/verdicts.jsonl"
echo "...   ($(wc -l < "$OUT/verdicts.jsonl") verdict changes in $OUT/verdicts.jsonl)"
set -e
echo
echo "exit status $status (0: all properties held, 1: a property was violated)"
[ "$status" -le 1 ]
