#!/usr/bin/env bash
# README command 1: install what is missing, build rvc, and run the main job on
# the embedded default — no containers, loopback only:
#   rvc timescales -> trace.jsonl
#   rvc replay trace.jsonl --to zenoh:rv/timescales   (publisher)
#   rvc monitor --input zenoh:rv/timescales --output zenoh:rv/verdicts --output file:verdicts.jsonl
# then the same trace through `rvc check`, to show the verdicts are identical.
# The monitor also keeps its results in SQLite (build/demo/results.db: runs,
# verdict changes, violations with their witness windows, counters);
# `scripts/demo.sh --dashboard` then serves them on http://127.0.0.1:8765.
set -euo pipefail
DASHBOARD=0
[ "${1:-}" = "--dashboard" ] && DASHBOARD=1
cd "$(dirname "$0")/.."
# Only what the demo needs (the test tiers' tools come with scripts/test.sh), and only the rvc
# binary: the unit tests, benchmarks and test helpers are built by scripts/test.sh.
bash scripts/install-deps.sh --demo
. scripts/cache-env.sh  # ~/.cache/rvc: cargo target keyed by Cargo.lock, ccache
cmake --preset release >/dev/null
cmake --build --preset release --target rvc
RVC=build/release/rvc
OUT=build/demo
mkdir -p "$OUT"

FAMILY=AlwaysBQR BOUND=100 STEPS=200000
echo
echo "== rvc timescales $FAMILY --ubound $BOUND --duration $STEPS --seed 7"
"$RVC" timescales "$FAMILY" --ubound $BOUND --duration $STEPS --seed 7 -o "$OUT/trace.jsonl" \
  --properties-out "$OUT/properties.yaml"
head -n 2 "$OUT/trace.jsonl"
# A second property that the trace violates, so there is something to see.
cat >> "$OUT/properties.yaml" <<'YAML'
  - name: q_answered_quickly
    spec: "historically({r} -> once[:20]{q})"
YAML
cat "$OUT/properties.yaml"

if "$RVC" router --help >/dev/null 2>&1; then
  PORT=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  ZENOH_MON=(--mode peer --listen "tcp/127.0.0.1:$PORT" --no-multicast-scouting)
  ZENOH_PUB=(--mode peer --connect "tcp/127.0.0.1:$PORT" --no-multicast-scouting)
  echo
  echo "== rvc monitor over Zenoh (peer-to-peer on tcp/127.0.0.1:$PORT, multicast scouting off)"
  "$RVC" monitor --properties "$OUT/properties.yaml" --input zenoh:rv/timescales \
    --output zenoh:rv/verdicts --output "file:$OUT/verdicts.jsonl" --output "sqlite:$OUT/results.db" \
    --exit-on-eos "${ZENOH_MON[@]}" \
    2> "$OUT/monitor.log" &
  MON=$!
  trap 'kill $MON 2>/dev/null || true' EXIT
  "$RVC" replay "$OUT/trace.jsonl" --to zenoh:rv/timescales --rate max "${ZENOH_PUB[@]}"
  set +e
  wait $MON
  status=$?
  set -e
  trap - EXIT
  echo "monitor counters: $(grep '^{' "$OUT/monitor.log" | tail -n 1)"
  grep "^rvc: results in" "$OUT/monitor.log" || true
else
  echo "(rvc was built without Zenoh: checking the file locally instead)"
  set +e
  "$RVC" check --properties "$OUT/properties.yaml" "$OUT/trace.jsonl" -o "$OUT/verdicts.jsonl" \
    -o "sqlite:$OUT/results.db"
  status=$?
  set -e
fi
echo
echo "== verdicts (changes only; $(wc -l < "$OUT/verdicts.jsonl") in $OUT/verdicts.jsonl)"
head -n 8 "$OUT/verdicts.jsonl"
set +e
"$RVC" check --properties "$OUT/properties.yaml" "$OUT/trace.jsonl" -o "$OUT/verdicts-local.jsonl"
set -e
if cmp -s "$OUT/verdicts.jsonl" "$OUT/verdicts-local.jsonl"; then
  echo "== identical to \`rvc check\` on the same file"
else
  echo "== DIFFERENT from \`rvc check\` on the same file" >&2
  exit 1
fi
echo "exit status $status (0: all properties held, 1: a property was violated, 4: messages lost)"
echo "== results in SQLite: $OUT/results.db (see them: $RVC dashboard --db sqlite:$OUT/results.db, or scripts/demo.sh --dashboard)"
[ "$status" -le 1 ] || exit 1
if [ "$DASHBOARD" = 1 ]; then
  echo "== rvc dashboard on http://127.0.0.1:8765 (Ctrl-C to stop)"
  exec "$RVC" dashboard --db "sqlite:$OUT/results.db" --listen 127.0.0.1:8765
fi
