#!/usr/bin/env bash
# A throwaway PostgreSQL 15 server for tests of the results store.
#
#   scripts/postgres-test.sh start DIR     initialise DIR (once) and start; prints the libpq URI
#   scripts/postgres-test.sh stop DIR      stop (fast: open sessions are cut)
#   scripts/postgres-test.sh restart DIR   stop, then start; prints the URI
#   scripts/postgres-test.sh status DIR    exit 0 if running
#
# The server listens on a unix socket in DIR only: listen_addresses is empty,
# so there is no TCP port at all (checked after every start). Authentication
# is "trust", which is safe only because of that. fsync is off: the data is
# thrown away, speed matters. As root the server runs as the `postgres` user
# (initdb and postgres refuse root), and DIR is given to that user.
#
# Layout: DIR/data (cluster), DIR/.s.PGSQL.5432 (socket), DIR/server.log.
# Environment: PG_BIN (default /usr/lib/postgresql/15/bin).
set -euo pipefail

PG_BIN=${PG_BIN:-/usr/lib/postgresql/15/bin}
DB_NAME=rvc
DB_USER=postgres

die() { echo "postgres-test.sh: $*" >&2; exit 1; }
say() { echo "postgres-test.sh: $*" >&2; }

usage() {
  echo "usage: $0 start|stop|restart|status DIR" >&2
  exit 2
}

[[ $# -eq 2 ]] || usage
cmd=$1
dir=$2
case $cmd in start | stop | restart | status) ;; *) usage ;; esac

for tool in initdb pg_ctl psql; do
  [[ -x $PG_BIN/$tool ]] || die "$PG_BIN/$tool not found: install postgresql-15 (apt-get install postgresql-15) or set PG_BIN"
done

if [[ $cmd == start || $cmd == restart ]]; then
  mkdir -p "$dir" || die "cannot create $dir"
elif [[ ! -d $dir ]]; then
  say "no directory $dir (no server there)"
  [[ $cmd == stop ]] && exit 0 || exit 3
fi
dir=$(cd "$dir" && pwd -P)
data=$dir/data
log=$dir/server.log
# The path goes into postgresql.conf and into a URI: keep it plain.
[[ $dir =~ ^[A-Za-z0-9/._+-]+$ ]] || die "$dir: use a directory path of letters, digits and / . _ + - only"
# A unix socket path holds at most 107 bytes.
(( ${#dir} + 16 <= 107 )) || die "$dir is too long for a unix socket path (at most 91 characters)"

# Run as the server's user: `postgres` when we are root, else ourselves.
if [[ $(id -u) -eq 0 ]]; then
  id postgres > /dev/null 2>&1 || die "running as root needs a 'postgres' user (it comes with the postgresql package)"
  command -v runuser > /dev/null || die "runuser not found (util-linux)"
  as_server() { runuser -u postgres -- "$@"; }
else
  as_server() { "$@"; }
fi

pg_ctl() { as_server "$PG_BIN/pg_ctl" -D "$data" "$@"; }
psql_admin() { "$PG_BIN/psql" -X -q -At -v ON_ERROR_STOP=1 -h "$dir" -U "$DB_USER" -d postgres "$@"; }
running() { [[ -f $data/PG_VERSION ]] && pg_ctl status > /dev/null 2>&1; }

init_cluster() {
  [[ -f $data/PG_VERSION ]] && return 0
  if [[ $(id -u) -eq 0 ]]; then
    chown postgres: "$dir" || die "cannot give $dir to the postgres user"
    as_server test -w "$dir" ||
      die "the postgres user cannot reach $dir: a parent directory is not searchable by it (use a directory under /tmp, not one inside a 0700 directory)"
  fi
  say "initialising $data"
  as_server "$PG_BIN/initdb" -D "$data" -U "$DB_USER" --auth=trust --encoding=UTF8 --locale=C.UTF-8 --no-sync \
    > "$dir/initdb.log" 2>&1 || { cat "$dir/initdb.log" >&2; die "initdb failed (log above)"; }
  # Later lines win in postgresql.conf, so these override the defaults.
  cat >> "$data/postgresql.conf" <<EOF

# postgres-test.sh: a throwaway server on a unix socket only
listen_addresses = ''
unix_socket_directories = '$dir'
port = 5432
fsync = off
synchronous_commit = off
full_page_writes = off
max_connections = 50
shared_buffers = 32MB
EOF
}

start() {
  init_cluster
  if running; then
    say "already running in $dir"
  else
    # listen_addresses on the command line too: it beats any config file
    # (postgresql.auto.conf included), so no TCP port can open.
    pg_ctl start -w -t 60 -l "$log" -o "-c listen_addresses=''" > /dev/null 2>&1 || {
      tail -n 20 "$log" >&2 2> /dev/null || true
      die "the server in $dir did not start (log: $log)"
    }
  fi
  local listen
  listen=$(psql_admin -c "SHOW listen_addresses") || die "cannot connect to the server in $dir (log: $log)"
  if [[ -n $listen ]]; then
    pg_ctl stop -m immediate > /dev/null 2>&1 || true
    die "the server in $dir listened on '$listen' (TCP); stopped it. Only a unix socket is allowed."
  fi
  if [[ -z $(psql_admin -c "SELECT 1 FROM pg_database WHERE datname = '$DB_NAME'") ]]; then
    psql_admin -c "CREATE DATABASE $DB_NAME" || die "cannot create database $DB_NAME in $dir"
  fi
  echo "postgresql:///$DB_NAME?host=$dir&user=$DB_USER"
}

stop() {
  if [[ ! -f $data/PG_VERSION ]]; then
    say "no server in $dir (nothing to stop)"
    return 0
  fi
  if ! running; then
    say "the server in $dir is not running"
    return 0
  fi
  pg_ctl stop -m fast -w -t 60 > /dev/null 2>&1 || die "cannot stop the server in $dir (log: $log)"
}

case $cmd in
  start) start ;;
  stop) stop ;;
  restart) stop; start ;;
  status) running ;;
esac
