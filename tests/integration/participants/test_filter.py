"""The filter in front of the monitor, over Zenoh with an independent
publisher (the eclipse-zenoh Python binding): one wildcard subscription,
--allow/--deny by each sample's own key, --project, and --forward (the
ROSMonitoring filter action) to a key a Python subscriber reads.
Oracle: the messages the test sent, selected by hand, and `rvc check` on
exactly those. Loopback only (tcp/127.0.0.1, multicast scouting off).
"""
import json
import subprocess
import threading
import time

from test_python_peers import HANG_GUARD, ZenohNet, wait_for, zenoh_mod, zsession  # noqa: F401 (fixture)


def test_allow_deny_project_and_forward_over_zenoh(rvc, tmp_path, zenoh_mod):
    zenoh = zenoh_mod
    net = ZenohNet(rvc, False)
    out = tmp_path / "v.jsonl"
    sent = []  # (key, message)
    for i in range(30):
        key = ["rvc/flt/a/status", "rvc/flt/b/status", "rvc/flt/a/debug", "rvc/flt/c/status"][i % 4]
        sent.append((key, {"time": i, "ok": i % 7 != 3, "noise": "x" * (i % 5), "pose": {"x": i, "y": -i}}))
    # --allow 'rvc/flt/*/status' --deny 'rvc/flt/b/**': keys a and c, status only.
    admitted = [m for k, m in sent if k in ("rvc/flt/a/status", "rvc/flt/c/status")]
    projected = [{"time": m["time"], "ok": m["ok"], "pose": {"x": m["pose"]["x"]}} for m in admitted]
    mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", "{ok}", "--input", "zenoh:rvc/flt/**",
                            "--allow", "rvc/flt/*/status", "--deny", "rvc/flt/b/**", "--project", "time,ok,pose.x",
                            "--forward", "p1", "--forward-to", "zenoh:rvc/passed", "--output", f"file:{out}",
                            *net.monitor], stderr=subprocess.PIPE, text=True)
    forwarded, lock = [], threading.Lock()
    try:
        time.sleep(0.3)
        s = zsession(zenoh, **net.py)

        def on_forward(sample):
            att = sample.attachment
            if att is not None and len(att.to_bytes()) >= 9 and att.to_bytes()[8] & 1:
                return  # end-of-stream marker
            with lock:
                forwarded.append(json.loads(sample.payload.to_bytes()))

        sub = s.declare_subscriber("rvc/passed", on_forward)
        pubs = {k: s.declare_publisher(k) for k in {k for k, _ in sent}}
        for p in pubs.values():
            wait_for(lambda: bool(getattr(p.matching_status, "matching", False)), "rvc monitor to match")
        for key, m in sent:
            pubs[key].put(json.dumps(m))
        wait_for(lambda: out.exists() and len(out.read_text().splitlines()) == len(admitted), "verdicts")
        time.sleep(0.3)  # forwarded samples travel after their verdicts
        mon.terminate()
        _, err = mon.communicate(timeout=HANG_GUARD)
        stats = json.loads(err.strip().splitlines()[-1])
        assert stats["received"] == len(sent)
        assert stats["filtered"] == len(sent) - len(admitted)
        assert stats["checked"] == len(admitted)
        # The verdicts are those of `rvc check` on the projected admitted messages.
        trace = tmp_path / "admitted.jsonl"
        trace.write_text("".join(json.dumps(m) + "\n" for m in projected))
        oracle = subprocess.run([rvc, "check", "--all", "--spec", "{ok}", str(trace)], capture_output=True, text=True)
        assert out.read_text() == oracle.stdout
        # Forwarded: the projected messages that keep {ok} true, in order.
        expected = [m for m in projected if m["ok"]]
        with lock:
            assert forwarded == expected
        assert stats["forwarded"] == len(expected) and stats["held_back"] == len(projected) - len(expected)
        sub.undeclare()
        s.close()
    finally:
        if mon.poll() is None:
            mon.kill()
        net.close()


def test_filter_usage_errors(rvc, tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"ok":true}\n')
    cases = [
        (["--forward", "p9"], "--forward p9: no property of that name (the properties: p1)"),
        (["--allow", ""], "--allow/--deny: empty key pattern"),
        (["--project", "a..b"], "--project 'a..b': empty field name"),
        (["--forward", "p1", "--forward-to", f"file:{trace}"], "refusing to monitor its own output"),
    ]
    for extra, message in cases:
        r = subprocess.run([rvc, "monitor", "--spec", "{ok}", "--input", f"file:{trace}", *extra],
                           capture_output=True, text=True, timeout=HANG_GUARD)
        assert r.returncode == 2, (extra, r.stderr)
        assert message in r.stderr, (extra, r.stderr)
