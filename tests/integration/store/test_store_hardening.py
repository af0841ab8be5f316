"""The results store under stress: stop signals, a database that is away or full, refused rows,
malformed URIs, files that are not rvc's (spools, databases). Every expectation is written down
here by hand or read back from the files with Python's own sqlite3; SQLite only (no server).

A full disk without root: rvc runs with RLIMIT_FSIZE (and SIGXFSZ ignored, inherited across
exec), so every write past the limit fails with EFBIG, as on a full file system.
"""
from __future__ import annotations

import hashlib
import json
import os
import queue
import re
import resource
import signal
import sqlite3
import subprocess
import sys
import threading

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
from rvc_testlib import rvc_binary  # noqa: E402

SPOOL_HEADER = '{"rvc_spool":1}'


def sha256(path) -> str:
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


def line(i: int) -> str:
    """Line i of the traces here: `a` alternates, so {a} changes its verdict on every line and
    is violated on every odd one (hand-computed: n lines -> n verdict rows, n // 2 violations)."""
    return json.dumps({"a": i % 2 == 0, "n": i})


def rows(db, sql):
    with sqlite3.connect(db) as c:
        return c.execute(sql).fetchall()


class LiveCheck:
    """`rvc check - -o sqlite:DB` reading a pipe we write; verdict lines read back as they come."""

    def __init__(self, db, *extra):
        self.proc = subprocess.Popen([rvc_binary(), "check", "-s", "{a}", "-o", f"sqlite:{db}", *extra, "-"],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.verdicts: queue.Queue = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for text in self.proc.stdout:
            self.verdicts.put(text)
        self.verdicts.put(None)

    def feed(self, first, count):
        """Writes lines first..first+count-1 and waits until rvc has given their verdicts."""
        self.proc.stdin.write("".join(line(i) + "\n" for i in range(first, first + count)))
        self.proc.stdin.flush()
        for _ in range(count):
            v = self.verdicts.get(timeout=60)
            assert v is not None, self.proc.stderr.read()

    def stop(self, *signals):
        for s in signals:
            self.proc.send_signal(s)
        # Liveness only: a run that waited for its --db-wait (600 s) would not end within this.
        status = self.proc.wait(timeout=120)
        return status, self.proc.stderr.read()


# --- 1. a stop signal ends `rvc check` like `rvc monitor`: everything read is stored, the run closed

@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_check_on_a_pipe_stopped_by_a_signal_keeps_every_row(tmp_path, sig):
    db = tmp_path / "results.db"
    run = LiveCheck(db)
    run.feed(0, 40)  # the pipe stays open: only the signal ends the run
    status, err = run.stop(sig)
    assert status == 1, err  # violated: it outranks the incomplete stream (6)
    assert "stopped by a signal after 40 messages" in err
    (ended, exit_status, reason, counters), = rows(db, "SELECT ended_at, exit_status, end_reason, counters FROM runs")
    assert ended is not None and exit_status == 1 and reason == "signal"
    assert json.loads(counters)["checked"] == 40
    assert rows(db, "SELECT time, value FROM verdicts ORDER BY id") == [(i, int(i % 2 == 0)) for i in range(40)]
    assert rows(db, "SELECT time FROM violations ORDER BY id") == [(i,) for i in range(1, 40, 2)]


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_check_stopped_by_a_signal_is_incomplete(tmp_path, sig):
    db = tmp_path / "results.db"
    run = LiveCheck(db)
    run.proc.stdin.write('{"a":true}\n{"a":true}\n')
    run.proc.stdin.flush()
    assert run.verdicts.get(timeout=60) is not None  # {a}'s first verdict: the lines were read
    status, err = run.stop(sig)
    assert status == 6, err  # nothing violated, the trace cut: incomplete, as `rvc monitor` on a signal
    assert rows(db, "SELECT exit_status, end_reason FROM runs WHERE ended_at IS NOT NULL") == [(6, "signal")]
    assert rows(db, "SELECT time, value FROM verdicts") == [(0, 1)]


# --- 2. a stop signal while the database is away: spooled at once, not after --db-wait

def test_signal_while_the_database_is_away_spools_at_once(tmp_path):
    db = tmp_path / "results.db"
    run = LiveCheck(db, "--db-wait", "600")
    run.feed(0, 10)
    # Another process holds the write lock: rvc's writes fail (busy) and its rows wait.
    holder = sqlite3.connect(db, timeout=30, isolation_level=None)
    holder.execute("BEGIN EXCLUSIVE")
    try:
        run.feed(10, 30)
        status, err = run.stop(signal.SIGTERM)
        assert status == 1, err  # violated outranks the runtime failure (results not all in the database)
        spool = f"{db}.spool"
        m = re.search(r"(\d+) rows kept in (\S+) ", err)
        assert m and m.group(2) == spool, err
        lines = open(spool).read().splitlines()
        # The claim is the file's content: header, then exactly that many rows.
        assert lines[0] == SPOOL_HEADER and len(lines) - 1 == int(m.group(1))
    finally:
        holder.execute("ROLLBACK")
        holder.close()
    # The next run writes the spool first: all 40 verdicts of the stopped run arrive, once.
    empty = tmp_path / "empty.jsonl"
    empty.write_text(line(0) + "\n")
    r = subprocess.run([rvc_binary(), "check", "-s", "{a}", "-o", f"sqlite:{db}", str(empty)],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert not os.path.exists(f"{db}.spool")
    first = rows(db, "SELECT run FROM runs ORDER BY run")[0][0]
    assert rows(db, f"SELECT time, value FROM verdicts WHERE run = '{first}' ORDER BY id") == \
        [(i, int(i % 2 == 0)) for i in range(40)]
    assert rows(db, f"SELECT exit_status, end_reason FROM runs WHERE run = '{first}'") == [(1, "signal")]


# --- 3. a full disk: what is said about the rows is true

def full_disk(limit):
    def preexec():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails (EFBIG), no signal
    return preexec


def test_full_disk_with_no_room_for_the_spool_says_the_rows_are_lost(tmp_path):
    db = tmp_path / "full.db"
    trace = tmp_path / "t.jsonl"
    trace.write_text(line(0) + "\n")
    assert subprocess.run([rvc_binary(), "check", "-s", "{a}", "-o", f"sqlite:{db}", str(trace)],
                          capture_output=True, timeout=60).returncode == 0
    trace.write_text("".join(line(i) + "\n" for i in range(20000)))  # 30 000 rows, megabytes with witnesses
    r = subprocess.run([rvc_binary(), "check", "-s", "{a}", "-o", f"sqlite:{db}", "--db-wait", "3", str(trace)],
                       capture_output=True, text=True, timeout=120, preexec_fn=full_disk(256 * 1024))
    assert r.returncode == 1, r.stderr  # violated wins; the loss is reported below
    assert "rows kept in" not in r.stderr, r.stderr  # no claim of safety for rows that are not safe
    m = re.search(r"the spool \S+ cannot be written \([^)]+\): (\d+) rows of results are lost", r.stderr)
    assert m and int(m.group(1)) > 0, r.stderr
    spool = f"{db}.spool"
    assert not os.path.exists(spool) or open(spool).read().count("\n") == 0
    # The database went away once and never came back: one message, no flip-flop.
    assert r.stderr.count("keeping results and retrying") == 1, r.stderr
    assert "is back" not in r.stderr, r.stderr


def test_full_disk_loss_is_status_5(tmp_path):
    db = tmp_path / "full.db"
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"a":true}\n')
    assert subprocess.run([rvc_binary(), "check", "-s", "{a}", "-o", f"sqlite:{db}", str(trace)],
                          capture_output=True, timeout=60).returncode == 0
    # 300 properties that hold: 300 property rows and 300 verdict rows, about 60 kB as spool lines and
    # more in the database's pages: neither fits under 40 KiB. Nothing is violated, so the loss decides.
    specs = [arg for _ in range(300) for arg in ("-s", "{a}")]
    r = subprocess.run([rvc_binary(), "check", *specs, "-o", f"sqlite:{db}", "--db-wait", "0", str(trace)],
                       capture_output=True, text=True, timeout=120, preexec_fn=full_disk(40 * 1024))
    assert r.returncode == 5, r.stderr
    assert "rows kept in" not in r.stderr and re.search(r"\d+ rows of results are lost", r.stderr), r.stderr


# --- 4. rows the database refuses are not a success; a malformed URI is a usage error

def test_refused_rows_give_status_5_with_count_and_reason(tmp_path):
    db = tmp_path / "results.db"
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"a":true}\n{"a":true}\n')
    assert subprocess.run([rvc_binary(), "check", "-s", "{a}", "-o", f"sqlite:{db}", str(trace)],
                          capture_output=True, timeout=60).returncode == 0
    with sqlite3.connect(db) as c:
        c.execute("CREATE TRIGGER no_p2 BEFORE INSERT ON verdicts WHEN NEW.property = 'p2' "
                  "BEGIN SELECT RAISE(ABORT, 'p2 is not welcome'); END")
    r = subprocess.run([rvc_binary(), "check", "-s", "{a}", "-s", "{a}", "-o", f"sqlite:{db}", str(trace)],
                       capture_output=True, text=True, timeout=60)
    # Both hold; p2's one verdict change (its first verdict) is refused: 1 row, with the reason.
    assert r.returncode == 5, r.stderr
    assert re.search(r"refused 1 row: not stored \(the first: a verdict row: .*p2 is not welcome",
                     r.stderr), r.stderr


@pytest.mark.parametrize("uri, says", [
    ("postgresql://[::1", "IPv6"),
    ("postgresql://127.0.0.1:99999/rvc", "port '99999'"),
    ("postgresql://127.0.0.1/rvc?sslmode=bogus", "sslmode=bogus"),
    ("postgresql://127.0.0.1/rvc?connect_timeout=soon", "connect_timeout=soon"),
])
def test_malformed_postgresql_uris_are_usage_errors(tmp_path, uri, says):
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"a":true}\n')
    r = subprocess.run([rvc_binary(), "check", "-s", "{a}", "-o", uri, "--db-wait", "0",
                        "--spool", str(tmp_path / "s.spool"), str(trace)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "bad PostgreSQL URI" in r.stderr and says in r.stderr, r.stderr
    assert not os.path.exists(tmp_path / "s.spool")
    d = subprocess.run([rvc_binary(), "dashboard", "--db", uri, "--listen", "127.0.0.1:0"],
                       capture_output=True, text=True, timeout=60)
    assert d.returncode == 2 and says in d.stderr, d.stderr


# --- 5. a spool must be rvc's: never read, cut or delete another file

def test_spool_that_is_the_input_or_not_a_spool_is_refused_unchanged(tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(line(i) + "\n" for i in range(5)))
    notes = tmp_path / "notes.txt"
    notes.write_text("my notes\n")
    empty = tmp_path / "empty"
    empty.write_text("")
    for spool in (trace, notes, empty):
        before = sha256(spool)
        r = subprocess.run([rvc_binary(), "check", "-s", "{a}", "-o", f"sqlite:{tmp_path}/r.db", "--spool",
                            str(spool), str(trace)], capture_output=True, text=True, timeout=60)
        assert r.returncode == 2 and f"results spool '{spool}' cannot be used" in r.stderr, r.stderr
        assert spool.exists() and sha256(spool) == before
    # An rvc spool named as the input too: it would be drained, then deleted.
    spool = tmp_path / "kept.spool"
    spool.write_text(SPOOL_HEADER + "\n")
    r = subprocess.run([rvc_binary(), "check", "-s", "{a}", "-o", f"sqlite:{tmp_path}/r.db", "--spool", str(spool),
                        str(spool)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "is the input" in r.stderr, r.stderr
    assert spool.read_text() == SPOOL_HEADER + "\n"


def test_spool_of_an_earlier_rvc_without_header_is_still_written(tmp_path):
    """Spools written before the header (rows from the first line on) are rvc's and are drained."""
    db = tmp_path / "r.db"
    spool = tmp_path / "old.spool"
    row = {"table": "run", "run": "r-old", "text": ["rvc check", "[]", "discrete"], "number": [1.0, 0],
           "integer": 0}
    spool.write_text(json.dumps(row) + "\n")
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"a":true}\n')
    r = subprocess.run([rvc_binary(), "check", "-s", "{a}", "-o", f"sqlite:{db}", "--spool", str(spool), str(trace)],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert ("r-old",) in rows(db, "SELECT run FROM runs") and not spool.exists()


# --- 7. a database that is not rvc's is refused as it is, by check and by the dashboard

def other_application_db(path):
    with sqlite3.connect(path) as c:
        c.execute("CREATE TABLE people (name TEXT)")
        c.execute("INSERT INTO people VALUES ('ada')")
    return path


def test_a_database_that_is_not_rvcs_is_never_changed(tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"a":true}\n')
    other = other_application_db(tmp_path / "app.db")
    empty = tmp_path / "empty.db"
    empty.write_bytes(b"")
    text = tmp_path / "text.db"
    text.write_text("not a database\n")
    for path, says in [(other, "tables: people"), (empty, "empty file"), (text, "not a results database")]:
        before = sha256(path)
        r = subprocess.run([rvc_binary(), "check", "-s", "{a}", "-o", f"sqlite:{path}", str(trace)],
                           capture_output=True, text=True, timeout=60)
        assert r.returncode == 2 and says in r.stderr, (path, r.stderr)
        d = subprocess.run([rvc_binary(), "dashboard", "--db", f"sqlite:{path}", "--listen", "127.0.0.1:0"],
                           capture_output=True, text=True, timeout=60)
        assert d.returncode == 2 and says in d.stderr, (path, d.stderr)
        assert sha256(path) == before, path
        assert not os.path.exists(f"{path}.spool") and not os.path.exists(f"{path}-wal")
    with sqlite3.connect(other) as c:
        assert c.execute("PRAGMA journal_mode").fetchone() == ("delete",)


@pytest.mark.parametrize("journal", ["delete", "wal"])
def test_a_database_whose_tables_share_rvcs_names_is_never_changed(tmp_path, journal):
    """Issue 36: another application's file with tables named runs, properties, verdicts, violations and
    counters (its own columns) was switched to WAL, stamped with rvc's application_id and left with -wal/-shm
    files, and only then refused. Whose file it is is now decided before the first write."""
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"a":true}\n')
    app = tmp_path / "app.db"
    c = sqlite3.connect(app)
    c.execute(f"PRAGMA journal_mode={journal}")
    for table in ("runs", "properties", "verdicts", "violations", "counters"):
        c.execute(f"CREATE TABLE {table} (run TEXT, note TEXT)")
    c.execute("INSERT INTO runs VALUES ('mine', 'keep me')")
    c.commit()
    c.close()
    assert sorted(os.listdir(tmp_path)) == ["app.db", "t.jsonl"]
    before = sha256(app)
    for args in (["check", "-s", "{a}", "-o", f"sqlite:{app}", str(trace)],
                 ["monitor", "-s", "{a}", "-o", f"sqlite:{app}", "--input", f"file:{trace}"],
                 ["dashboard", "--db", f"sqlite:{app}", "--listen", "127.0.0.1:0"]):
        r = subprocess.run([rvc_binary(), *args], capture_output=True, text=True, timeout=60)
        assert r.returncode == 2, (args, r.stderr)
        assert "is not an rvc results database" in r.stderr and "refusing" in r.stderr, (args, r.stderr)
        assert sha256(app) == before, args  # byte-identical
        assert sorted(os.listdir(tmp_path)) == ["app.db", "t.jsonl"], args  # no -wal, -shm, spool
    c = sqlite3.connect(app)
    assert c.execute("PRAGMA application_id").fetchone() == (0,)
    assert c.execute("PRAGMA journal_mode").fetchone() == (journal,)
    assert c.execute("SELECT * FROM runs").fetchall() == [("mine", "keep me")]
    c.close()


def test_rvc_databases_old_and_new_are_accepted_and_the_dashboard_changes_neither(tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"a":true}\n')
    new = tmp_path / "new.db"
    assert subprocess.run([rvc_binary(), "check", "-s", "{a}", "-o", f"sqlite:{new}", str(trace)],
                          capture_output=True, timeout=60).returncode == 0
    with sqlite3.connect(new) as c:
        assert c.execute("PRAGMA application_id").fetchone() == (0x72766331,)  # "rvc1": rvc's stamp
    # A database of an rvc before the stamp: its five tables, application_id 0, journal mode delete.
    old = tmp_path / "old.db"
    with sqlite3.connect(old) as c:
        for table in ("runs (run TEXT PRIMARY KEY, command TEXT, inputs TEXT, time_model TEXT, started_at REAL, "
                      "ended_at REAL, exit_status INTEGER, end_reason TEXT, counters TEXT)",
                      "properties (run TEXT, name TEXT, spec TEXT, PRIMARY KEY (run, name))",
                      "verdicts (id INTEGER PRIMARY KEY AUTOINCREMENT, run TEXT, property TEXT, time REAL, "
                      "value INTEGER, wall REAL)",
                      "violations (id INTEGER PRIMARY KEY AUTOINCREMENT, run TEXT, property TEXT, time REAL, "
                      "wall REAL, witness TEXT, explanation TEXT)",
                      "counters (id INTEGER PRIMARY KEY AUTOINCREMENT, run TEXT, wall REAL, counters TEXT)"):
            c.execute("CREATE TABLE " + table)
    before = {p: sha256(p) for p in (old, new)}
    for path in (old, new):
        d = subprocess.Popen([rvc_binary(), "dashboard", "--db", f"sqlite:{path}", "--listen", "127.0.0.1:0"],
                             stderr=subprocess.PIPE, text=True)
        assert "serving" in d.stderr.readline()
        d.send_signal(signal.SIGTERM)
        assert d.wait(timeout=30) == 0
    assert {p: sha256(p) for p in (old, new)} == before  # read only: no WAL switch, no tables
    with sqlite3.connect(old) as c:
        assert c.execute("PRAGMA journal_mode").fetchone() == ("delete",)
    r = subprocess.run([rvc_binary(), "check", "-s", "{a}", "-o", f"sqlite:{old}", str(trace)],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr  # an older rvc's database is written to, and stamped
    with sqlite3.connect(old) as c:
        assert c.execute("PRAGMA application_id").fetchone() == (0x72766331,)
        assert len(c.execute("SELECT * FROM runs").fetchall()) == 1


def test_a_run_refused_for_its_spec_creates_no_database(tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"a":true}\n')
    r = subprocess.run([rvc_binary(), "check", "-s", "{a", "-o", f"sqlite:{tmp_path}/new.db", str(trace)],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2, r.stderr
    assert sorted(os.listdir(tmp_path)) == ["t.jsonl"]  # no database, no spool, no lock
