#!/usr/bin/env bash
# Installs Docker Compose v2 as a docker CLI plugin, built from source fetched
# through the Go module proxy (Debian bookworm packages only Compose 1.29, and
# neither GitHub releases nor Docker Hub are reachable here):
#
#   scripts/compose-v2.sh              # v2.29.7 into /usr/local/lib/docker/cli-plugins
#   COMPOSE_V2_VERSION=v2.30.3 scripts/compose-v2.sh
#
# Needs Go >= 1.21 on PATH (Debian's golang-go 1.19 is too old). Takes several
# minutes on 2 cores. rvc's compose tooling (deploy/compose/rvc_compose.py)
# prefers `docker compose` when present; RVC_COMPOSE=v1 selects docker-compose.
set -euo pipefail
VERSION=${COMPOSE_V2_VERSION:-v2.29.7}
DEST=${COMPOSE_V2_PLUGIN_DIR:-/usr/local/lib/docker/cli-plugins}

if docker compose version 2>/dev/null | grep -q "${VERSION#v}"; then
  echo "compose-v2: docker compose ${VERSION} already installed"
  exit 0
fi
if ! command -v go >/dev/null; then
  echo "compose-v2: no Go toolchain on PATH (Go >= 1.21 needed)" >&2
  exit 1
fi
minor=$(go env GOVERSION | sed -E 's/^go1\.([0-9]+).*/\1/')
if [ "${minor:-0}" -lt 21 ]; then
  echo "compose-v2: $(go env GOVERSION) is too old (Go >= 1.21 needed)" >&2
  exit 1
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "compose-v2: building github.com/docker/compose/v2 ${VERSION} from the Go module proxy ..."
GOBIN="$work" GOFLAGS=-trimpath go install -p 2 \
  -ldflags "-s -w -X github.com/docker/compose/v2/internal.Version=${VERSION}" \
  "github.com/docker/compose/v2/cmd@${VERSION}"
mkdir -p "$DEST"
install -m 0755 "$work/cmd" "$DEST/docker-compose"
docker compose version
