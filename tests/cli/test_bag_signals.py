"""SIGINT/SIGTERM end `rvc check BAG` and `rvc monitor --input mcap:BAG` as they end a JSON-lines run:
reading stops where it is, what was read is checked, the counters add up, a results database gets
its rows and the run's end (reason `signal`), and the status is 6 (the bag was not read to its end).

The signal is made to land while the bag is being read, without timing: the verdicts (`--all`, one
line per message) go to a pipe the test does not read, so rvc blocks on it long before the bag ends.
"""
import json
import signal
import sqlite3
import subprocess
import time

import pytest

from conftest import transports_built
from test_mcap_hostile import json_bag

pytestmark = pytest.mark.needs_rust  # every test here reads a bag

MESSAGES = 20_000  # ~45 bytes of verdict each: far more than a pipe's 64 KiB buffer


@pytest.fixture
def mcap_rvc(rvc):
    if "zenoh" not in transports_built(rvc):  # the MCAP reader lives in the Rust library
        pytest.fail("this rvc was built without its Rust library (RVC_WITH_ZENOH=OFF): no MCAP")
    return rvc


def stopped_run(args, sig):
    p = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(1.0)  # let it fill the pipe and block (only a sync point: nothing is asserted on time)
    assert p.poll() is None, "rvc ended before the signal: the bag was read whole"
    p.send_signal(sig)
    out, err = p.communicate(timeout=60)
    return p.returncode, out, err


def counters(stderr):
    lines = [json.loads(l) for l in stderr.splitlines() if l.startswith("{")]
    assert lines, stderr
    return lines[-1]


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_check_of_a_bag_ends_cleanly_on_a_stop_signal(mcap_rvc, tmp_path, sig):
    bag = json_bag(tmp_path / "b.mcap", [{"p": True}] * MESSAGES)
    db = tmp_path / "r.db"
    code, out, err = stopped_run([mcap_rvc, "check", "--all", "--stats", "--spec", "{p}", str(bag),
                                  "-o", f"sqlite:{db}"], sig)
    assert code == 6, err  # not a pass: the bag was cut; no property was violated
    assert "stopped by a signal" in err and "was not read to its end" in err, err
    c = counters(err)
    verdicts = out.splitlines()
    assert 0 < c["checked"] < MESSAGES, c
    assert c["received"] == c["checked"] + c["rejected"] + sum(c["dropped"].values()), c
    assert len(verdicts) == c["checked"]  # --all: one verdict per checked message, every one written
    with sqlite3.connect(db) as con:
        ended, status, reason = con.execute("SELECT ended_at IS NOT NULL, exit_status, end_reason FROM runs").fetchone()
        stored = con.execute("SELECT count(*) FROM verdicts").fetchone()[0]
    assert ended and status == 6 and reason == "signal"
    assert stored == 1  # changes only in the database: the one verdict, true, written before the end


def test_monitor_of_a_bag_ends_cleanly_on_a_stop_signal(mcap_rvc, tmp_path):
    bag = json_bag(tmp_path / "b.mcap", [{"p": True}] * MESSAGES)
    code, out, err = stopped_run([mcap_rvc, "monitor", "--all", "--spec", "{p}", "--input", f"mcap:{bag}",
                                  "--output", "-"], signal.SIGTERM)
    assert code == 6, err
    assert "stopped by a signal" in err, err
    c = counters(err)
    assert 0 < c["checked"] < MESSAGES and len(out.splitlines()) == c["checked"], c
