"""`rvc replay` to files and stdout: stop signals, where its summary goes,
write errors. Expected counts are read from what was actually written."""
import json
import signal
import subprocess
import time


def trace(tmp_path, n):
    p = tmp_path / "t.jsonl"
    p.write_text("".join('{"i":%d}\n' % i for i in range(n)))
    return p


def test_stop_signal_during_a_rate_wait_sends_nothing_more(rvc, tmp_path):
    out = tmp_path / "out.jsonl"
    # 2 messages/s: message k is due at k/2 s; the signal comes during a wait.
    rep = subprocess.Popen([rvc, "replay", str(trace(tmp_path, 100)), "--to", f"file:{out}", "--rate", "2",
                            "--wait-subscribers", "0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(1.2)
    t0 = time.monotonic()
    rep.send_signal(signal.SIGINT)
    stdout, stderr = rep.communicate(timeout=30)
    assert time.monotonic() - t0 < 5  # not after the next rate slot
    summary = json.loads(stdout.strip().splitlines()[-1])
    lines = out.read_text().splitlines()
    assert len(lines) == summary["sent"] and 1 <= summary["sent"] <= 4, (lines, summary)
    assert lines == ['{"i":%d}' % i for i in range(summary["sent"])]
    assert rep.returncode == 6 and "incomplete" in stderr


def test_summary_goes_to_stderr_when_data_goes_to_stdout(rvc, tmp_path):
    t = trace(tmp_path, 5)
    r = subprocess.run([rvc, "replay", str(t), "--to", "-", "--wait-subscribers", "0"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 0, r.stderr
    assert r.stdout == t.read_text()
    assert json.loads([l for l in r.stderr.splitlines() if l.startswith("{")][-1])["sent"] == 5


def test_write_errors_exit_5(rvc, tmp_path):
    r = subprocess.run([rvc, "replay", str(trace(tmp_path, 50000)), "--to", "file:/dev/full",
                        "--wait-subscribers", "0"], capture_output=True, text=True, timeout=30)
    assert r.returncode == 5 and "/dev/full" in r.stderr, r.stderr
    t = trace(tmp_path, 3)
    r = subprocess.run([rvc, "check", "--spec", "{i >= 0}", str(t), "-o", "/dev/full"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 5 and "/dev/full" in r.stderr, r.stderr
