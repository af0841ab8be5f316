"""How `rvc monitor` ends when the stream does not end properly: a publisher
that never comes or dies before its end-of-stream marker is not a pass
(exit 6), an idle monitor still reports its counters, and an output that
cannot be written ends the run (exit 5) instead of hanging or losing verdicts
silently. DDS on loopback, each test on its own domain."""
import json
import os
import signal
import subprocess
import time

import pytest

from conftest import transports_built

_domain = [150 + (os.getpid() % 20) * 3]


def domain():
    _domain[0] += 1
    return str(_domain[0] % 230)


def stats_lines(stderr):
    return [json.loads(l) for l in stderr.splitlines() if l.startswith("{")]


@pytest.fixture
def dds(rvc):
    if "dds" not in transports_built(rvc):
        pytest.fail("this rvc was built without the DDS transport")
    return ["--domain", domain()]


def test_publisher_that_never_comes_ends_by_idle_timeout(rvc, dds, tmp_path):
    r = subprocess.run([rvc, "monitor", "--spec", "{p}", "--input", "dds:/rvc_test/nobody", "--exit-on-eos",
                        "--idle-timeout", "1", "--output", f"file:{tmp_path / 'v'}", *dds],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 6, r.stderr
    assert "nothing was received" in r.stderr
    assert stats_lines(r.stderr)[-1]["received"] == 0


def test_signal_before_end_of_stream_is_incomplete(rvc, dds, tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"p":true}\n' * 5)
    mon = subprocess.Popen([rvc, "monitor", "--spec", "{p}", "--input", "dds:/rvc_test/in", "--exit-on-eos",
                            "--output", f"file:{tmp_path / 'v'}", *dds], stderr=subprocess.PIPE, text=True)
    rep = subprocess.run([rvc, "replay", str(trace), "--to", "dds:/rvc_test/in", "--no-eos", "--wait-timeout", "20",
                          *dds], capture_output=True, text=True, timeout=60)
    assert rep.returncode == 0, rep.stderr
    time.sleep(1)
    mon.send_signal(signal.SIGTERM)
    _, err = mon.communicate(timeout=30)
    assert mon.returncode == 6, err
    assert "before the publisher's end-of-stream marker" in err
    assert stats_lines(err)[-1]["checked"] == 5


def test_idle_monitor_prints_counters(rvc, dds, tmp_path):
    mon = subprocess.Popen([rvc, "monitor", "--spec", "{p}", "--input", "dds:/rvc_test/quiet", "--stats-interval",
                            "0.3", "--output", f"file:{tmp_path / 'v'}", *dds], stderr=subprocess.PIPE, text=True)
    time.sleep(2)
    mon.send_signal(signal.SIGUSR1)
    time.sleep(0.5)
    mon.send_signal(signal.SIGTERM)
    _, err = mon.communicate(timeout=30)
    # At least 3 scheduled lines in 2.5 s of silence, plus the final one.
    assert len(stats_lines(err)) >= 4, err
    assert mon.returncode == 6  # stopped with nothing received


def test_unwritable_output_ends_the_run(rvc, dds, tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"p":true}\n' * 4000)  # holds: exit 1 would mask exit 5
    mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", "{p}", "--input", "dds:/rvc_test/in",
                            "--exit-on-eos", "--output", "file:/dev/full", *dds], stderr=subprocess.PIPE, text=True)
    rep = subprocess.run([rvc, "replay", str(trace), "--to", "dds:/rvc_test/in", "--wait-timeout", "20", *dds],
                         capture_output=True, text=True, timeout=60)
    _, err = mon.communicate(timeout=60)
    assert mon.returncode == 5, err
    assert "/dev/full" in err
    assert rep.returncode == 0, rep.stderr
