"""Fixtures of the results-store tests: a throwaway PostgreSQL server
(scripts/postgres-test.sh: a unix socket in a temporary directory, no TCP) and
a way to read its tables without a Python driver (psql)."""
import json
import os
import shutil
import subprocess
import sys
import tempfile

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
sys.path.insert(0, os.path.join(ROOT, "tests"))
# fixtures (rvc) and hooks (skips fail under CI=true) shared by every pytest tier
from rvc_testlib import (BY_DESIGN, PLATFORM, in_ci, pytest_make_collect_report,  # noqa: E402,F401
                         pytest_runtest_makereport, rvc, rvc_binary)

SCRIPT = os.path.join(ROOT, "scripts", "postgres-test.sh")
PG_BIN = os.environ.get("PG_BIN", "/usr/lib/postgresql/15/bin")
TABLES = ("runs", "properties", "verdicts", "violations", "counters")


def missing(reason):
    """A missing dependency: a failure under CI, a skip (saying why) elsewhere."""
    if in_ci():
        pytest.fail(f"CI=true: {reason}", pytrace=False)
    pytest.skip(reason)


def psql_binary():
    for candidate in (os.path.join(PG_BIN, "psql"), shutil.which("psql")):
        if candidate and os.access(candidate, os.X_OK):
            return candidate
    return None


class PgServer:
    """The server of scripts/postgres-test.sh in `dir`; `uri` is its libpq URI."""

    def __init__(self, dir):
        self.dir = dir
        self.uri = None

    def _script(self, command):
        r = subprocess.run([SCRIPT, command, self.dir], capture_output=True, text=True, timeout=120)
        assert r.returncode == 0, f"postgres-test.sh {command} failed ({r.returncode}):\n{r.stderr}"
        return r.stdout.strip()

    def start(self):
        self.uri = self._script("start")
        return self.uri

    def stop(self):
        self._script("stop")

    def sql(self, query):
        """Rows of `query` as dicts (through json_agg, so numbers stay numbers)."""
        r = subprocess.run([psql_binary(), "-X", "-q", "-At", "-v", "ON_ERROR_STOP=1", "-d", self.uri, "-c",
                            f"SELECT coalesce(json_agg(q), '[]') FROM ({query}) q"],
                           capture_output=True, text=True, timeout=30)
        assert r.returncode == 0, f"psql failed: {r.stderr}"
        return json.loads(r.stdout)

    def drop_tables(self):
        subprocess.run([psql_binary(), "-X", "-q", "-v", "ON_ERROR_STOP=1", "-d", self.uri, "-c",
                        "DROP TABLE IF EXISTS " + ", ".join(TABLES)], check=True, capture_output=True, timeout=30)


@pytest.fixture(scope="session")
def rvc_pg(rvc):
    """The rvc binary, if it writes results to a database (else a skip, a failure under CI)."""
    help_text = subprocess.run([rvc, "check", "--help"], capture_output=True, text=True).stdout
    if "--db-wait" not in help_text:
        missing(f"{rvc} has no results store (`rvc check --help` lists no --db-wait)")
    return rvc


@pytest.fixture(scope="module")
def pg_server():
    for tool in ("initdb", "pg_ctl", "postgres"):
        if not os.access(os.path.join(PG_BIN, tool), os.X_OK):
            missing(f"PostgreSQL 15 server not installed ({PG_BIN}/{tool} missing; "
                    "apt-get install postgresql-15, or set PG_BIN)")
    if not psql_binary():
        missing("psql not found (apt-get install postgresql-client-15)")
    # Not pytest's tmp_path: as root the server runs as `postgres`, which
    # cannot enter pytest's 0700 directories; /tmp itself is open to all.
    dir = tempfile.mkdtemp(prefix="rvc-pg-", dir="/tmp")
    server = PgServer(dir)
    try:
        server.start()
        yield server
    finally:
        subprocess.run([SCRIPT, "stop", dir], capture_output=True, timeout=120)
        shutil.rmtree(dir, ignore_errors=True)


@pytest.fixture
def pg(pg_server):
    """The server, running, with no results tables (rvc creates them)."""
    pg_server.start()
    pg_server.drop_tables()
    return pg_server
