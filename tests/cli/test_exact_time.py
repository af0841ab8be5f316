"""Dense time exact to the nanosecond (issue 36): epoch stamps, 25 ms apart, bounds read from their
text, verdict times printed as the stamps came in, and the timeline starting at the first message.

Oracles: integer arithmetic written from the definitions below (no double anywhere), and for the
random traces an interval oracle for once[a:b] / historically[a:b] / {@age <= d} over nanosecond
stamps around 1.7e9 s, checked at every window edge."""
import json
import random
import subprocess

import pytest

EPOCH_NS = 1746721937599626818  # a real Autoware stamp (sec 1746721937, nanosec 599626818)


def run(args, stdin=None):
    return subprocess.run(args, capture_output=True, text=True, timeout=120, input=stdin)


def sec_text(ns):
    """Nanoseconds as exact decimal seconds, the way rvc must print them."""
    whole, frac = divmod(ns, 10**9)
    return str(whole) if frac == 0 else f"{whole}.{frac:09d}".rstrip("0")


def jsonl(path, rows):
    """rows: (time_ns, fields) written with the time as exact decimal text."""
    with open(path, "w") as f:
        for ns, fields in rows:
            body = json.dumps(fields)[1:-1]
            f.write('{"time": ' + sec_text(ns) + (", " + body if body else "") + "}\n")
    return str(path)


def verdicts(stdout):
    """(time text, value) of each verdict line, the time as printed (raw JSON text)."""
    out = []
    for line in stdout.splitlines():
        assert line.startswith('{"time":'), line
        t = line[len('{"time":'):line.index(",")]
        out.append((t, json.loads(line)["value"]))
    return out


def test_a_25ms_topic_with_one_real_gap_gives_one_violation_at_its_exact_instant(rvc, tmp_path):
    # 10 s of a 40 Hz topic, exactly 25,000,000 ns apart, message 200 missing: one real gap. As doubles
    # of epoch seconds these stamps are ~240 ns apart from exact, and {@age <= 0.025} fired 42 times.
    rows = [(EPOCH_NS + k * 25_000_000, {"x": 1}) for k in range(400) if k != 200]
    trace = jsonl(tmp_path / "t.jsonl", rows)
    r = run([rvc, "check", "--dense", "--spec", "{@age <= 0.025}", trace])
    assert r.returncode == 1, r.stderr
    got = verdicts(r.stdout)
    gap_start = EPOCH_NS + 199 * 25_000_000 + 25_000_000  # age passes 0.025 s there
    assert got == [(sec_text(EPOCH_NS), True), (sec_text(gap_start), False),
                   (sec_text(EPOCH_NS + 201 * 25_000_000), True)], got
    # Printed exactly: no exponent, at most 9 decimals.
    for t, _ in got:
        assert "e" not in t.lower() and len(t.split(".")[-1]) <= 9, t


def test_timeline_starts_at_the_first_message_and_origin_zero_keeps_reelays_rule(rvc, tmp_path):
    rows = [(EPOCH_NS + k * 100_000_000, {"speed": 3}) for k in range(20)]
    trace = jsonl(tmp_path / "t.jsonl", rows)
    r = run([rvc, "check", "--dense", "--spec", "historically({speed < 1000})", trace])
    assert r.returncode == 0, (r.stdout, r.stderr)  # it holds: nothing is said before the first message
    assert verdicts(r.stdout) == [(sec_text(EPOCH_NS), True)]
    z = run([rvc, "check", "--dense", "--origin", "zero", "--spec", "historically({speed < 1000})", trace])
    assert z.returncode == 1, z.stderr  # Reelay's rule: [0, first stamp) has the field unseen
    assert verdicts(z.stdout)[0] == ("0", False)


def test_json_time_forms_are_read_exactly(rvc, tmp_path):
    # The same instants as decimal seconds, as a Time object, and with an exponent.
    a = tmp_path / "a.jsonl"
    a.write_text('{"time": 1746721937.599626818, "p": true}\n{"time": 1746721937.624626818, "p": false}\n')
    b = tmp_path / "b.jsonl"
    b.write_text('{"time": {"sec": 1746721937, "nanosec": 599626818}, "p": true}\n'
                 '{"time": {"sec": 1746721937, "nanosec": 624626818}, "p": false}\n')
    c = tmp_path / "c.jsonl"
    c.write_text('{"time": 1.746721937599626818e9, "p": true}\n{"time": 174672193762462681.8e-8, "p": false}\n')
    outs = [run([rvc, "check", "--dense", "--spec", "once[0:0.025]{p}", str(f)]) for f in (a, b, c)]
    for o in outs:
        assert o.returncode == 0, o.stderr
        assert verdicts(o.stdout) == [("1746721937.599626818", True)], o.stdout
    assert outs[0].stdout == outs[1].stdout == outs[2].stdout


def test_a_time_beyond_exact_range_is_named_as_such(rvc):
    r = run([rvc, "check", "--dense", "--spec", "{x}", "-"], stdin='{"time": 1e400, "x": 1}\n{"time": 1, "x": 1}\n')
    assert "line 1: time field \"time\" is 1e400 s: beyond the range of exact time" in r.stderr, r.stderr
    assert "not a number" not in r.stderr
    assert r.returncode == 3, r.stderr  # the valid line is checked, the other counted as rejected
    assert "1 messages checked, 1 rejected" in r.stderr or "1 message checked, 1 rejected" in r.stderr, r.stderr


@pytest.mark.parametrize("spec", ["once[0:1e17]{p}", "historically[0:9007200]{p}", "eventually[0:1e308] eventually[0:1e308]{p}",
                                  "{p} since[1:1e16] {q}"])
def test_bounds_the_exact_time_cannot_hold_are_refused_at_their_column(rvc, spec):
    r = run([rvc, "check", "--dense", "--spec", spec, "-"], stdin='{"time": 0, "p": true, "q": true}\n')
    assert r.returncode == 2, (r.stdout, r.stderr)
    assert "9007199.254740992 s" in r.stderr and "^" in r.stderr, r.stderr


def test_nested_horizons_past_the_exact_span_are_refused(rvc):
    r = run([rvc, "check", "--dense", "--spec", "eventually[0:5000000] eventually[0:5000000]{p}", "-"],
            stdin='{"time": 0, "p": true}\n')
    assert r.returncode == 2 and "horizon" in r.stderr, r.stderr


# ---- random nanosecond traces against an exact interval oracle ----

def true_set_once(msgs, a, b, end):
    """once[a:b]{p}: true at t iff p held at some s in [t-b, t-a]. p holds over [t_i, t_i+1) after a
    message with p, and at the last message's instant. As half-open intervals [u + a, v + b)."""
    out = []
    for i, (t, p) in enumerate(msgs):
        if not p:
            continue
        v = msgs[i + 1][0] if i + 1 < len(msgs) else end + 1  # the last instant counts (right-closed end)
        out.append((t + a, v + b))
    return out


def true_set_age(msgs, d, end):
    """{@age <= d}: true over [t_i, t_i + d] ... as right-continuous: [t_i, t_i + d) unless the next
    message comes at or before t_i + d (then it is true up to it and beyond)."""
    out = []
    for i, (t, _) in enumerate(msgs):
        out.append((t, t + d))
    return out


def value_at(intervals, t):
    return any(u <= t < v for u, v in intervals)


def oracle(intervals, t0, end, negate=False):
    points = {t0}
    for u, v in intervals:
        for x in (u, v):
            if t0 <= x <= end:
                points.add(x)
    out = []
    for t in sorted(points):
        val = value_at(intervals, t) != negate
        if not out or out[-1][1] != val:
            out.append((sec_text(t), val))
    return out


def random_bound(rng):
    # Decimal seconds with up to 9 decimals, some exactly on the message grid.
    return rng.choice([25_000_000, 50_000_000, 1_000_000_000, rng.randrange(1, 2_000_000_000),
                       rng.randrange(1, 200) * 1_000_000, rng.randrange(1, 10**9)])


@pytest.mark.parametrize("seed", range(12))
def test_random_nanosecond_traces_match_the_exact_oracle(rvc, tmp_path, seed):
    rng = random.Random(seed)
    t = EPOCH_NS + rng.randrange(0, 10**9)
    msgs = []
    for _ in range(rng.randrange(5, 60)):
        msgs.append((t, rng.random() < 0.5))
        # Gaps on and off the 25 ms grid, a few single nanoseconds.
        t += rng.choice([25_000_000, 25_000_000, 50_000_000, 1, rng.randrange(1, 80_000_000)])
    end = msgs[-1][0]
    trace = jsonl(tmp_path / "t.jsonl", [(ns, {"p": p}) for ns, p in msgs])
    a = rng.choice([0, 0, random_bound(rng)])
    b = a + random_bound(rng)
    d = random_bound(rng)
    cases = [
        (f"once[{sec_text(a)}:{sec_text(b)}]{{p}}", oracle(true_set_once(msgs, a, b, end), msgs[0][0], end)),
        # historically[a:b] not p == not once[a:b] p
        (f"historically[{sec_text(a)}:{sec_text(b)}](not {{p}})",
         oracle(true_set_once(msgs, a, b, end), msgs[0][0], end, negate=True)),
        (f"{{@age <= {sec_text(d)}}}", oracle(true_set_age(msgs, d, end), msgs[0][0], end)),
    ]
    for spec, want in cases:
        r = run([rvc, "check", "--dense", "--spec", spec, trace])
        assert r.returncode in (0, 1), r.stderr
        assert verdicts(r.stdout) == want, (spec, msgs, r.stdout)


def test_the_results_store_records_where_the_stream_ended(rvc, tmp_path):
    # The dashboard's timeline reaches the last instant checked, not the last verdict change: the run's
    # counters carry stream_time (dense), read back here with Python's sqlite3.
    import sqlite3
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"time": 1.5, "p": true}\n{"time": 7.25, "p": true}\n')
    for args in (["check", "--dense", "--spec", "{p}", str(trace), "-o"],
                 ["monitor", "--dense", "--spec", "{p}", "--input", f"file:{trace}", "--output"]):
        db = tmp_path / (args[0] + ".db")
        r = run([rvc, *args, f"sqlite:{db}"])
        assert r.returncode == 0, r.stderr
        (counters,), = sqlite3.connect(db).execute("SELECT counters FROM runs").fetchall()
        assert json.loads(counters)["stream_time"] == 7.25, counters


def test_diagnostics_name_the_verdict_time_exactly(rvc, tmp_path):
    # /diagnostics (diagnostic_msgs/DiagnosticArray as JSON lines here): the property's verdict_time is the
    # stamp as it came in, not a double of epoch seconds (1746721937.6246268 before exact time).
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"time": 1746721937.599626818, "p": true}\n{"time": 1746721937.624626818, "p": false}\n')
    diag = tmp_path / "diag.jsonl"
    r = run([rvc, "monitor", "--dense", "--spec", "{p}", "--input", f"file:{trace}", "--diagnostics", f"file:{diag}"])
    assert r.returncode == 1, r.stderr
    times = {kv["value"] for line in diag.read_text().splitlines() for s in json.loads(line)["status"]
             for kv in s["values"] if kv["key"] == "verdict_time" and kv["value"]}
    assert times == {"1746721937.599626818", "1746721937.624626818"}, times
