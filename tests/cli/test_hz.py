"""rvc hz on files with --time-source stamps: the statistics run on the messages' own times, so
Python recomputes them exactly from the same stamps (the oracle: statistics.pstdev, min, max, the
rate as topic_state_monitor defines it: (n - 1) / (last - first) over the last window_size arrivals)
and the topic_state_monitor states from the same thresholds. Also the YAML configuration, the
DiagnosticArray written as JSON lines, bad files and options, and counts that add up."""
import json
import random
import statistics
import subprocess

import pytest

from conftest import transports_built

WINDOW = 7


def write_topic(path, n, start, period, seed, stamp=True):
    rnd = random.Random(seed)
    rows, t = [], start
    for _ in range(n):
        # Stamps with at most 9 decimals, as real ones have: rvc reads them to the nanosecond, exactly
        # the double Python reads (longer random floats would be rounded to the nanosecond first).
        t = round(t + period + rnd.uniform(-period / 10, period / 10), 9)
        row = {"time": t}
        if stamp:
            row["stamp"] = round(t - rnd.uniform(0.001, 0.05), 9)
        rows.append(row)
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
    return rows


def expected(rows, now, window=WINDOW, warn=0.0, error=0.0, timeout=1.0):
    """What rvc hz must report for these arrivals at time `now` (all of rows arrived by then)."""
    win = rows[-window:]
    times = [r["time"] for r in win]
    iv = [b - a for a, b in zip(times, times[1:])]
    rate = (len(times) - 1) / (times[-1] - times[0])
    lat = [r["time"] - r["stamp"] for r in win if "stamp" in r]
    if now - times[-1] > timeout > 0:
        state = "Timeout"
    elif error > 0 and rate < error:
        state = "ErrorRate"
    elif warn > 0 and rate < warn:
        state = "WarnRate"
    else:
        state = "OK"
    return {"rate_hz": rate, "interval_mean_s": statistics.fmean(iv), "interval_std_s": statistics.pstdev(iv),
            "interval_min_s": min(iv), "interval_max_s": max(iv), "silence_s": now - times[-1],
            "latency_mean_s": statistics.fmean(lat) if lat else None, "latency_max_s": max(lat) if lat else None,
            "window": len(win), "state": state}


def compare(got, want):
    for key, value in want.items():
        if isinstance(value, float):
            assert got[key] == pytest.approx(value, rel=1e-9, abs=1e-12), key
        else:
            assert got[key] == value, key


def run(rvc, *args, timeout=60):
    return subprocess.run([rvc, "hz", *args], capture_output=True, text=True, timeout=timeout)


def test_periodic_reports_match_python_on_the_same_stamps(rvc, tmp_path):
    rows = write_topic(tmp_path / "a.jsonl", 120, 1000.0, 0.1, seed=1)
    r = run(rvc, f"file:{tmp_path / 'a.jsonl'}", "--time-source", "stamps", "--stamp-field", "stamp", "--json",
            "--period", "1", "--window", str(WINDOW), "--warn-rate", "9.9", "--error-rate", "5")
    assert r.returncode == 0, r.stderr
    reports = [json.loads(line) for line in r.stdout.splitlines()]
    periodic, final = reports[:-1], reports[-1]
    # A report falls on each period boundary of the stamps, before the first message at or past it.
    first = rows[0]["time"]
    boundaries = []
    b = first + 1
    while b <= rows[-1]["time"]:
        boundaries.append(b)
        b += 1
    assert [p["t"] for p in periodic] == pytest.approx(boundaries, rel=0, abs=1e-9)
    assert len(periodic) >= 10
    states = set()
    for p in periodic:
        seen = [row for row in rows if row["time"] < p["t"]]
        want = expected(seen, p["t"], warn=9.9, error=5)
        compare(p, want)
        assert p["received"] == p["checked"] == len(seen) and p["rejected"] == 0
        states.add(p["state"])
    assert final["final"] is True and final["received"] == 120
    compare(final, expected(rows, rows[-1]["time"], warn=9.9, error=5))
    assert states == {"OK", "WarnRate"}  # the thresholds sit inside the jitter: both states occur
    assert "received 120 (checked 120, rejected 0), final state" in r.stderr


def test_two_files_merged_by_time_and_a_stopped_topic_times_out(rvc, tmp_path):
    a = write_topic(tmp_path / "a.jsonl", 60, 0.0, 0.1, seed=2)  # until ~6 s
    b = write_topic(tmp_path / "b.jsonl", 20, 0.0, 0.1, seed=3)  # stops at ~2 s
    ua, ub = f"file:{tmp_path / 'a.jsonl'}", f"file:{tmp_path / 'b.jsonl'}"
    diag = tmp_path / "diag.jsonl"
    r = run(rvc, ua, ub, "--time-source", "stamps", "--stamp-field", "stamp", "--json", "--window", str(WINDOW),
            "--timeout", "0.5", "--diagnostics", f"file:{diag}")
    assert r.returncode == 1, r.stderr  # a topic ended in an ERROR state
    reports = [json.loads(line) for line in r.stdout.splitlines()]
    # Files are merged by time: every periodic report is exact for both topics.
    start = min(a[0]["time"], b[0]["time"])
    periodic = [p for p in reports if not p["final"]]
    assert len(periodic) == 2 * 5
    for p in periodic:
        rows = a if p["topic"] == ua else b
        seen = [row for row in rows if row["time"] < p["t"]]
        compare(p, expected(seen, p["t"], timeout=0.5))
        assert (p["t"] - start) == pytest.approx(round(p["t"] - start), abs=1e-9)
    final = {o["topic"]: o for o in reports if o["final"]}
    now = a[-1]["time"]
    compare(final[ua], expected(a, now, timeout=0.5))
    compare(final[ub], expected(b, now, timeout=0.5))
    assert (final[ub]["state"], final[ub]["level"]) == ("Timeout", "ERROR")
    # The last DiagnosticArray: one status per topic, levels as topic_state_monitor's.
    arrays = [json.loads(line) for line in diag.read_text().splitlines()]
    last = arrays[-1]
    by_name = {s["name"]: s for s in last["status"]}
    sa, sb = by_name[f"rvc hz: {ua}"], by_name[f"rvc hz: {ub}"]
    assert (sa["level"], sb["level"]) == (0, 2)
    values = {v["key"]: v["value"] for v in sb["values"]}
    assert values["status"] == "Timeout" and values["received"] == "20" and values["window_size"] == str(WINDOW)
    assert float(values["rate_hz"]) == pytest.approx(expected(b, now)["rate_hz"], rel=1e-12)
    assert last["header"]["stamp"]["sec"] == int(now)
    # b turned Timeout at the first instant rvc hz looked after its deadline (a message of a, or a
    # report boundary), published then, not at the end.
    deadline = b[-1]["time"] + 0.5
    boundaries = [start + k for k in range(1, 10) if start + k <= now]
    first_look = min(t for t in [row["time"] for row in a] + boundaries if t > deadline)
    timeouts = [x for x in arrays if any(s["name"] == sb["name"] and s["message"].startswith("Timeout")
                                         for s in x["status"])]
    stamp = timeouts[0]["header"]["stamp"]
    assert stamp["sec"] + stamp["nanosec"] * 1e-9 == pytest.approx(first_look, abs=2e-9)
    assert stamp["sec"] + stamp["nanosec"] * 1e-9 < now


def test_yaml_thresholds_per_topic_and_defaults(rvc, tmp_path):
    rows = write_topic(tmp_path / "a.jsonl", 40, 0.0, 0.1, seed=4)
    write_topic(tmp_path / "b.jsonl", 40, 0.0, 0.1, seed=5)
    cfg = tmp_path / "hz.yaml"
    cfg.write_text(f"warn_rate: 20\nwindow_size: 5\ntopics:\n"
                   f"  - topic: file:{tmp_path / 'a.jsonl'}\n"
                   f"  - topic: file:{tmp_path / 'b.jsonl'}\n    warn_rate: 2\n    window_size: 4\n")
    r = run(rvc, "--config", str(cfg), "--time-source", "stamps", "--json", "--timeout", "0")
    assert r.returncode == 0, r.stderr  # WarnRate is a WARN: not a failed run
    final = {o["topic"]: o for o in map(json.loads, r.stdout.splitlines()) if o["final"]}
    a = final[f"file:{tmp_path / 'a.jsonl'}"]
    b = final[f"file:{tmp_path / 'b.jsonl'}"]
    assert (a["state"], a["window"]) == ("WarnRate", 5)
    assert (b["state"], b["window"]) == ("OK", 4)
    assert a["rate_hz"] == pytest.approx(4 / (rows[-1]["time"] - rows[-5]["time"]), rel=1e-12)
    # JSON time without --stamp-field is the arrival here: no latency asked for.
    assert a["latency_samples"] == 0 and a["latency_mean_s"] is None


def test_counts_add_up_with_refused_messages(rvc, tmp_path):
    f = tmp_path / "a.jsonl"
    f.write_text('{"time": 1.0}\n{"x": 1}\nnot json\n{"time": 0.5}\n{"time": 1.5}\n{"time": "2"}\n{"time": 2.0}\n')
    r = run(rvc, f"file:{f}", "--time-source", "stamps", "--json", "--timeout", "0")
    assert r.returncode == 3, r.stderr
    final = json.loads(r.stdout.splitlines()[-1])
    assert (final["received"], final["checked"], final["rejected"]) == (7, 3, 4)
    assert final["received"] == final["checked"] + final["rejected"]
    assert "before the previous message's" in r.stderr
    assert final["rate_hz"] == pytest.approx(2 / 1.0)


def test_explicit_stamp_field_is_required(rvc, tmp_path):
    f = tmp_path / "a.jsonl"
    f.write_text('{"time": 1.0, "stamp": 0.9}\n{"time": 2.0}\n{"time": 3.0, "stamp": 2.5}\n')
    r = run(rvc, f"file:{f}", "--time-source", "stamps", "--stamp-field", "stamp", "--json", "--timeout", "0")
    assert r.returncode == 3
    final = json.loads(r.stdout.splitlines()[-1])
    assert (final["checked"], final["rejected"], final["latency_samples"]) == (2, 1, 2)
    assert final["latency_mean_s"] == pytest.approx((0.1 + 0.5) / 2)
    assert 'no field "stamp"' in r.stderr


def test_every_message_refused_is_not_success(rvc, tmp_path):
    f = tmp_path / "a.jsonl"
    f.write_text('{"x": 1}\n{"x": 2}\n')
    r = run(rvc, f"file:{f}", "--time-source", "stamps", "--json")
    assert r.returncode == 6, r.stderr
    assert "every message was refused" in r.stderr and "received 2 (checked 0, rejected 2)" in r.stderr


def test_nothing_received_is_not_success(rvc, tmp_path):
    f = tmp_path / "empty.jsonl"
    f.write_text("")
    r = run(rvc, f"file:{f}", "--time-source", "stamps")
    assert r.returncode == 6
    assert "nothing was received" in r.stderr and "final state NotReceived" in r.stderr


@pytest.mark.parametrize("text,needle", [
    ("topics: [{topic: file:x, warn_rate: -1}]", "warn_rate must be a number from 0"),
    ("topics: [{topic: file:x, window_size: 1}]", "window_size must be a whole number"),
    ("topics: [{topic: file:x, timeout: 1e9}]", "timeout must be a number from 0 (off) to 604800"),
    ("error_rate: .nan\ntopics: [file:x]", "error_rate must be a number"),
    ("topics: [{topic: file:x, window_size: 2.5}]", "window_size must be a whole number"),
    ("topics: [{topic: file:x, warn_rte: 1}]", "unknown key 'warn_rte'"),
    ("warn_rate: fast\ntopics: [file:x]", "warn_rate must be a number"),
    ("tpoics: [file:x]", "unknown key 'tpoics'"),
    ("- file:x", "expected a map"),
    ("topics: [file:x, file:x]", "listed twice"),
    ("topics: [{warn_rate: 1}]", "without 'topic: URI'"),
    ("topics: [{topic: file:x\n", "hz.yaml:2:1: end of map flow not found"),
])
def test_bad_yaml_is_named(rvc, tmp_path, text, needle):
    cfg = tmp_path / "hz.yaml"
    cfg.write_text(text)
    r = run(rvc, "--config", str(cfg))
    assert r.returncode == 2, r.stderr
    assert needle in r.stderr
    assert "hz.yaml" in r.stderr or needle.startswith("--")


@pytest.mark.parametrize("uri,args,needle", [
    ("file", ["--window", "1"], "--window: '1' is out of range (allowed: 2 to"),
    ("file", ["--time-source", "wall"], "--time-source: wall not in {receive,stamps}"),
    ("file", ["--warn-rate", "-2"], "--warn-rate: '-2' is out of range"),
    ("file", ["--period", "0"], "--period: '0' is out of range"),
    ("file", ["--timeout", "nan"], "--timeout: 'nan' is out of range"),
    ("file", ["--duration", "-1"], "--duration: '-1' is out of range"),
    (None, [], "no topic to watch"),
    ("file", ["--type", "std_msgs/msg/Header"], "applies to dds: and zenoh: topics"),
    # No network is opened: types and fields are checked first.
    ("dds:/rvc_hz/never", ["--type", "std_msgs/msg/Nope"], "unknown message type"),
    ("dds:/rvc_hz/never", ["--type", "std_msgs/msg/Header", "--stamp-field", "nope"],
     "stamp field 'nope' is no number or builtin_interfaces/Time field of std_msgs/msg/Header (its fields: stamp"),
])
def test_bad_options_are_named(rvc, tmp_path, uri, args, needle):
    f = tmp_path / "a.jsonl"
    f.write_text('{"time": 1}\n')
    if uri and uri.startswith("dds:") and "dds" not in transports_built(rvc):
        pytest.skip("rvc built without DDS")
    r = run(rvc, *([f"file:{f}"] if uri == "file" else [uri] if uri else []), *args)
    assert r.returncode == 2, (r.stdout, r.stderr)
    assert needle in r.stderr


def test_count_ends_a_run_reading_ahead(rvc, tmp_path):
    # 20,000 lines: the reading thread fills the queue long before --count is reached; the run must
    # still end (the queue is closed before the sources are stopped) with exactly N counted.
    f = tmp_path / "big.jsonl"
    f.write_text("".join('{"time": %r}\n' % (i * 0.01) for i in range(20000)))
    r = run(rvc, f"file:{f}", "--time-source", "stamps", "--count", "5", "--json", timeout=30)
    assert r.returncode == 0, r.stderr
    final = json.loads(r.stdout.splitlines()[-1])
    assert (final["received"], final["window"]) == (5, 5)
    assert final["rate_hz"] == pytest.approx(4 / 0.04)


def test_sigint_flushes_the_final_report(rvc):
    # stdin stays open (a live pipe): only the signal ends the run, with the final report and counts.
    import signal
    import time
    p = subprocess.Popen([rvc, "hz", "-", "--json", "--period", "0.1", "--timeout", "0", "--stamp-field", "none"],
                         stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        p.stdin.write('{"a": 1}\n{"a": 2}\n{"a": 3}\n')
        p.stdin.flush()
        seen = 0
        deadline = time.time() + 30  # a guard, not a measurement
        while seen < 3 and time.time() < deadline:
            line = p.stdout.readline()
            if line:
                seen = json.loads(line)["received"]
        assert seen == 3
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=30)
    finally:
        if p.poll() is None:
            p.kill()
    final = [json.loads(l) for l in out.splitlines() if '"final":true' in l]
    assert len(final) == 1 and final[0]["received"] == 3 and final[0]["state"] == "OK"
    assert "rvc hz: -: received 3 (checked 3, rejected 0), final state OK" in err
    assert p.returncode == 0


def test_plain_text_payloads_are_counted_without_latency(rvc, tmp_path):
    # Receive time: a String topic's text (no JSON) still arrives; only an asked-for stamp refuses it.
    f = tmp_path / "text.jsonl"
    f.write_text("hello 1\nhello 2\n{\"time\": 5}\n")
    r = run(rvc, f"file:{f}", "--json", "--timeout", "0")
    assert r.returncode == 0, r.stderr
    final = json.loads(r.stdout.splitlines()[-1])
    assert (final["received"], final["checked"], final["rejected"]) == (3, 3, 0)
    assert final["latency_samples"] == 1  # the one message with a "time"
    r = run(rvc, f"file:{f}", "--json", "--timeout", "0", "--stamp-field", "time")
    assert r.returncode == 3
    final = json.loads(r.stdout.splitlines()[-1])
    assert (final["received"], final["checked"], final["rejected"]) == (3, 1, 2)


def test_a_stamp_jump_is_one_report_and_one_line(rvc, tmp_path):
    """--time-source stamps, a jump of 1e9 s (a simulator reset) after 1 s of messages: the reports at
    1 and 2 (the state before the jump), one line saying the stamps jumped and by how much, then the
    reports of the new stamps' boundaries and the final one. Before: one report per period boundary
    of the 1e9 s, ~1e9 lines, never ending (a bounded harness timeout here)."""
    f = tmp_path / "jump.jsonl"
    times = [0, 0.5, 1.0, 1e9 + 1.0, 1e9 + 1.5, 1e9 + 2.6]
    f.write_text("".join(json.dumps({"time": t}) + "\n" for t in times))
    r = run(rvc, f"file:{f}", "--time-source", "stamps", "--json", "--timeout", "0", timeout=30)
    assert r.returncode == 0, r.stderr
    reports = [json.loads(line) for line in r.stdout.splitlines()]
    # boundary 1 (before the message at 1.0), the jump's one report at 2, then the new stamps'
    # boundary 1e9 + 2 (before the message at 1e9 + 2.6), and the final report
    assert [p["t"] for p in reports] == [1, 2, 1e9 + 2, 1e9 + 2.6]
    assert [p["received"] for p in reports] == [2, 3, 5, 6]
    assert reports[-1]["final"] is True
    jumped = [line for line in r.stderr.splitlines() if "jumped" in line]
    assert jumped == [f"rvc hz: file:{f}: the stamps jumped by 1e+09 s (from 1 to 1000000001): the reports of the "
                      "999999999 periods in between are skipped"]


def test_a_gap_of_a_few_periods_still_reports_each_period(rvc, tmp_path):
    f = tmp_path / "gap.jsonl"
    f.write_text("".join(json.dumps({"time": t}) + "\n" for t in [0, 0.5, 5.5]))
    r = run(rvc, f"file:{f}", "--time-source", "stamps", "--json", timeout=30)
    reports = [json.loads(line) for line in r.stdout.splitlines()]
    assert [p["t"] for p in reports] == [1, 2, 3, 4, 5, 5.5]
    assert [p["state"] for p in reports[:3]] == ["OK", "Timeout", "Timeout"]  # silence past the 1 s timeout
    assert "jumped" not in r.stderr


BAGS = __import__("pathlib").Path(__file__).resolve().parent.parent / "data" / "ros2-bags"


@pytest.mark.parametrize("bag,what", [
    (BAGS / "talker_mcap" / "talker.mcap", "is a ROS 2 bag (an MCAP file)"),
    (BAGS / "talker_sqlite3" / "talker.db3", "is a ROS 2 bag (a SQLite database)"),
    (BAGS / "talker_mcap", "is a ROS 2 bag folder"),
])
def test_a_bag_is_refused_not_read_as_lines(rvc, bag, what):
    """Before: the bag's bytes were counted as lines, "received 3353, final state OK", exit 0."""
    for uri in (f"file:{bag}", str(bag)):
        r = run(rvc, uri, "--time-source", "stamps", timeout=30)
        assert r.returncode == 2, r.stderr
        assert f"rvc hz: '{bag}' {what}: rvc hz watches live topics and files of JSON lines" in r.stderr
        assert r.stdout == "" and "received" not in r.stderr


def test_a_gzip_file_is_refused(rvc, tmp_path):
    import gzip
    f = tmp_path / "trace.jsonl.gz"
    f.write_bytes(gzip.compress(b'{"time": 0}\n{"time": 0.1}\n'))
    for extra in ([], ["--time-source", "stamps"]):
        r = run(rvc, f"file:{f}", *extra, "--duration", "5", timeout=30)
        assert r.returncode == 2 and f"rvc hz: '{f}' is a gzip file, not JSON lines" in r.stderr, r.stderr


def test_stamps_beyond_exact_time_are_refused_and_the_run_ends(rvc, tmp_path):
    """1e20 s is past int64 nanoseconds (9223372036.854775807 s): each such stamp is refused by name,
    counted, and the run ends with nothing checked (exit 6). Before exact time such stamps hung the
    report schedule (boundary + period == boundary at a double's 16384 s resolution)."""
    f = tmp_path / "far.jsonl"
    f.write_text("".join(json.dumps({"time": t}) + "\n" for t in [1e20, 1e20 + 65536, 1e20 + 131072]))
    r = run(rvc, f"file:{f}", "--time-source", "stamps", "--json", "--timeout", "0", timeout=30)
    assert r.returncode == 6, r.stderr
    assert r.stderr.count("beyond the range of exact time") == 3, r.stderr
    assert "received 3 (checked 0, rejected 3)" in r.stderr, r.stderr
