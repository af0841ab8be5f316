"""How a live monitor's messages reach its checker (`rvc monitor --handoff`, docs/performance.md
"Inline hand-off"): on a Zenoh input the receive thread checks each message itself (inline, the
default there), elsewhere a queue hands them to the checker's thread.

Oracles: `rvc check` of the same file (the verdicts, one per message with --all) and the replay's
own count (every message received and checked, none lost). Both hand-offs give the same bytes. A
run's end (an output that cannot be written, a signal) and buffered outputs (a file is readable
while the stream runs) work on the inline path too. Zenoh peers on 127.0.0.1 only."""
import json
import os
import signal
import socket
import subprocess
import time

import pytest

from conftest import transports_built


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def stats_lines(stderr):
    return [json.loads(ln) for ln in stderr.splitlines() if ln.startswith("{")]


@pytest.fixture
def zenoh(rvc):
    if "zenoh" not in transports_built(rvc):
        pytest.fail("this rvc was built without the Zenoh transport")
    ep = "tcp/127.0.0.1:%d" % free_port()
    return dict(listen=["--listen", ep, "--no-multicast-scouting"], connect=["--connect", ep, "--no-multicast-scouting"])


def trace(path, n):
    # Values that change (so verdicts change too) and a deadline-bound property over them.
    path.write_text("".join('{"p":%s,"q":%s}\n' % ("true" if i % 7 > 2 else "false", "true" if i % 3 else "false")
                            for i in range(n)))
    return path


SPEC = "historically[0:1]({q} -> once[0:2]{p})"


def run_pair(rvc, zenoh, tmp_path, handoff, n=3000, extra=()):
    src = trace(tmp_path / "t.jsonl", n)
    out = tmp_path / ("v-%s.jsonl" % handoff)
    cmd = [rvc, "monitor", "--all", "--spec", SPEC, "--input", "zenoh:rvc_test/handoff", "--exit-on-eos",
           "--output", "file:%s" % out, *zenoh["listen"], *extra]
    if handoff:
        cmd += ["--handoff", handoff]
    mon = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True)
    rep = subprocess.run([rvc, "replay", str(src), "--to", "zenoh:rvc_test/handoff", "--wait-subscribers", "1",
                          "--wait-timeout", "20", "--no-progress", *zenoh["connect"]],
                         capture_output=True, text=True, timeout=120)
    _, err = mon.communicate(timeout=120)
    assert rep.returncode == 0, rep.stderr
    return mon.returncode, err, out


def test_inline_is_zenohs_default_and_checks_every_message_as_check_does(rvc, zenoh, tmp_path):
    code, err, out = run_pair(rvc, zenoh, tmp_path, None)
    assert code in (0, 1), err
    s = stats_lines(err)[-1]
    assert s["handoff"] == "inline", s
    assert (s["received"], s["checked"], s["rejected"], s["gaps"], s["duplicates"], s["dropped"]) == \
        (3000, 3000, 0, 0, 0, {}), s
    oracle = subprocess.run([rvc, "check", "--all", "--spec", SPEC, str(tmp_path / "t.jsonl")],
                            capture_output=True, text=True, timeout=60)
    want = [json.loads(ln) for ln in oracle.stdout.splitlines()]
    got = [json.loads(ln) for ln in out.read_text().splitlines()]
    # A live input's time is its sequence number (1, 2, ...), a file's its line number: the same here.
    assert [(v["time"], v["value"]) for v in got] == [(v["time"], v["value"]) for v in want]
    assert len(got) == 3000 and {v["value"] for v in got} == {True, False}


def test_queue_and_inline_give_the_same_bytes(rvc, zenoh, tmp_path):
    _, err_q, out_q = run_pair(rvc, zenoh, tmp_path, "queue")
    assert stats_lines(err_q)[-1]["handoff"] == "queue"
    port = free_port()  # a fresh endpoint: the first pair's may linger in TIME_WAIT
    z2 = dict(listen=["--listen", "tcp/127.0.0.1:%d" % port, "--no-multicast-scouting"],
              connect=["--connect", "tcp/127.0.0.1:%d" % port, "--no-multicast-scouting"])
    _, err_i, out_i = run_pair(rvc, z2, tmp_path, "inline")
    assert stats_lines(err_i)[-1]["handoff"] == "inline"
    assert out_q.read_bytes() == out_i.read_bytes() and out_q.stat().st_size > 0


def test_inline_output_that_cannot_be_written_ends_the_run(rvc, zenoh, tmp_path):
    src = trace(tmp_path / "t.jsonl", 4000)
    mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", "{p} or {q} or not {p}", "--input",
                            "zenoh:rvc_test/full", "--exit-on-eos", "--output", "file:/dev/full", "--handoff", "inline",
                            *zenoh["listen"]], stderr=subprocess.PIPE, text=True)
    subprocess.run([rvc, "replay", str(src), "--to", "zenoh:rvc_test/full", "--wait-subscribers", "1",
                    "--wait-timeout", "20", "--no-progress", *zenoh["connect"]],
                   capture_output=True, text=True, timeout=120)
    _, err = mon.communicate(timeout=60)
    assert mon.returncode == 5, err  # a runtime failure, not a pass, not a hang
    assert "rvc: error" in err and "No space left" in err, err


def test_inline_file_output_is_readable_while_the_stream_runs(rvc, zenoh, tmp_path):
    # 40 messages at 20/s: two seconds. Halfway, the verdicts so far are in the file (flushed once
    # the stream pauses, as the queue's checker flushes when its queue is empty), not only at the end.
    src = trace(tmp_path / "t.jsonl", 40)
    out = tmp_path / "v.jsonl"
    mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", "{p}", "--input", "zenoh:rvc_test/slow",
                            "--exit-on-eos", "--output", "file:%s" % out, *zenoh["listen"]],
                           stderr=subprocess.PIPE, text=True)
    rep = subprocess.Popen([rvc, "replay", str(src), "--to", "zenoh:rvc_test/slow", "--rate", "20",
                            "--wait-subscribers", "1", "--wait-timeout", "20", "--no-progress", *zenoh["connect"]],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and not (out.exists() and out.read_text().count("\n") >= 5):
        time.sleep(0.05)
    midway = out.read_text().count("\n") if out.exists() else 0
    assert rep.poll() is None, "the replay ended before the check: no mid-stream look"
    assert 5 <= midway < 40, midway
    rep.communicate(timeout=60)
    _, err = mon.communicate(timeout=60)
    assert stats_lines(err)[-1]["handoff"] == "inline"
    assert out.read_text().count("\n") == 40


def test_inline_monitor_stops_on_a_signal_with_its_counters(rvc, zenoh, tmp_path):
    mon = subprocess.Popen([rvc, "monitor", "--spec", "{p}", "--input", "zenoh:rvc_test/none",
                            "--output", "file:%s" % (tmp_path / "v"), *zenoh["listen"]],
                           stderr=subprocess.PIPE, text=True)
    time.sleep(1.0)
    mon.send_signal(signal.SIGTERM)
    _, err = mon.communicate(timeout=30)
    assert mon.returncode == 6, err  # nothing received: not a pass
    s = stats_lines(err)[-1]
    assert s["handoff"] == "inline" and s["received"] == 0, s


def test_inline_needs_a_zenoh_input(rvc, tmp_path):
    for uri in ("dds:/rvc_test/x", "file:%s" % (tmp_path / "t.jsonl")):
        r = subprocess.run([rvc, "monitor", "--spec", "{p}", "--input", uri, "--handoff", "inline"],
                           capture_output=True, text=True, timeout=30)
        assert r.returncode == 2, r.stderr
        assert "--handoff inline" in r.stderr and "use --handoff queue or auto" in r.stderr, r.stderr
    # A Zenoh input with a DDS /clock: that input's thread would check too.
    r = subprocess.run([rvc, "monitor", "--spec", "{p}", "--input", "zenoh:rvc_test/x", "--clock", "ros=dds:/clock",
                        "--handoff", "inline"], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and "not dds:/clock" in r.stderr, r.stderr
