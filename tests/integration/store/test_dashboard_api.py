"""rvc dashboard: its JSON API and event stream over a SQLite results database.

The database is written here with Python's sqlite3 and the DDL of src/store/schema.cpp
(Dialect::Sqlite), so every row is known and the API must return exactly those rows;
test_schema_matches_rvc and test_database_written_by_rvc_check tie that DDL and those rows
to what `rvc check --output sqlite:` really writes. The server runs as a process on
127.0.0.1 with port 0 (the real port is read from its stderr); only the standard library
talks to it.
"""
from __future__ import annotations

import http.client
import json
import os
import queue
import re
import signal
import sqlite3
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
from rvc_testlib import rvc_binary  # noqa: E402

# src/store/schema.cpp, Dialect::Sqlite (test_schema_matches_rvc keeps the two in step).
SCHEMA = [
    "CREATE TABLE IF NOT EXISTS runs (run TEXT PRIMARY KEY, command TEXT, inputs TEXT, time_model TEXT, "
    "started_at DOUBLE PRECISION, ended_at DOUBLE PRECISION, exit_status INTEGER, end_reason TEXT, counters TEXT)",
    "CREATE TABLE IF NOT EXISTS properties (run TEXT NOT NULL, name TEXT NOT NULL, spec TEXT, PRIMARY KEY (run, name))",
    "CREATE TABLE IF NOT EXISTS verdicts (id INTEGER PRIMARY KEY AUTOINCREMENT, run TEXT NOT NULL, "
    "property TEXT NOT NULL, time DOUBLE PRECISION, value INTEGER, wall DOUBLE PRECISION, known_at DOUBLE PRECISION)",
    "CREATE INDEX IF NOT EXISTS verdicts_by_run ON verdicts (run, property, id)",
    "CREATE TABLE IF NOT EXISTS violations (id INTEGER PRIMARY KEY AUTOINCREMENT, run TEXT NOT NULL, "
    "property TEXT NOT NULL, time DOUBLE PRECISION, wall DOUBLE PRECISION, witness TEXT, explanation TEXT, "
    "known_at DOUBLE PRECISION)",
    "CREATE INDEX IF NOT EXISTS violations_by_run ON violations (run, id)",
    "CREATE TABLE IF NOT EXISTS counters (id INTEGER PRIMARY KEY AUTOINCREMENT, run TEXT NOT NULL, "
    "wall DOUBLE PRECISION, counters TEXT)",
    "CREATE INDEX IF NOT EXISTS counters_by_run ON counters (run, id)",
]

WITNESS = [
    {"input": "vehicle/status", "seq": 11, "payload": '{"speed":38.5,"emergency":false}'},
    {"input": "vehicle/status", "seq": 12, "payload": '{"speed":44.1,"emergency":false}'},
]
HEX_WITNESS = [{"input": "dds:rt/vehicle/control", "seq": 4, "payload_hex": "0001000000e0", "truncated": True}]
SNAPSHOTS = [  # run r-live: (wall, counters) for two inputs, interleaved
    (3001.0, {"input": "a", "received": 100, "checked": 100, "gaps": 0}),
    (3001.5, {"input": "b", "received": 10, "checked": 10, "gaps": 1}),
    (3003.0, {"input": "a", "received": 300, "checked": 290, "gaps": 2}),
    (3005.5, {"input": "b", "received": 60, "checked": 60, "gaps": 1}),
]


def older(sql):
    """A CREATE statement as an rvc before explanations and known_at (bounded future) wrote it."""
    return sql.replace(", known_at DOUBLE PRECISION)", ")").replace(", explanation TEXT)", ")")


def execute(path, sql, params=()):
    """One statement, committed at once (as the monitor's writer commits its batches)."""
    db = sqlite3.connect(path)
    try:
        with db:
            return db.execute(sql, params).lastrowid
    finally:
        db.close()


def make_db(path) -> str:
    """Three runs (one still live) with known verdicts, violations and counters."""
    db = sqlite3.connect(path)
    db.execute("PRAGMA journal_mode=WAL")  # as the monitor leaves it
    for stmt in SCHEMA:
        db.execute(stmt)
    runs = [  # run, command, inputs, time_model, started, ended, exit, reason, final counters
        ("r-old", "rvc check -s {a} old.jsonl", '["old.jsonl"]', "discrete", 1000.0, 1010.0, 0, "end of input",
         '{"checked":3}'),
        ("r-mid", "rvc check -p props.yaml mid.jsonl", '["mid.jsonl"]', "discrete", 2000.0, 2050.5, 1, "end of input",
         None),
        ("r-live", "rvc monitor --input zenoh:vehicle/**", '["a","b"]', "dense", 3000.0, None, None, None, None),
        ("fleet/car 7", "rvc monitor", "[]", "discrete", 500.0, 501.0, 0, "eos", None),
    ]
    db.executemany("INSERT INTO runs VALUES (?,?,?,?,?,?,?,?,?)", runs)
    db.executemany("INSERT INTO properties VALUES (?,?,?)", [
        ("r-mid", "p1", "{speed < 40}"), ("r-mid", "p2", "historically({emergency} -> {hazard})"),
        ("r-mid", "quiet", "{true}"), ("r-old", "p1", "{a}")])
    db.executemany("INSERT INTO verdicts (run, property, time, value, wall) VALUES (?,?,?,?,?)", [
        ("r-mid", "p1", 0, 1, 2001.0), ("r-mid", "p2", 0, 1, 2001.0), ("r-mid", "p1", 3, 0, 2003.0),
        ("r-mid", "p2", 5, 0, 2005.0), ("r-mid", "p1", 7, 1, 2007.0),  # ids 1..5
        ("r-old", "p1", 0, 1, 1001.0)])  # id 6
    db.executemany("INSERT INTO violations (run, property, time, wall, witness) VALUES (?,?,?,?,?)", [
        ("r-mid", "p1", 3, 2003.0, json.dumps(WITNESS)),
        ("r-mid", "p2", 5, 2005.0, json.dumps(HEX_WITNESS)),
        ("r-mid", "p2", 9, 2009.0, "not json [")])  # a damaged row must not break the response
    db.executemany("INSERT INTO counters (run, wall, counters) VALUES (?,?,?)",
                   [("r-live", wall, json.dumps(c)) for wall, c in SNAPSHOTS])
    db.commit()
    db.close()
    return str(path)


class Dashboard:
    """`rvc dashboard` on 127.0.0.1, port 0; stopped by SIGTERM, which must end it cleanly."""

    def __init__(self, db_uri, *extra):
        self.proc = subprocess.Popen([rvc_binary(), "dashboard", "--db", db_uri, "--listen", "127.0.0.1:0", *extra],
                                     stderr=subprocess.PIPE, text=True)
        self.lines: queue.Queue = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()
        deadline = time.monotonic() + 15
        while True:
            try:
                line = self.lines.get(timeout=max(0.1, deadline - time.monotonic()))
            except queue.Empty:
                self.proc.kill()
                raise AssertionError("rvc dashboard did not say where it serves within 15 s")
            m = re.search(r"serving (\S+) on http://127\.0\.0\.1:(\d+)", line or "")
            if m:
                self.port = int(m.group(2))
                self.described = m.group(1)
                return
            if line is None:
                raise AssertionError(f"rvc dashboard exited with {self.proc.wait()}")

    def _read(self):
        for line in self.proc.stderr:
            self.lines.put(line)
        self.lines.put(None)

    def get(self, path, headers=None):
        """(status, JSON body). No proxy: the environment's http_proxy must not see loopback traffic."""
        opener = urllib.request.build_opener(urllib.request.ProxyHandler({}))
        req = urllib.request.Request(f"http://127.0.0.1:{self.port}{path}", headers=headers or {})
        try:
            with opener.open(req, timeout=10) as r:
                return r.status, json.loads(r.read())
        except urllib.error.HTTPError as e:
            return e.code, json.loads(e.read())

    def stop(self):
        self.proc.send_signal(signal.SIGTERM)
        return self.proc.wait(timeout=10)


@pytest.fixture
def db(tmp_path):
    return make_db(tmp_path / "results.db")


@pytest.fixture
def dash(db):
    d = Dashboard("sqlite:" + db)
    yield d
    assert d.stop() == 0


class Events:
    """An /api/events client: reads server-sent events as (event, data, id)."""

    def __init__(self, port, path, headers=None):
        self.conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
        self.conn.request("GET", path, headers=headers or {})
        self.resp = self.conn.getresponse()

    def next(self, timeout=5.0):
        """The next event (comments skipped), or None after `timeout` seconds."""
        deadline = time.monotonic() + timeout
        fields: dict = {}
        while time.monotonic() < deadline:
            line = self.resp.readline().decode()
            if line == "":
                return None  # the stream ended
            line = line.rstrip("\n")
            if line == "":
                if "data" in fields:
                    return fields.get("event", "message"), json.loads(fields["data"]), fields.get("id")
                fields = {}
            elif not line.startswith(":"):
                name, _, value = line.partition(":")
                fields[name] = value[1:] if value.startswith(" ") else value
        return None

    def close(self):
        # The server closes every connection after its response ("Connection: close"), so
        # http.client hands the socket to the response: closing the connection alone would
        # leave it open.
        self.resp.close()
        self.conn.close()


# --- the JSON API ------------------------------------------------------------------------

def test_health(dash, db):
    assert dash.get("/api/health") == (200, {"ok": True, "db": "sqlite:" + db, "runs": 4})
    assert dash.described == "sqlite:" + db


def test_runs_newest_first(dash):
    status, body = dash.get("/api/runs")
    assert status == 200 and body["more"] is False
    assert [r["run"] for r in body["runs"]] == ["r-live", "r-mid", "r-old", "fleet/car 7"]
    live, mid, old = body["runs"][:3]
    assert mid == {"run": "r-mid", "command": "rvc check -p props.yaml mid.jsonl", "inputs": ["mid.jsonl"],
                   "time_model": "discrete", "started_at": 2000, "ended_at": 2050.5, "exit_status": 1,
                   "end_reason": "end of input", "final_counters": None, "violations": 3, "property_count": 3,
                   "last_counters_at": None, "live": False, "silent": False}
    assert old["final_counters"] == {"checked": 3} and old["violations"] == 0
    assert live["live"] is True and live["ended_at"] is None and live["exit_status"] is None
    assert live["silent"] is True  # no end, and its last counters are from 1970
    assert live["last_counters_at"] == 3005.5 and live["inputs"] == ["a", "b"]
    status, body = dash.get("/api/runs?limit=2")
    assert [r["run"] for r in body["runs"]] == ["r-live", "r-mid"] and body["more"] is True


def test_run_with_properties(dash):
    status, body = dash.get("/api/runs/r-mid")
    assert status == 200 and body["run"]["run"] == "r-mid"
    assert body["properties"] == [
        {"name": "p1", "spec": "{speed < 40}", "value": True, "since": 7, "changes": 3, "violations": 1},
        {"name": "p2", "spec": "historically({emergency} -> {hazard})", "value": False, "since": 5, "changes": 2,
         "violations": 2},
        {"name": "quiet", "spec": "{true}", "value": None, "since": None, "changes": 0, "violations": 0},
    ]
    # A run id with a slash and a space, percent-encoded in the path.
    status, body = dash.get("/api/runs/fleet%2Fcar%207")
    assert status == 200 and body["run"]["run"] == "fleet/car 7" and body["properties"] == []
    assert dash.get("/api/runs/fleet%2Fcar%207/verdicts")[0] == 200


def test_verdicts_after_and_property(dash):
    def ids(path):
        status, body = dash.get(path)
        assert status == 200, body
        return [v["id"] for v in body["verdicts"]], body["last_id"], body["more"]

    status, body = dash.get("/api/runs/r-mid/verdicts")
    assert body == {"run": "r-mid", "after": 0, "last_id": 5, "more": False, "verdicts": [
        {"id": 1, "property": "p1", "time": 0, "value": True, "wall": 2001, "known_at": None},
        {"id": 2, "property": "p2", "time": 0, "value": True, "wall": 2001, "known_at": None},
        {"id": 3, "property": "p1", "time": 3, "value": False, "wall": 2003, "known_at": None},
        {"id": 4, "property": "p2", "time": 5, "value": False, "wall": 2005, "known_at": None},
        {"id": 5, "property": "p1", "time": 7, "value": True, "wall": 2007, "known_at": None}]}
    assert ids("/api/runs/r-mid/verdicts?after=2") == ([3, 4, 5], 5, False)
    assert ids("/api/runs/r-mid/verdicts?property=p1") == ([1, 3, 5], 5, False)
    assert ids("/api/runs/r-mid/verdicts?after=3&property=p1") == ([5], 5, False)
    assert ids("/api/runs/r-mid/verdicts?after=5") == ([], 5, False)  # nothing new: last_id stays
    assert ids("/api/runs/r-mid/verdicts?limit=2") == ([1, 2], 2, True)
    assert ids("/api/runs/r-mid/verdicts?after=2&limit=2") == ([3, 4], 4, True)
    assert ids("/api/runs/r-old/verdicts") == ([6], 6, False)  # rows of other runs never leak in
    assert ids("/api/runs/r-mid/verdicts?property=quiet") == ([], 0, False)  # declared, no verdict yet


@pytest.mark.parametrize("query", ["after=-1", "after=abc", "after=1.5", "after=", "afer=1", "limit=0",
                                   "property=", "after=1&after=2", "limit=100001"])
def test_bad_parameters_are_400(dash, query):
    status, body = dash.get("/api/runs/r-mid/verdicts?" + query)
    assert status == 400 and body["status"] == 400 and body["error"]


@pytest.mark.parametrize("limit", ["0", "-1", "100001", "x"])
def test_a_bad_limit_names_the_one_allowed_range(dash, limit):
    """limit=0 said "at least 1" and limit=-1 "from 0 to ...": one message, the range allowed."""
    for path, top in [("/api/runs/r-mid/verdicts", 100000), ("/api/runs", None)]:
        status, body = dash.get(f"{path}?limit={limit}")
        assert status == 400, (path, body)
        assert re.fullmatch(rf"limit must be an integer from 1 to {top or r'[0-9]+'}, not '{re.escape(limit)}'",
                            body["error"]), body


@pytest.mark.parametrize("method", ["POST", "PUT", "PATCH", "DELETE", "OPTIONS"])
def test_other_methods_are_405_with_allow(dash, method):
    for path in ["/api/health", "/api/runs", "/"]:
        conn = http.client.HTTPConnection("127.0.0.1", dash.port, timeout=10)
        conn.request(method, path, body=b"{}" if method in ("POST", "PUT", "PATCH") else None,
                     headers={"Content-Type": "application/json"})
        r = conn.getresponse()
        body = json.loads(r.read())
        conn.close()
        assert r.status == 405 and r.getheader("Allow") == "GET, HEAD", (method, path, r.status)
        assert body["status"] == 405 and "read-only" in body["error"]
    assert dash.get("/api/health")[0] == 200


def test_unknown_things_are_404(dash):
    for path in ["/api/runs/nope", "/api/runs/nope/verdicts", "/api/runs/nope/violations", "/api/runs/nope/counters",
                 "/api/runs/r-mid/verdicts?property=nope", "/api/nothing", "/nothing"]:
        status, body = dash.get(path)
        assert status == 404 and body["status"] == 404 and body["error"], path
    assert "nope" in dash.get("/api/runs/nope")[1]["error"]


def test_violations_with_parsed_witness(dash):
    status, body = dash.get("/api/runs/r-mid/violations")
    assert status == 200 and body["last_id"] == 3 and body["more"] is False
    assert body["violations"] == [
        {"id": 1, "property": "p1", "time": 3, "wall": 2003, "witness": WITNESS, "explanation": None, "known_at": None},
        {"id": 2, "property": "p2", "time": 5, "wall": 2005, "witness": HEX_WITNESS, "explanation": None, "known_at": None},
        {"id": 3, "property": "p2", "time": 9, "wall": 2009, "witness": "not json [", "explanation": None, "known_at": None},  # as text
    ]
    status, body = dash.get("/api/runs/r-mid/violations?after=1&property=p2&limit=1")
    assert [v["id"] for v in body["violations"]] == [2] and body["more"] is True


def test_counters_with_rates(dash):
    status, body = dash.get("/api/runs/r-live/counters")
    assert status == 200
    rows = body["counters"]
    assert [(r["id"], r["wall"], r["counters"]) for r in rows] == [
        (i + 1, wall, c) for i, (wall, c) in enumerate(SNAPSHOTS)]
    # Rates per input, between that input's consecutive snapshots.
    assert [r["rates"] for r in rows] == [
        None, None,
        {"seconds": 2, "received_per_s": 100, "checked_per_s": 95},
        {"seconds": 4, "received_per_s": 12.5, "checked_per_s": 12.5}]
    # Following on: the rate of the first row still comes from the snapshot before it.
    status, body = dash.get("/api/runs/r-live/counters?after=2")
    assert [r["id"] for r in body["counters"]] == [3, 4] and body["counters"][0]["rates"]["received_per_s"] == 100
    # Without after: the latest `limit` snapshots, oldest first.
    status, body = dash.get("/api/runs/r-live/counters?limit=2")
    assert [r["id"] for r in body["counters"]] == [3, 4] and body["last_id"] == 4
    assert dash.get("/api/runs/r-mid/counters")[1]["counters"] == []


# --- the page and network safety -----------------------------------------------------------

def test_page_is_self_contained(dash):
    conn = http.client.HTTPConnection("127.0.0.1", dash.port, timeout=10)
    conn.request("GET", "/")
    r = conn.getresponse()
    page = r.read().decode()
    assert r.status == 200 and r.getheader("Content-Type").startswith("text/html")
    assert "connect-src 'self'" in r.getheader("Content-Security-Policy")
    assert 'id="runs"' in page and 'id="filter"' in page and "EventSource" in page
    # Nothing from elsewhere: no URLs at all, no external scripts or styles.
    assert not re.search(r"(https?:)?//[a-z0-9.-]+\.[a-z]{2,}", page, re.I), "the page names an external URL"
    assert "<script src" not in page and "<link" not in page


def test_foreign_host_header_is_refused(dash):
    # DNS rebinding: a page elsewhere resolving its own name to 127.0.0.1 sends its name as Host.
    status, body = dash.get("/api/runs", headers={"Host": "attacker.example:8765"})
    assert status == 403 and "loopback" in body["error"]
    assert dash.get("/api/runs", headers={"Host": f"localhost:{dash.port}"})[0] == 200


@pytest.mark.parametrize("listen", ["0.0.0.0:0", "192.0.2.1:0", "[::]:0", "example.com:0"])
def test_remote_listen_is_refused(db, listen):
    r = subprocess.run([rvc_binary(), "dashboard", "--db", "sqlite:" + db, "--listen", listen],
                       capture_output=True, text=True, timeout=20)
    assert r.returncode == 2 and "--allow-remote" in r.stderr and "serving" not in r.stderr


@pytest.mark.parametrize("listen", ["127.0.0.1", "127.0.0.1:99999", ":8765", "127.0.0.1:x"])
def test_bad_listen_is_usage_error(db, listen):
    r = subprocess.run([rvc_binary(), "dashboard", "--db", "sqlite:" + db, "--listen", listen],
                       capture_output=True, text=True, timeout=20)
    assert r.returncode == 2 and "--listen" in r.stderr


def test_port_in_use_is_refused(dash, db):
    # Not shared either (httplib would set SO_REUSEPORT): a second server must not take half the requests.
    r = subprocess.run([rvc_binary(), "dashboard", "--db", "sqlite:" + db, "--listen", f"127.0.0.1:{dash.port}"],
                       capture_output=True, text=True, timeout=20)
    assert r.returncode == 5 and "cannot listen" in r.stderr


def test_bad_database_is_usage_error(tmp_path):
    for uri in ["results.db", "sqlite:", f"sqlite:{tmp_path}/missing.db", f"sqlite:{tmp_path}/no/dir/x.db",
                "postgresql://127.0.0.1:1/rvc?connect_timeout=2"]:
        r = subprocess.run([rvc_binary(), "dashboard", "--db", uri, "--listen", "127.0.0.1:0"],
                           capture_output=True, text=True, timeout=30)
        assert r.returncode == 2 and r.stderr.startswith("rvc dashboard: "), (uri, r.stderr)
    assert not (tmp_path / "missing.db").exists()  # a typo does not create an empty database


# --- server-sent events ------------------------------------------------------------------------

def test_events_deliver_rows_inserted_after_connecting(dash, db):
    ev = Events(dash.port, "/api/events?run=r-live")
    assert ev.resp.status == 200 and ev.resp.getheader("Content-Type") == "text/event-stream"
    assert ev.resp.readline().startswith(b"retry:")  # the stream is open: what comes now is new
    vid = execute(db, "INSERT INTO verdicts (run, property, time, value, wall) VALUES ('r-live','p9',4.5,0,3010)")
    kid = execute(db, "INSERT INTO violations (run, property, time, wall, witness) VALUES ('r-live','p9',4.5,3010,?)",
                  (json.dumps(WITNESS),))
    cid = execute(db, "INSERT INTO counters (run, wall, counters) VALUES ('r-live', 3007.0, ?)",
                  (json.dumps({"input": "a", "received": 500}),))
    execute(db, "INSERT INTO verdicts (run, property, time, value, wall) VALUES ('r-mid','p1',99,0,1)")  # other run
    got = {}
    while len(got) < 3:
        e = ev.next(timeout=5)
        assert e is not None, f"events so far: {got}"
        got[e[0]] = e
    # (ev.next's timeout bounds the wait: rows arrive live, not at the end of a long poll)
    assert got["verdict"][1] == [{"id": vid, "property": "p9", "time": 4.5, "value": False, "wall": 3010,
                                  "known_at": None}]
    assert got["violation"][1] == [{"id": kid, "property": "p9", "time": 4.5, "wall": 3010, "witness": WITNESS,
                                    "explanation": None, "known_at": None}]
    assert [(c["id"], c["counters"]) for c in got["counters"][1]] == [(cid, {"input": "a", "received": 500})]
    assert got["counters"][1][0]["rates"] == {"seconds": 4, "received_per_s": 50, "checked_per_s": None}
    assert got["counters"][2] == f"{vid},{kid},{cid}"  # the cursor, for a reconnecting EventSource
    ev.close()


def test_events_start_from_given_ids_and_last_event_id(dash):
    ev = Events(dash.port, "/api/events?run=r-mid&verdict=3&violation=0&counters=0")
    found = {e[0]: e[1] for e in (ev.next(), ev.next())}
    assert [v["id"] for v in found["verdict"]] == [4, 5]
    assert [v["id"] for v in found["violation"]] == [1, 2, 3]
    ev.close()
    # A reconnecting EventSource sends Last-Event-ID: it wins over the ids in the URL.
    ev = Events(dash.port, "/api/events?run=r-mid&verdict=0&violation=0&counters=0", {"Last-Event-ID": "4,3,0"})
    event = ev.next(timeout=3)
    assert event is not None and event[0] == "verdict" and [v["id"] for v in event[1]] == [5]
    ev.close()


def test_events_announce_new_and_ended_runs(dash, db):
    ev = Events(dash.port, "/api/events")  # no run: only run events
    ev.resp.readline()
    execute(db, "INSERT INTO runs (run, command, started_at) VALUES ('r-new', 'rvc monitor', 4000)")
    event = ev.next(timeout=5)
    assert event[0] == "run" and [r["run"] for r in event[1]][:2] == ["r-new", "r-live"]
    execute(db, "UPDATE runs SET ended_at = 3100, exit_status = 0, end_reason = 'signal' WHERE run = 'r-live'")
    event = ev.next(timeout=5)
    live = next(r for r in event[1] if r["run"] == "r-live")
    assert event[0] == "run" and live["live"] is False and live["end_reason"] == "signal"
    ev.close()


def test_events_announce_a_run_going_silent(db):
    """No row changes: the run's last counters just grow older than --silent-after."""
    execute(db, "INSERT INTO runs (run, command, started_at) VALUES ('r-quiet', 'rvc monitor', ?)", (time.time(),))
    # Its last counters 3 s ahead: not silent while the dashboard starts and the stream connects.
    execute(db, "INSERT INTO counters (run, wall, counters) VALUES ('r-quiet', ?, '{}')", (time.time() + 3,))
    d = Dashboard("sqlite:" + db, "--silent-after", "1")
    try:
        assert next(r for r in d.get("/api/runs")[1]["runs"] if r["run"] == "r-quiet")["silent"] is False
        ev = Events(d.port, "/api/events")
        ev.resp.readline()
        event = ev.next(timeout=30)
        assert event is not None and event[0] == "run"
        assert next(r for r in event[1] if r["run"] == "r-quiet")["silent"] is True
        ev.close()
    finally:
        assert d.stop() == 0


def test_events_bad_requests(dash):
    for path, status in [("/api/events?run=nope", 404), ("/api/events?run=r-mid&verdict=x", 400),
                         ("/api/events?run=", 400), ("/api/events?runn=r-mid", 400)]:
        assert dash.get(path)[0] == status, path


def test_closed_streams_free_their_slots(dash):
    # At most 8 streams at once; a client that goes away must give its slot back
    # (found by a failed write: keep-alive comments go out every 2 s).
    streams = [Events(dash.port, "/api/events?run=r-live") for _ in range(8)]
    for s in streams:
        assert s.resp.status == 200
    assert dash.get("/api/events?run=r-live")[0] == 503
    for s in streams:
        s.close()
    deadline = time.monotonic() + 10
    while True:
        ev = Events(dash.port, "/api/events?run=r-live")
        if ev.resp.status == 200:
            ev.close()
            break
        ev.close()
        assert time.monotonic() < deadline, "closed event streams were not noticed within 10 s"
        time.sleep(0.5)
    assert dash.get("/api/health")[0] == 200  # the API never starved meanwhile


def test_sigterm_with_open_streams_stops_promptly(db):
    d = Dashboard("sqlite:" + db)
    ev = Events(d.port, "/api/events?run=r-live")
    ev.resp.readline()
    # Not a speed test: a server that waited for its open streams to end would never stop
    # (the stream stays open); 15 s only guards against that hang.
    t0 = time.monotonic()
    assert d.stop() == 0
    assert time.monotonic() - t0 < 15
    ev.close()


# --- the same schema and rows as rvc itself writes -----------------------------------------------

def test_schema_matches_rvc(tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"a":true}\n')
    r = subprocess.run([rvc_binary(), "check", "-s", "{a}", "--output", f"sqlite:{tmp_path}/rvc.db", str(trace)],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 0, r.stderr
    make_db(tmp_path / "ours.db")

    def ddl(path):
        with sqlite3.connect(path) as c:
            return sorted(row[0] for row in c.execute("SELECT sql FROM sqlite_master WHERE sql IS NOT NULL "
                                                      "AND name NOT LIKE 'sqlite_%'"))
    assert ddl(tmp_path / "ours.db") == ddl(tmp_path / "rvc.db")


def test_database_written_by_rvc_check(tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(json.dumps({"speed": s}) + "\n" for s in [10, 50, 20, 60]))
    db = tmp_path / "results.db"
    r = subprocess.run([rvc_binary(), "check", "-s", "{speed < 40}", "--output", f"sqlite:{db}", str(trace)],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 1, r.stderr  # violated
    d = Dashboard(f"sqlite:{db}")
    try:
        runs = d.get("/api/runs")[1]["runs"]
        assert len(runs) == 1 and runs[0]["live"] is False and runs[0]["exit_status"] == 1
        run = runs[0]["run"]
        verdicts = d.get(f"/api/runs/{run}/verdicts")[1]["verdicts"]
        assert [(v["time"], v["value"]) for v in verdicts] == [(0, True), (1, False), (2, True), (3, False)]
        violations = d.get(f"/api/runs/{run}/violations")[1]["violations"]
        assert [v["time"] for v in violations] == [1, 3]
        assert [json.loads(m["payload"]) for m in violations[0]["witness"]][-1] == {"speed": 50}
        detail = d.get(f"/api/runs/{run}")[1]
        assert detail["properties"] == [{"name": "p1", "spec": "{speed < 40}", "value": False, "since": 3,
                                         "changes": 4, "violations": 2}]
    finally:
        assert d.stop() == 0


def test_killed_monitor_run_is_reported_silent(tmp_path):
    """A live monitor records counters every second, also without messages; once it is killed
    (no end recorded) and nothing comes for --silent-after, the API says "silent"."""
    db = tmp_path / "results.db"
    mon = subprocess.Popen([rvc_binary(), "monitor", "-s", "{speed < 40}", "--input", "-", "--output",
                            f"sqlite:{db}", "--output", f"file:{tmp_path}/v.jsonl"],
                           stdin=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    d = None
    try:
        mon.stdin.write(json.dumps({"speed": 10}) + "\n")
        mon.stdin.flush()

        def counters_rows():
            if not db.exists():
                return 0
            with sqlite3.connect(db) as c:
                try:
                    return c.execute("SELECT COUNT(*) FROM counters").fetchone()[0]
                except sqlite3.OperationalError:  # the tables are not there yet
                    return 0

        deadline = time.monotonic() + 60
        while counters_rows() < 3 and time.monotonic() < deadline:
            time.sleep(0.1)
        assert counters_rows() >= 3, "the monitor recorded no counters"
        d = Dashboard(f"sqlite:{db}", "--silent-after", "4")
        run = d.get("/api/runs")[1]["runs"][0]
        assert run["live"] is True and run["silent"] is False  # records keep arriving
        mon.kill()
        mon.wait(timeout=30)
        while time.monotonic() < deadline + 60:
            run = d.get("/api/runs")[1]["runs"][0]
            if run["silent"]:
                break
            time.sleep(0.2)
        assert run["live"] is True and run["silent"] is True
        assert d.get(f"/api/runs/{run['run']}")[1]["run"]["silent"] is True
    finally:
        if mon.poll() is None:
            mon.kill()
        if d is not None:
            assert d.stop() == 0


def test_explanations_kept_and_an_older_database_gains_their_column(tmp_path):
    """A database made before explanations were stored (violations without the column) is
    migrated by the next run, which keeps --explain's sentences; the API returns them."""
    db = tmp_path / "old.db"
    with sqlite3.connect(db) as c:
        for sql in SCHEMA:
            c.execute(older(sql))
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(json.dumps({"speed": s}) + "\n" for s in [10, 50]))
    r = subprocess.run([rvc_binary(), "check", "--explain", "-s", "{speed < 40}", "--output", f"sqlite:{db}",
                        str(trace)], capture_output=True, text=True, timeout=30)
    assert r.returncode == 1, r.stderr
    d = Dashboard(f"sqlite:{db}")
    try:
        run = d.get("/api/runs")[1]["runs"][0]["run"]
        violations = d.get(f"/api/runs/{run}/violations")[1]["violations"]
        assert [v["explanation"] for v in violations] == [["{speed < 40} is false at step 1"]]
    finally:
        assert d.stop() == 0


def test_an_older_database_is_served_as_it_is(tmp_path):
    """A database from before explanations (violations without the column) is read, not migrated:
    the dashboard opens it read-only, its violations have null explanations, and its bytes stay."""
    import hashlib
    db = tmp_path / "old.db"
    with sqlite3.connect(db) as c:
        for sql in SCHEMA:
            c.execute(older(sql))
        c.execute("INSERT INTO runs (run, command, started_at) VALUES ('r1', 'rvc check', 1)")
        c.execute("INSERT INTO violations (run, property, time, wall, witness) VALUES ('r1', 'p1', 3, 4, '[]')")
    before = hashlib.sha256(db.read_bytes()).hexdigest()
    d = Dashboard(f"sqlite:{db}")
    try:
        status, body = d.get("/api/runs/r1/violations")
        assert status == 200 and [(v["time"], v["explanation"]) for v in body["violations"]] == [(3, None)]
        ev = Events(d.port, "/api/events?run=r1&verdict=0&violation=0&counters=0")
        event = ev.next(timeout=5)
        assert event is not None and event[0] == "violation" and event[1][0]["explanation"] is None
        ev.close()
    finally:
        assert d.stop() == 0
    assert hashlib.sha256(db.read_bytes()).hexdigest() == before


def test_delayed_verdicts_keep_known_at_and_an_older_database_gains_the_column(tmp_path):
    """Bounded future (issue 29): a delayed verdict is stored with the instant it became known
    (known_at), a past-only one with known_at = time; a database from before known_at (no such
    column) is migrated by the next run; the API returns known_at (null for an older database's rows,
    which the dashboard reads without migrating). Hand-computed: p at step 2 only, eventually[1:2]{p}
    is true for 0 (known at 2) and false from 2 (known at 4)."""
    db = tmp_path / "old.db"
    with sqlite3.connect(db) as c:
        for sql in SCHEMA:
            c.execute(sql.replace(", known_at DOUBLE PRECISION)", ")"))  # explanations, no known_at
        c.execute("INSERT INTO runs (run, command, started_at) VALUES ('r0', 'rvc check', 1)")
        c.execute("INSERT INTO verdicts (run, property, time, value, wall) VALUES ('r0', 'p1', 3, 1, 4)")
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(json.dumps({"p": p}) + "\n" for p in [False, False, True, False, False]))
    r = subprocess.run([rvc_binary(), "check", "-s", "eventually[1:2]{p}", "-s", "historically{p: false}",
                        "--output", f"sqlite:{db}", str(trace)], capture_output=True, text=True, timeout=30)
    assert r.returncode == 1, r.stderr
    with sqlite3.connect(db) as c:
        rows = c.execute("SELECT property, time, value, known_at FROM verdicts WHERE run != 'r0' ORDER BY id").fetchall()
        assert rows == [("p2", 0, 1, 0), ("p1", 0, 1, 2), ("p2", 2, 0, 2), ("p1", 2, 0, 4)]
        assert c.execute("SELECT property, time, known_at FROM violations ORDER BY id").fetchall() == [
            ("p2", 2, 2), ("p1", 2, 4)]
    d = Dashboard(f"sqlite:{db}")
    try:
        run = [x["run"] for x in d.get("/api/runs")[1]["runs"] if x["run"] != "r0"][0]
        verdicts = d.get(f"/api/runs/{run}/verdicts")[1]["verdicts"]
        assert [(v["property"], v["time"], v["known_at"]) for v in verdicts] == [
            ("p2", 0, 0), ("p1", 0, 2), ("p2", 2, 2), ("p1", 2, 4)]
        assert [v["known_at"] for v in d.get("/api/runs/r0/verdicts")[1]["verdicts"]] == [None]
    finally:
        assert d.stop() == 0


# --- the same API over PostgreSQL ------------------------------------------------------------------

def test_postgresql_database(rvc_pg, pg, tmp_path):
    """The SQL is the same for both databases: a run written to PostgreSQL by `rvc check` reads back
    as from SQLite, and events follow rows inserted later (the `pg` fixture of conftest.py: a
    throwaway server on a unix socket, no TCP)."""
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(json.dumps({"speed": s}) + "\n" for s in [10, 50, 20]))
    r = subprocess.run([rvc_pg, "check", "-s", "{speed < 40}", "--output", pg.uri, str(trace)],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 1, r.stderr
    d = Dashboard(pg.uri)
    try:
        status, body = d.get("/api/runs")
        assert status == 200 and len(body["runs"]) == 1 and body["runs"][0]["violations"] == 1
        run = body["runs"][0]["run"]
        assert body["runs"][0]["live"] is False and body["runs"][0]["inputs"] == [str(trace)]
        detail = d.get(f"/api/runs/{run}")[1]
        assert detail["properties"] == [{"name": "p1", "spec": "{speed < 40}", "value": True, "since": 2,
                                         "changes": 3, "violations": 1}]
        assert [(v["id"], v["value"]) for v in d.get(f"/api/runs/{run}/verdicts?after=1&property=p1")[1]["verdicts"]] \
            == [(2, False), (3, True)]
        witness = d.get(f"/api/runs/{run}/violations")[1]["violations"][0]["witness"]
        assert json.loads(witness[-1]["payload"]) == {"speed": 50}
        assert d.get("/api/runs/nope")[0] == 404 and d.get(f"/api/runs/{run}/verdicts?after=x")[0] == 400
        ev = Events(d.port, f"/api/events?run={run}")
        ev.resp.readline()
        psql = os.path.join(os.environ.get("PG_BIN", "/usr/lib/postgresql/15/bin"), "psql")  # as conftest.py
        subprocess.run([psql if os.access(psql, os.X_OK) else "psql", "-X", "-q", "-d", pg.uri, "-c",
                        f"INSERT INTO verdicts (run, property, time, value, wall) VALUES ('{run}', 'p1', 3, 0, 5)"],
                       check=True, capture_output=True, timeout=30)
        event = ev.next(timeout=5)
        assert event is not None and event[0] == "verdict"
        assert [(v["id"], v["time"], v["value"]) for v in event[1]] == [(4, 3, False)]
        ev.close()
    finally:
        assert d.stop() == 0


# --- under load: slow clients and too many event streams leave the API answerable ----------------

def test_api_answers_with_slow_clients_and_streams_over_the_cap(dash):
    """20 clients that send a byte of their request every 3 s, the 8 event streams allowed, and 100
    more that must each get a 503 and a closed connection: /api/health still answers. (Without read
    timeouts the slow clients hold server threads for as long as they trickle; the 503s, left open
    by keep-alive, held one more each.) Every socket here is to 127.0.0.1 and has a timeout."""
    import socket

    stop = threading.Event()
    closed_by_server = []

    def slow_client():
        s = socket.create_connection(("127.0.0.1", dash.port), timeout=30)
        try:
            for byte in b"GET /api/health HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n":
                s.sendall(bytes([byte]))
                if stop.wait(3):
                    return
                s.settimeout(0.01)
                try:
                    if s.recv(1024) == b"":  # the server gave up on us
                        closed_by_server.append(True)
                        return
                except (socket.timeout, BlockingIOError):
                    pass
                except OSError:
                    closed_by_server.append(True)
                    return
        except OSError:
            closed_by_server.append(True)
        finally:
            s.close()

    slow = [threading.Thread(target=slow_client, daemon=True) for _ in range(20)]
    for t in slow:
        t.start()
    streams = [Events(dash.port, "/api/events?run=r-live") for _ in range(8)]
    try:
        assert all(s.resp.status == 200 for s in streams)
        for _ in range(100):
            s = socket.create_connection(("127.0.0.1", dash.port), timeout=15)
            s.sendall(b"GET /api/events?run=r-live HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
            got = b""
            while True:  # to the end: the server closes the connection after its 503
                chunk = s.recv(65536)
                if not chunk:
                    break
                got += chunk
            s.close()
            assert got.startswith(b"HTTP/1.1 503") and b"too many event streams" in got, got[:200]
        status, body = dash.get("/api/health")  # 10 s socket timeout: liveness, not speed
        assert status == 200 and body["ok"] is True
        for t in slow:  # each notices the server's close at its next byte, 3 s on
            t.join(timeout=20)
    finally:
        stop.set()
        for s in streams:
            s.close()
        for t in slow:
            t.join(timeout=30)
    assert len(closed_by_server) == 20  # every slow client was cut off by the server's read timeout


def test_health_answers_while_60_clients_trickle(dash):
    """60 clients each sending one byte of a request every 1.5 s (more than the server's threads):
    every connection must deliver its whole request within a deadline, so the tricklers are cut off
    and /api/health answers while they still trickle (before: 40 of them left it unanswered for ~50 s;
    each holds a thread ~70 s). Bounded: 60 loopback sockets, each closed within 90 s."""
    import socket

    stop = threading.Event()
    cut = []

    def trickle():
        try:
            s = socket.create_connection(("127.0.0.1", dash.port), timeout=5)
        except OSError:
            return
        try:
            for byte in b"GET /api/health HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Padding: aaaaaaaaaaaaaaaaaaaa\r\n\r\n":
                s.sendall(bytes([byte]))
                if stop.wait(1.5):
                    return
        except OSError:
            cut.append(True)  # the server closed the connection (reset or broken pipe)
        finally:
            s.close()

    slow = [threading.Thread(target=trickle, daemon=True) for _ in range(60)]
    for t in slow:
        t.start()
    try:
        time.sleep(3)  # every trickler connected and holding its connection
        conn = http.client.HTTPConnection("127.0.0.1", dash.port, timeout=45)
        conn.request("GET", "/api/health", headers={"Host": "127.0.0.1"})
        r = conn.getresponse()
        assert r.status == 200 and json.loads(r.read())["ok"] is True
        conn.close()  # within the socket's 45 s: a liveness bound, not a speed (each trickler needs ~90 s)
    finally:
        stop.set()
        for t in slow:
            t.join(timeout=90)
