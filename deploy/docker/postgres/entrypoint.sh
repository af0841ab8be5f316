#!/bin/sh
# First start: makes the cluster in $PGDATA, the role $POSTGRES_USER with the password in
# $POSTGRES_PASSWORD_FILE and its database $POSTGRES_DB; logins from the network only with that
# password (SCRAM). Every start: runs the server in the foreground (SIGINT: fast shutdown).
set -eu
: "${PGDATA:=/var/lib/postgresql/data}"
: "${POSTGRES_PASSWORD_FILE:?POSTGRES_PASSWORD_FILE must name the file holding the password}"
db=${POSTGRES_DB:-rvc}
user=${POSTGRES_USER:-rvc}
if [ ! -s "$PGDATA/PG_VERSION" ]; then
  initdb -D "$PGDATA" -U postgres --auth-local=peer --auth-host=scram-sha-256 >/dev/null
  echo "listen_addresses = '*'" >>"$PGDATA/postgresql.conf"
  echo "host all all 0.0.0.0/0 scram-sha-256" >>"$PGDATA/pg_hba.conf"
  pg_ctl -D "$PGDATA" -o "-c listen_addresses=''" -w start >/dev/null
  psql -q -v ON_ERROR_STOP=1 -U postgres -d postgres --set pw="$(cat "$POSTGRES_PASSWORD_FILE")" \
    --set user="$user" --set db="$db" <<'SQL'
CREATE ROLE :"user" LOGIN PASSWORD :'pw';
CREATE DATABASE :"db" OWNER :"user";
SQL
  pg_ctl -D "$PGDATA" -m fast -w stop >/dev/null
  echo "rvc-postgres: made database $db for role $user"
fi
exec postgres -D "$PGDATA"
