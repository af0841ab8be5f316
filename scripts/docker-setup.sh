#!/usr/bin/env bash
# Prepares Docker for rvc's containers (deploy/), idempotently:
#   1. installs Debian's docker.io and docker-compose if no docker / compose is present;
#   2. starts dockerd if none answers (log: /tmp/rvc-dockerd.log), waits for its socket;
#   3. creates the base image debian:bookworm-slim locally with debootstrap when it is missing
#      and cannot be pulled (no Docker Hub here), so Dockerfiles keep a plain
#      `FROM debian:bookworm-slim`. The root filesystem tarball is cached in $RVC_DOCKER_CACHE
#      (default /var/cache/rvc-docker), the mirror is read from this machine's apt sources.
#
#   scripts/docker-setup.sh           # all of the above; prints "docker-setup: ok"
#   scripts/docker-setup.sh --check   # exit 0 if Docker is usable and the base image exists, else 1
#
# A dockerd started here gets explicit address pools (docker0 = 172.28.255.1/24, other networks
# from 172.28.128.0/17), so nothing it creates overlaps the subnets deploy/compose uses
# (172.28.0.0/17) or the machine's own network. Exit 0 on success, 1 when Docker cannot run here.
set -euo pipefail

CACHE=${RVC_DOCKER_CACHE:-/var/cache/rvc-docker}
BASE_IMAGE=debian:bookworm-slim
SUITE=bookworm
LOG=/tmp/rvc-dockerd.log
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi

say() { echo "docker-setup: $*" >&2; }
die() { say "$*"; exit 1; }

docker_ok() { docker info >/dev/null 2>&1; }

# Certificate authorities this machine added locally (a TLS-inspecting proxy in front of the
# package registries needs them inside builds too). They go into the imported image, not into
# the cached tarball, so a changed set only means a quick re-import.
ca_dir=/usr/local/share/ca-certificates
local_cas() { find "$ca_dir" -type f -name '*.crt' 2>/dev/null | sort; }
ca_hash=$( (local_cas | xargs -r cat; echo) | sha256sum | cut -c1-16)
image_label() { docker image inspect -f "{{ index .Config.Labels \"$1\" }}" "$BASE_IMAGE" 2>/dev/null || true; }

if [ "${1:-}" = "--check" ]; then
  docker_ok && docker image inspect "$BASE_IMAGE" >/dev/null 2>&1 || exit 1
  [ "$(image_label rvc.local-base)" != "1" ] || [ "$(image_label rvc.local-ca)" = "$ca_hash" ] || exit 1
  exit 0
fi

# 1. packages -------------------------------------------------------------------------------
apt_install() {
  say "apt packages: $*"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "$@" >/dev/null
}
need=()
command -v dockerd >/dev/null 2>&1 || need+=(docker.io)
if ! command -v docker-compose >/dev/null 2>&1 && ! docker compose version >/dev/null 2>&1; then
  need+=(docker-compose)
fi
command -v ip >/dev/null 2>&1 || need+=(iproute2)
if [ "${#need[@]}" -gt 0 ]; then apt_install "${need[@]}"; fi

# 2. daemon ---------------------------------------------------------------------------------
if ! docker_ok; then
  if ! pgrep -x dockerd >/dev/null 2>&1; then
    # containerd is started by dockerd itself when no system containerd runs.
    say "starting dockerd (log: $LOG)"
    $SUDO setsid nohup dockerd \
      --bip 172.28.255.1/24 \
      --default-address-pool base=172.28.128.0/17,size=24 \
      >"$LOG" 2>&1 </dev/null &
  fi
  for _ in $(seq 1 120); do
    docker_ok && break
    sleep 0.5
  done
  docker_ok || { tail -n 20 "$LOG" >&2 2>/dev/null || true; die "dockerd did not come up (see $LOG)"; }
fi

# 3. base image -----------------------------------------------------------------------------
# The first apt source of this machine that serves $SUITE (one-line or deb822 format).
apt_mirror() {
  local f
  for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
    [ -f "$f" ] || continue
    awk -v s="$SUITE" '$1 == "deb" { i = 2; if ($i ~ /^\[/) { while ($i !~ /\]$/) i++; i++ }
                          if ($(i+1) == s) { print $i; exit } }' "$f"
  done
  for f in /etc/apt/sources.list.d/*.sources; do
    [ -f "$f" ] || continue
    awk -v s="$SUITE" 'BEGIN { RS = ""; FS = "\n" }
      { uri = ""; ok = 0
        for (i = 1; i <= NF; i++) {
          if ($i ~ /^URIs:/) { split($i, a, /[ \t]+/); uri = a[2] }
          if ($i ~ /^Suites:/) { n = split($i, b, /[ \t]+/); for (j = 2; j <= n; j++) if (b[j] == s) ok = 1 }
        }
        if (ok && uri != "") { print uri; exit } }' "$f"
  done
}

# Make the debootstrap tree look like the official slim image: no docs/man/locales (and dpkg
# excludes so later installs add none), apt tuned for image builds, this machine's apt sources
# and Acquire options (a snapshot mirror may need them), empty caches.
slimify() {
  local root=$1
  mkdir -p "$root/etc/dpkg/dpkg.cfg.d" "$root/etc/apt/apt.conf.d"
  cat >"$root/etc/dpkg/dpkg.cfg.d/docker" <<'EOF'
path-exclude /usr/share/doc/*
path-include /usr/share/doc/*/copyright
path-exclude /usr/share/man/*
path-exclude /usr/share/groff/*
path-exclude /usr/share/info/*
path-exclude /usr/share/lintian/*
path-exclude /usr/share/linda/*
path-exclude /usr/share/locale/*
EOF
  echo 'APT::AutoRemove::SuggestsImportant "false";' >"$root/etc/apt/apt.conf.d/docker-autoremove-suggests"
  cat >"$root/etc/apt/apt.conf.d/docker-clean" <<'EOF'
DPkg::Post-Invoke { "rm -f /var/cache/apt/archives/*.deb /var/cache/apt/archives/partial/*.deb /var/cache/apt/*.bin || true"; };
APT::Update::Post-Invoke { "rm -f /var/cache/apt/archives/*.deb /var/cache/apt/archives/partial/*.deb /var/cache/apt/*.bin || true"; };
Dir::Cache::pkgcache "";
Dir::Cache::srcpkgcache "";
EOF
  echo 'Acquire::GzipIndexes "true";' >"$root/etc/apt/apt.conf.d/docker-gzip-indexes"
  echo 'Acquire::Languages "none";' >"$root/etc/apt/apt.conf.d/docker-no-languages"
  echo 'force-unsafe-io' >"$root/etc/dpkg/dpkg.cfg.d/docker-apt-speedup"
  # apt sources and Acquire options of this machine
  rm -f "$root/etc/apt/sources.list"
  if [ -f /etc/apt/sources.list ] && grep -q '^deb ' /etc/apt/sources.list; then
    grep '^deb ' /etc/apt/sources.list >"$root/etc/apt/sources.list"
  fi
  local f
  for f in /etc/apt/sources.list.d/*.sources /etc/apt/sources.list.d/*.list; do
    [ -f "$f" ] && grep -qi 'debian' "$f" && cp "$f" "$root/etc/apt/sources.list.d/"
  done
  local acq='^Acquire::(Check-Valid-Until|Check-Date|https?::Proxy|Retries|ForceIPv4|https?::Timeout)'
  for f in /etc/apt/apt.conf /etc/apt/apt.conf.d/*; do
    [ -f "$f" ] || continue
    if grep -Eq "$acq" "$f"; then grep -E "$acq" "$f" >"$root/etc/apt/apt.conf.d/90host-$(basename "$f")"; fi
  done
  find "$root/usr/share/doc" -mindepth 1 -not -name copyright -not -type d -delete 2>/dev/null || true
  find "$root/usr/share/doc" -mindepth 1 -type d -empty -delete 2>/dev/null || true
  rm -rf "$root"/usr/share/{man,info,groff,lintian,linda,locale}/* \
         "$root"/var/cache/apt/*.bin "$root"/var/cache/apt/archives/*.deb \
         "$root"/var/lib/apt/lists/* "$root"/var/log/* "$root"/tmp/* "$root"/var/cache/debconf/*-old
  : >"$root/etc/machine-id" 2>/dev/null || true
  echo "rvc-local-$SUITE" >"$root/etc/hostname"
}

need_import=0
if ! docker image inspect "$BASE_IMAGE" >/dev/null 2>&1; then
  need_import=1
elif [ "$(image_label rvc.local-base)" = "1" ] && [ "$(image_label rvc.local-ca)" != "$ca_hash" ]; then
  say "this machine's local CA certificates changed: re-importing $BASE_IMAGE"
  need_import=1
fi

if [ "$need_import" = 1 ]; then
  tarball="$CACHE/debian-$SUITE-slim.tar"
  if [ ! -s "$tarball" ] && [ "${RVC_DOCKER_PULL:-0}" = 1 ] && docker pull -q "$BASE_IMAGE" >/dev/null 2>&1; then
    say "pulled $BASE_IMAGE"
  else
    if [ ! -s "$tarball" ]; then
      command -v debootstrap >/dev/null 2>&1 || apt_install debootstrap
      mirror=$(apt_mirror | head -n 1)
      [ -n "$mirror" ] || die "no apt source for $SUITE found in /etc/apt (needed for debootstrap)"
      $SUDO mkdir -p "$CACHE"
      root=$(mktemp -d "$CACHE/rootfs.XXXXXX")
      trap '$SUDO rm -rf "$root"' EXIT
      say "debootstrap --variant=minbase $SUITE from $mirror (a minute or two)"
      $SUDO debootstrap --variant=minbase "$SUITE" "$root" "$mirror" >"$CACHE/debootstrap.log" 2>&1 ||
        { tail -n 20 "$CACHE/debootstrap.log" >&2; die "debootstrap failed (log: $CACHE/debootstrap.log)"; }
      slimify "$root"
      $SUDO tar --numeric-owner -C "$root" -cf "$tarball.tmp" .
      $SUDO mv "$tarball.tmp" "$tarball"
      $SUDO rm -rf "$root"
      trap - EXIT
    fi
    work=$(mktemp -d)
    trap 'rm -rf "$work"' EXIT
    cp "$tarball" "$work/rootfs.tar"
    if [ -n "$(local_cas)" ]; then
      mkdir -p "$work/ca/.$ca_dir"
      local_cas | xargs -r -I{} cp {} "$work/ca/.$ca_dir/"
      tar --numeric-owner --owner=0 --group=0 -C "$work/ca" -rf "$work/rootfs.tar" ".$ca_dir"
    fi
    say "docker import $tarball as $BASE_IMAGE"
    docker import \
      --change 'ENV PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin' \
      --change 'CMD ["bash"]' \
      --change 'LABEL rvc.local-base=1' \
      --change "LABEL rvc.local-ca=$ca_hash" \
      -m "debootstrap --variant=minbase $SUITE (rvc scripts/docker-setup.sh)" \
      "$work/rootfs.tar" "$BASE_IMAGE" >/dev/null
    rm -rf "$work"
    trap - EXIT
  fi
fi
say "ok ($(docker version --format 'server {{.Server.Version}}' 2>/dev/null), $BASE_IMAGE $(docker image inspect -f '{{.Size}}' "$BASE_IMAGE" | awk '{printf "%.0f MB", $1/1e6}'))"
