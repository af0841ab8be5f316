#!/bin/sh
# make-rootfs.sh ROOT FILE...
# Copies into ROOT (the runtime image's root filesystem, later COPY'd into a FROM scratch stage)
# every shared library FILE needs, as ldd lists it, and FILE itself when it is not already inside
# ROOT. FILE is a path, or a library's soname (no slash): rvc loads CycloneDDS and libpq with
# dlopen only when a feature needs them, so ldd of the binary does not list them
# (cmake/RuntimeLibraries.cmake writes their sonames to runtime-libraries.txt); they are found with
# `ldconfig -p` and copied with what they need in turn.
# Files land in their canonical directory (/lib is a link to usr/lib on Debian bookworm, merged
# /usr; ROOT gets the same links), under the name ldd gives (the soname), links dereferenced.
# Each copied file's Debian package is appended to ROOT/usr/share/rvc/packages.txt (for the
# copyright notices). Fails if a library cannot be found.
set -eu
root=$1
shift

copy() {  # copy SRC DEST-PATH-INSIDE-ROOT
  [ -e "$root$2" ] && return 0
  mkdir -p "$root$(dirname "$2")"
  cp -L "$1" "$root$2"
  pkg=""
  # dpkg knows a file by the path its package ships (/lib/... or /usr/lib/... under merged /usr)
  for p in "$1" "$(readlink -f "$1")" "/$(readlink -f "$1" | cut -d/ -f3-)"; do
    pkg=$(dpkg -S "$p" 2>/dev/null | head -n 1 | cut -d: -f1) && [ -n "$pkg" ] && break
  done
  echo "${pkg:-?} $2" >>"$root/usr/share/rvc/files.txt"
}

canonical() {  # the path with its directory resolved (/lib/x86_64-linux-gnu -> /usr/lib/x86_64-linux-gnu)
  echo "$(readlink -f "$(dirname "$1")")/$(basename "$1")"
}

deps() {  # the absolute paths of every library FILE needs (ldd: "name => /path (addr)" or "/path (addr)")
  out=$(ldd "$1") || { echo "make-rootfs: ldd $1 failed" >&2; exit 1; }
  if echo "$out" | grep -q 'not found'; then
    echo "make-rootfs: $1 needs a library this system lacks:" >&2; echo "$out" | grep 'not found' >&2; exit 1
  fi
  echo "$out" | awk '$2 == "=>" && $3 ~ /^\// {print $3} $1 ~ /^\// {print $1}'
}

mkdir -p "$root/usr/lib" "$root/usr/lib64" "$root/usr/share/rvc"
[ -e "$root/lib" ] || ln -s usr/lib "$root/lib"
[ -e "$root/lib64" ] || ln -s usr/lib64 "$root/lib64"
for f in "$@"; do
  case "$f" in
    */*) src=$f ;;
    *) src=$(ldconfig -p | awk -v so="$f" '$1 == so {print $NF; exit}')
       [ -n "$src" ] || { echo "make-rootfs: library $f not installed" >&2; exit 1; } ;;
  esac
  case "$src" in
    "$root"/*) ;;
    *) copy "$src" "$(canonical "$src")" ;;
  esac
  for lib in $(deps "$src"); do copy "$lib" "$(canonical "$lib")"; done
done
sort -u -o "$root/usr/share/rvc/files.txt" "$root/usr/share/rvc/files.txt"
