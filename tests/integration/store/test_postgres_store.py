"""`rvc check --output postgresql://...`: the results store on a real
PostgreSQL server (scripts/postgres-test.sh, a unix socket only).

Two properties over {"a": bool} messages, in discrete time (a verdict's time
is its step, a witness entry's seq the line number):
  now     {a}              the verdict is a itself
  always  historically{a}  true until the first false a, then false
Test A spells the expected rows out by hand; the longer traces of B and C use
`expected()`, the same rules as code. Rows are compared exactly, in id order.
"""
import json
import os
import signal
import sqlite3
import subprocess
import threading
import time

import pytest

PROPERTIES = {"now": "{a}", "always": "historically{a}"}


def props_file(tmp_path):
    p = tmp_path / "props.json"
    p.write_text(json.dumps(PROPERTIES))
    return str(p)


def line(step, a):
    return json.dumps({"a": a, "n": step}, separators=(",", ":"))


def expected(values, input_name, witness=10, first_line=1):
    """Verdict changes and violations of `now` and `always` over a = values[step]."""
    lines = [line(i, a) for i, a in enumerate(values)]
    verdicts, violations, last = [], [], {}
    for step, a in enumerate(values):
        current = {"now": a, "always": all(values[:step + 1])}
        for prop in PROPERTIES:  # the properties file's order
            if last.get(prop) == current[prop]:
                continue
            last[prop] = current[prop]
            verdicts.append((prop, step, int(current[prop])))
            if not current[prop]:
                window = range(max(0, step - witness + 1), step + 1)
                violations.append((prop, step, [{"input": input_name, "seq": first_line + i, "payload": lines[i]}
                                                 for i in window]))
    return verdicts, violations


def stored(pg, run):
    verdicts = [(r["property"], r["time"], r["value"]) for r in
                pg.sql(f"SELECT property, time, value FROM verdicts WHERE run = '{run}' ORDER BY id")]
    violations = [(r["property"], r["time"], json.loads(r["witness"])) for r in
                  pg.sql(f"SELECT property, time, witness FROM violations WHERE run = '{run}' ORDER BY id")]
    return verdicts, violations


def only_run(pg):
    runs = pg.sql("SELECT * FROM runs")
    assert len(runs) == 1, runs
    return runs[0]


class Stderr:
    """Collects a process's stderr lines as they come; wait_for() a text."""

    def __init__(self, proc):
        self.lines = []
        self._cv = threading.Condition()
        self._thread = threading.Thread(target=self._read, args=(proc.stderr,), daemon=True)
        self._thread.start()

    def _read(self, stream):
        for text in stream:
            with self._cv:
                self.lines.append(text)
                self._cv.notify_all()

    def wait_for(self, text, timeout):
        with self._cv:
            found = self._cv.wait_for(lambda: any(text in l for l in self.lines), timeout)
        assert found, f"rvc's stderr never said '{text}' within {timeout} s:\n{self.text()}"

    def text(self):
        with self._cv:
            return "".join(self.lines)


def rows_in(pg, table):
    """Rows in `table`; 0 before rvc has created it."""
    try:
        return pg.sql(f"SELECT count(*) AS n FROM {table}")[0]["n"]
    except AssertionError:
        return 0


def wait_until(predicate, timeout, what):
    deadline = time.time() + timeout
    while not predicate():
        assert time.time() < deadline, f"timed out ({timeout} s) waiting for {what}"
        time.sleep(0.1)


# ---------------------------------------------------------------------------
# A: one run, every table, against the hand-computed rows (and SQLite's).

TRACE_A = [
    '{"a":true,"n":0}',
    '{"a":true,"n":1}',
    '{"a":false,"n":2,"s":"quote \\" back\\\\slash \\t tab caf\u00e9"}',  # escapes in the payload
    '{"a":false,\t"n":3}',  # a raw tab: legal JSON whitespace
    '{"a":true,"n":4}',
    '{"a":false,"n":5}',
    '{"a":true,"n":6}',
]


def test_a_rows_of_one_run(rvc_pg, pg, tmp_path):
    trace = tmp_path / "a.jsonl"
    trace.write_text("".join(l + "\n" for l in TRACE_A))
    props = props_file(tmp_path)
    r = subprocess.run([rvc_pg, "check", "-p", props, str(trace), "--output", pg.uri, "--witness", "3", "--explain"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 1, r.stderr  # violated

    run = only_run(pg)
    assert run["time_model"] == "discrete"
    assert json.loads(run["inputs"]) == [str(trace)]
    assert run["exit_status"] == 1 and run["end_reason"] == "end of input"
    assert 0 < run["started_at"] <= run["ended_at"] < time.time() + 1
    counters = json.loads(run["counters"])
    assert counters["checked"] == 7 and counters["violations"] == 3
    assert sorted((p["name"], p["spec"]) for p in pg.sql("SELECT name, spec FROM properties")) == \
        [("always", "historically{a}"), ("now", "{a}")]

    # a = T T F F T F T: `now` changes at 0, 2, 4, 5, 6; `always` at 0 and 2.
    verdicts, violations = stored(pg, run["run"])
    assert verdicts == [("now", 0, 1), ("always", 0, 1), ("now", 2, 0), ("always", 2, 0),
                        ("now", 4, 1), ("now", 5, 0), ("now", 6, 1)]
    # Violations where a verdict turns false; the witness is the last 3
    # lines up to the violating one, oldest first (seq: the line number).
    w = lambda *lines: [{"input": str(trace), "seq": n, "payload": TRACE_A[n - 1]} for n in lines]
    assert violations == [("now", 2, w(1, 2, 3)), ("always", 2, w(1, 2, 3)), ("now", 5, w(4, 5, 6))]
    # --explain: each violation keeps why, as the verdict line says it.
    explained = [json.loads(r["explanation"]) for r in pg.sql("SELECT explanation FROM violations ORDER BY id")]
    assert explained[0] == ["{a} is false at step 2"]
    assert explained[1] == ["(historically {a}) is false: {a} failed at least once at steps 0..2", "{a} is false at step 2"]
    walls = pg.sql("SELECT wall FROM verdicts ORDER BY id")
    assert all(run["started_at"] <= v["wall"] <= run["ended_at"] for v in walls)

    # The same run into SQLite stores the same rows.
    db = tmp_path / "a.db"
    r = subprocess.run([rvc_pg, "check", "-p", props, str(trace), "--output", f"sqlite:{db}", "--witness", "3",
                        "--explain"], capture_output=True, text=True, timeout=30)
    assert r.returncode == 1, r.stderr
    with sqlite3.connect(db) as con:
        assert [json.loads(e) for (e,) in con.execute("SELECT explanation FROM violations ORDER BY id")] == explained
        assert [tuple(r) for r in con.execute("SELECT property, time, value FROM verdicts ORDER BY id")] == verdicts
        assert [(p, t, json.loads(w)) for p, t, w in
                con.execute("SELECT property, time, witness FROM violations ORDER BY id")] == violations


# ---------------------------------------------------------------------------
# B: the database goes away in the middle of a live run and comes back.

def test_b_outage_in_the_middle(rvc_pg, pg, tmp_path):
    # Phase 1 (steps 0-9) all true; a is false at 12, 15, 18 (database away)
    # and 21, 24, 27 (back): `always` is violated while the database is away.
    values = [not (i >= 10 and i % 3 == 0) for i in range(30)]
    phases = [range(0, 10), range(10, 20), range(20, 30)]
    spool = tmp_path / "b.spool"
    with open(tmp_path / "b.out", "w") as out:
        proc = subprocess.Popen([rvc_pg, "check", "-p", props_file(tmp_path), "-", "--output", pg.uri,
                                 "--db-wait", "30", "--spool", str(spool)],
                                stdin=subprocess.PIPE, stdout=out, stderr=subprocess.PIPE, text=True)
        try:
            err = Stderr(proc)

            def feed(steps):
                for i in steps:
                    proc.stdin.write(line(i, values[i]) + "\n")
                proc.stdin.flush()

            feed(phases[0])
            # Written live: phase 1's two verdicts reach the database while stdin is open.
            wait_until(lambda: rows_in(pg, "verdicts") == 2, 10, "phase 1 verdicts")
            pg.stop()
            feed(phases[1])
            err.wait_for("keeping results and retrying", 10)
            pg.start()
            err.wait_for("is back", 15)
            feed(phases[2])
            proc.stdin.close()
            assert proc.wait(timeout=45) == 1, err.text()  # violated
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()

    run = only_run(pg)
    assert run["exit_status"] == 1 and run["end_reason"] == "end of input"
    want_verdicts, want_violations = expected(values, "-")
    assert len(want_violations) == 7  # `always` once, `now` six times
    assert stored(pg, run["run"]) == (want_verdicts, want_violations)
    assert not spool.exists()  # nothing left behind


# ---------------------------------------------------------------------------
# D: `docker stop` while the server is away: SIGTERM spools at once instead of
# waiting --db-wait (docker would SIGKILL after its 10 s grace), and the next
# run writes the spool.

def test_d_signal_while_the_server_is_away_spools_at_once(rvc_pg, pg, tmp_path):
    values = [i != 12 for i in range(20)]  # violated at 12, while the server is away
    spool = tmp_path / "d.spool"
    proc = subprocess.Popen([rvc_pg, "check", "-p", props_file(tmp_path), "-", "--output", pg.uri,
                             "--db-wait", "600", "--spool", str(spool)],
                            stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        err = Stderr(proc)
        proc.stdin.write("".join(line(i, values[i]) + "\n" for i in range(10)))
        proc.stdin.flush()
        wait_until(lambda: rows_in(pg, "verdicts") == 2, 10, "the first verdicts")
        pg.stop()
        proc.stdin.write("".join(line(i, values[i]) + "\n" for i in range(10, 20)))
        proc.stdin.flush()
        err.wait_for("keeping results and retrying", 10)
        proc.send_signal(signal.SIGTERM)  # stdin stays open: only the signal ends the run
        # Liveness only: waiting out --db-wait (600 s) would not end within this.
        assert proc.wait(timeout=60) == 1, err.text()  # violated
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert "stopped by a signal (no waiting)" in err.text(), err.text()
    tables = spooled_tables(spool)
    # Hand-counted, while away: `now` false at 12 and true at 13, `always` false at 12; two violations.
    assert tables == ["verdict", "violation", "verdict", "violation", "verdict", "run_end"], tables

    pg.start()
    trace = tmp_path / "d2.jsonl"
    trace.write_text(line(0, True) + "\n")
    second = subprocess.run([rvc_pg, "check", "-p", props_file(tmp_path), str(trace), "--output", pg.uri,
                             "--spool", str(spool)], capture_output=True, text=True, timeout=60)
    assert second.returncode == 0, second.stderr
    assert not spool.exists()
    first = pg.sql("SELECT run, exit_status, end_reason FROM runs ORDER BY started_at")[0]
    assert (first["exit_status"], first["end_reason"]) == (1, "signal")
    want_verdicts, want_violations = expected(values, "-")
    assert stored(pg, first["run"]) == (want_verdicts, want_violations)


# ---------------------------------------------------------------------------
# C: the database is away until the run ends: the rows wait in the spool,
# and the next run on that spool writes them (once).

def spooled_tables(spool):
    lines = [l for l in spool.read_text().splitlines() if l.strip()]
    assert lines[0] == '{"rvc_spool":1}', lines[:1]  # rvc's own spool: its header first
    return [json.loads(l)["table"] for l in lines[1:]]


@pytest.mark.parametrize("away", ["from_the_start", "after_the_start"])
def test_c_spool_until_the_next_run(rvc_pg, pg, tmp_path, away):
    props = props_file(tmp_path)
    spool = tmp_path / "c.spool"
    values1 = [True] * 5  # holds: exit status 5 (a violation would outrank it)
    if away == "from_the_start":
        pg.stop()
        trace1 = tmp_path / "c1.jsonl"
        trace1.write_text("".join(line(i, a) + "\n" for i, a in enumerate(values1)))
        input1 = str(trace1)
        first = subprocess.run([rvc_pg, "check", "-p", props, input1, "--output", pg.uri, "--db-wait", "1",
                                "--spool", str(spool)], capture_output=True, text=True, timeout=30)
        rc, stderr = first.returncode, first.stderr
    else:
        input1 = "-"
        proc = subprocess.Popen([rvc_pg, "check", "-p", props, "-", "--output", pg.uri, "--db-wait", "1",
                                 "--spool", str(spool)],
                                stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        try:
            wait_until(lambda: rows_in(pg, "runs") == 1, 10, "the run's row")
            pg.stop()
            _, stderr = proc.communicate("".join(line(i, a) + "\n" for i, a in enumerate(values1)), timeout=30)
            rc = proc.returncode
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    assert rc == 5, stderr  # runtime failure: results not all written
    assert "did not come back" in stderr and str(spool) in stderr, stderr
    tables = spooled_tables(spool)
    assert tables.count("verdict") == 2 and tables.count("run_end") == 1, tables
    if away == "from_the_start":
        assert tables.count("run") == 1 and tables.count("property") == 2, tables

    pg.start()
    trace2 = tmp_path / "c2.jsonl"
    values2 = [True, False, True]
    trace2.write_text("".join(line(i, a) + "\n" for i, a in enumerate(values2)))
    second = subprocess.run([rvc_pg, "check", "-p", props, str(trace2), "--output", pg.uri, "--spool", str(spool)],
                            capture_output=True, text=True, timeout=30)
    assert second.returncode == 1, second.stderr
    assert not spool.exists()

    runs = pg.sql("SELECT run, inputs, end_reason FROM runs ORDER BY started_at")
    assert [json.loads(r["inputs"]) for r in runs] == [[input1], [str(trace2)]]
    assert all(r["end_reason"] == "end of input" for r in runs)
    for r, values, name in ((runs[0], values1, input1), (runs[1], values2, str(trace2))):
        assert stored(pg, r["run"]) == expected(values, name)
    assert len(pg.sql("SELECT * FROM properties")) == 4
    # Exactly the rows of the two runs: nothing written twice.
    assert pg.sql("SELECT count(*) AS n FROM verdicts")[0]["n"] == 2 + 5
    assert pg.sql("SELECT count(*) AS n FROM violations")[0]["n"] == 0 + 2


def test_script_serves_a_unix_socket_only(pg):
    """postgres-test.sh's promises: no TCP port; start again is a no-op."""
    assert pg.sql("SELECT current_setting('listen_addresses') AS l")[0]["l"] == ""
    uri = pg.uri
    assert pg.start() == uri
