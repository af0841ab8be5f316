#!/usr/bin/env bash
# Builds the rvc image from deploy/docker/Dockerfile with the best builder this machine has:
#   - BuildKit (buildx, or a pre-23 docker client with DOCKER_BUILDKIT=1): cache mounts for apt,
#     the cargo registry and ccache persist between builds;
#   - otherwise the legacy builder, fed the same Dockerfile with the RUN --mount flags removed.
#
#   deploy/docker/build.sh [--tag IMAGE] [--network host] [--no-cache] [--jobs N] [--zenoh-lib FILE]
#
# Makes two images from the same layers: IMAGE (the runtime: FROM scratch, no shell) and
# IMAGE-debug (tag + "-debug", e.g. rvc:latest-debug: the same plus sh, sleep, cat, date, for
# scripts that run several commands in one container).
#
# --zenoh-lib FILE: use FILE (librvc_zenoh.a from a host build of the same checkout, e.g.
# build/release/cargo-target/release/librvc_zenoh.a) instead of compiling the Zenoh crate in the
# image; the host must be Debian bookworm like the image. The test tier does this (one compile of
# the crate per CI run instead of two); everything else in the image is built as usual.
#
# Environment: RVC_IMAGE (default rvc:latest), RVC_DOCKER (docker client to use),
# RVC_DOCKER_BUILDER=buildkit|legacy (force one). Prints one JSON line at the end:
#   {"image":"rvc:latest","builder":"buildkit","seconds":312.4,"size_bytes":35123456,
#    "debug_image":"rvc:latest-debug","debug_size_bytes":35456789}
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
IMAGE=${RVC_IMAGE:-rvc:latest}
debug_tag() { case "${1##*/}" in *:*) echo "$1-debug" ;; *) echo "$1:latest-debug" ;; esac; }
JOBS=2
ZENOH_LIB=""
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --tag|-t) IMAGE=$2; shift 2 ;;
    --network) extra+=(--network "$2"); shift 2 ;;
    --no-cache) extra+=(--no-cache); shift ;;
    --jobs) JOBS=$2; shift 2 ;;
    --zenoh-lib) ZENOH_LIB=$2; shift 2 ;;
    -h|--help) sed -n '2,22p' "$0"; exit 0 ;;
    *) echo "build.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done

"$ROOT/scripts/docker-setup.sh" --check || "$ROOT/scripts/docker-setup.sh"

client_major() { "$1" version --format '{{.Client.Version}}' 2>/dev/null | cut -d. -f1; }
pick_builder() {
  local c
  for c in ${RVC_DOCKER:-} docker /usr/bin/docker; do
    command -v "$c" >/dev/null 2>&1 || continue
    if [ "${RVC_DOCKER_BUILDER:-}" = legacy ]; then echo "legacy $c"; return; fi
    if "$c" buildx version >/dev/null 2>&1; then echo "buildkit $c"; return; fi
    local m; m=$(client_major "$c")
    # Clients before 23.0 have BuildKit built in (DOCKER_BUILDKIT=1), later ones need buildx.
    if [ -n "$m" ] && [ "$m" -lt 23 ]; then echo "buildkit $c"; return; fi
  done
  echo "legacy ${RVC_DOCKER:-docker}"
}
read -r builder client < <(pick_builder)
if [ "${RVC_DOCKER_BUILDER:-}" = buildkit ] && [ "$builder" != buildkit ]; then
  echo "build.sh: BuildKit requested but no client here supports it" >&2; exit 2
fi

cd "$ROOT"
prebuilt=$ROOT/rust/prebuilt
rm -rf "$prebuilt"
zenoh=source
if [ -n "$ZENOH_LIB" ]; then
  [ -f "$ZENOH_LIB" ] || { echo "build.sh: --zenoh-lib $ZENOH_LIB: no such file" >&2; exit 2; }
  mkdir -p "$prebuilt" && cp "$ZENOH_LIB" "$prebuilt/librvc_zenoh.a"
  trap 'rm -rf "$prebuilt"' EXIT
  zenoh=prebuilt
fi
start=$(date +%s.%N)
echo "build.sh: $builder builder ($client), image $IMAGE" >&2
DEBUG_IMAGE=$(debug_tag "$IMAGE")
for target in runtime debug; do
  tag=$IMAGE
  [ "$target" = debug ] && tag=$DEBUG_IMAGE
  if [ "$builder" = buildkit ]; then
    DOCKER_BUILDKIT=1 "$client" build --progress=plain -f deploy/docker/Dockerfile --target "$target" \
      --build-arg JOBS="$JOBS" -t "$tag" "${extra[@]}" .
  else
    sed -E '/^ *#/!s/--mount=[^ ]+ *//g; /^ *\\$/d' deploy/docker/Dockerfile |
      DOCKER_BUILDKIT=0 "$client" build -f - --target "$target" --build-arg JOBS="$JOBS" -t "$tag" "${extra[@]}" .
  fi
done
end=$(date +%s.%N)
size=$("$client" image inspect -f '{{.Size}}' "$IMAGE")
dsize=$("$client" image inspect -f '{{.Size}}' "$DEBUG_IMAGE")
printf '{"image":"%s","builder":"%s","zenoh":"%s","seconds":%.1f,"size_bytes":%s,"debug_image":"%s","debug_size_bytes":%s}\n' \
  "$IMAGE" "$builder" "$zenoh" "$(echo "$end - $start" | bc -l 2>/dev/null || python3 -c "print($end-$start)")" "$size" \
  "$DEBUG_IMAGE" "$dsize"
