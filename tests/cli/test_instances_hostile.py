"""Hostile inputs to `--instances-by` (issue 36). Oracles: hand-computed traces and `rvc check` of each
key's own messages (an instance must give exactly the verdicts a check of its sub-trace gives)."""
import json
import subprocess

import pytest


def run(rvc, *args, stdin=None, timeout=120):
    return subprocess.run([rvc, *args], input=stdin, capture_output=True, text=True, timeout=timeout)


def write(path, objs):
    path.write_text("".join(json.dumps(o) + "\n" for o in objs))
    return str(path)


def counters(stderr):
    line = [l for l in stderr.splitlines() if l.startswith("{")][-1]
    c = json.loads(line)
    assert c["received"] == c["checked"] + c["rejected"] + sum(c["dropped"].values()), c
    return c


def verdicts(text):
    return [(json.dumps(v.get("instance")), v["time"], v["value"]) for v in map(json.loads, text.splitlines())]


# A key string long enough to be a third of simdjson's string buffer was unescaped into it twice (once to
# route, once by the instance's decoder): heap corruption (SIGSEGV, "double free") at ~54,700 characters.
@pytest.mark.parametrize("n", [54700, 1_000_000])
@pytest.mark.parametrize("how", ["file", "stdin", "monitor"])
def test_a_very_long_key_is_an_ordinary_key(rvc, tmp_path, n, how):
    long_key = "x" * n
    msgs = [{"id": long_key, "p": True}, {"id": "b", "p": False}, {"id": long_key, "p": False}]
    trace = write(tmp_path / "t.jsonl", msgs)
    args = ["--instances-by", "id", "--spec", "{p}"]
    if how == "file":
        r = run(rvc, "check", "--stats", *args, trace)
        out = r.stdout
    elif how == "stdin":
        r = run(rvc, "check", "--stats", *args, "-", stdin=open(trace).read())
        out = r.stdout
    else:
        o = tmp_path / "v.jsonl"
        r = run(rvc, "monitor", *args, "-i", f"file:{trace}", "-o", f"file:{o}")
        out = "\n".join(l for l in o.read_text().splitlines() if '"instance"' in l)
    assert r.returncode == 1, r.stderr[-2000:]
    assert verdicts(out) == [(json.dumps({"id": long_key}), 0, True), ('{"id": "b"}', 0, False),
                             (json.dumps({"id": long_key}), 1, False)]
    if how != "monitor":
        c = counters(r.stderr)
        assert c["checked"] == 3 and c["instances"]["created"] == 2


def test_a_long_key_with_escapes_is_unescaped(rvc, tmp_path):
    key = '"\\\n' + "\u00e9" * 40000 + "\t"
    trace = write(tmp_path / "t.jsonl", [{"id": key, "p": True}, {"id": "b", "p": False}, {"id": key, "p": False}])
    r = run(rvc, "check", "--instances-by", "id", "--spec", "{p}", trace)
    assert r.returncode == 1, r.stderr[-2000:]
    assert [json.loads(l)["instance"]["id"] for l in r.stdout.splitlines()] == [key, "b", key]


def by_key(stdout, field="id"):
    out = {}
    for v in map(json.loads, stdout.splitlines()):
        out.setdefault(v["instance"][field], []).append((v["time"], v["property"], v["value"]))
    return out


def plain(stdout):
    return [(v["time"], v["property"], v["value"]) for v in map(json.loads, stdout.splitlines())]


# Only a message its instance checks makes an instance: garbage under many keys (a bad dense time, a --strict
# type error) took the --max-instances places and locked the valid keys out.
@pytest.mark.parametrize("mode", [["--dense"], ["--strict"]])
def test_rejected_messages_take_no_instance_place(rvc, tmp_path, mode):
    bad = ({"time": "soon", "p": True} if mode == ["--dense"] else {"time": 0, "p": "yes"})
    msgs = [dict(bad, id=f"g{i}") for i in range(5)]
    msgs += [{"time": t, "id": k, "p": True} for t in (1, 2, 3) for k in ("a", "b")]
    trace = write(tmp_path / "t.jsonl", msgs)
    # (a tautology over p: no violation, also before the first message in dense time)
    r = run(rvc, "check", *mode, "--stats", "--instances-by", "id", "--max-instances", "2", "--spec",
            "{p} or not {p}", trace)
    c = counters(r.stderr)
    assert (c["checked"], c["rejected"], c["dropped"]) == (6, 5, {}), r.stderr
    assert c["instances"] == {"created": 2, "expired": 0, "live": 2, "refused_keys": 0}
    assert set(by_key(r.stdout)) == {"a", "b"}
    assert r.returncode == 3  # rejected messages, nothing dropped


def pieces_oracle(rvc, tmp_path, msgs, expiry, args):
    """Each key's sub-trace cut where a message comes more than `expiry` after the key's previous one, every
    piece checked on its own by rvc check."""
    want, n = {}, 0
    for key in sorted({m["id"] for m in msgs}):
        sub = [m for m in msgs if m["id"] == key]
        cuts = [0] + [i for i in range(1, len(sub)) if sub[i]["time"] - sub[i - 1]["time"] > expiry] + [len(sub)]
        for a, b in zip(cuts, cuts[1:]):
            n += 1
            p = write(tmp_path / f"piece_{key}_{a}.jsonl", sub[a:b])
            want.setdefault(key, []).extend(plain(run(rvc, "check", *args, p).stdout))
    return want, n


# One rejected message (a negative dense time) made an instance that never expired; an instance whose last
# time is late (key "far") kept every instance behind it from expiring, for the rest of the run.
def test_expiry_goes_on_past_a_rejected_time_and_a_late_instance(rvc, tmp_path):
    # "far" comes first (its time expires no one: there is no one yet), then the others' earlier times
    msgs = [{"time": 1_000_000, "id": "far", "p": False}, {"time": 1, "id": "a", "p": True},
            {"time": -1, "id": "neg", "p": True}]
    msgs += [{"time": t, "id": "a", "p": t != 3} for t in (2, 3, 4)]
    msgs += [{"time": t, "id": "b", "p": t % 7 != 0} for t in range(5, 40)]
    msgs += [{"time": 50, "id": "a", "p": True}]  # a's gap of 46 s: a fresh instance
    trace = write(tmp_path / "t.jsonl", msgs)
    args = ["--dense", "--spec", "historically[0:2]{p}"]
    r = run(rvc, "check", "--stats", "--instances-by", "id", "--instance-expiry", "3", *args, trace)
    c = counters(r.stderr)
    assert c["rejected"] == 1 and c["checked"] == len(msgs) - 1, r.stderr
    # a's first piece expires (at b's time 8), then b's (at a's time 50); "far" never does (1e6 is later)
    assert c["instances"] == {"created": 4, "expired": 2, "live": 2, "refused_keys": 0}, c
    want, n = pieces_oracle(rvc, tmp_path, [m for m in msgs if m["time"] >= 0], 3, args)
    assert n == 4 and by_key(r.stdout) == want


# Bounded future per instance: the last horizon of each instance was never settled at the end (a violation
# lost, exit 0), and an expiring instance was dropped unsettled (no verdicts at all).
@pytest.mark.parametrize("mode", [[], ["--all"], ["--dense"]])
def test_instances_settle_their_last_horizon(rvc, tmp_path, mode):
    msgs = [{"time": 1, "id": "a", "p": True}, {"time": 1, "id": "b", "p": True},
            {"time": 2, "id": "a", "p": False}, {"time": 2.5, "id": "b", "p": True}]
    trace = write(tmp_path / "t.jsonl", msgs)
    spec = ["--spec", "eventually[0:1]{p}"]
    r = run(rvc, "check", *mode, "--instances-by", "id", *spec, trace)
    alone = run(rvc, "check", *mode, *spec, write(tmp_path / "a.jsonl", [m for m in msgs if m["id"] == "a"]))
    assert alone.returncode == 1  # a's last message: p false, nothing after it
    assert r.returncode == 1, r.stderr
    assert by_key(r.stdout)["a"] == plain(alone.stdout)
    if mode != ["--dense"]:  # hand-computed, discrete: a = T, F -> step 0 true, step 1 false (the end)
        assert [v for v in plain(alone.stdout) if v[0] == 1] == [(1, "p1", False)]


@pytest.mark.parametrize("mode", [["--all"], ["--dense"]])
def test_expiring_instances_settle_their_horizon_as_their_pieces(rvc, tmp_path, mode):
    import random
    rnd = random.Random(2)
    msgs, t = [], 0.0
    for _ in range(200):
        t += rnd.choice([0.25, 0.5, 1.0, 4.0])
        msgs.append({"time": t, "id": f"k{rnd.randrange(3)}", "p": rnd.random() < 0.4})
    trace = write(tmp_path / "t.jsonl", msgs)
    args = [*mode, "--spec", "eventually[0:1]{p}", "--spec", "historically[0:2](eventually[0:1]{p})"]
    r = run(rvc, "check", "--stats", "--instances-by", "id", "--instance-expiry", "3", *args, trace)
    c = counters(r.stderr)
    want, n = pieces_oracle(rvc, tmp_path, msgs, 3, args)
    assert c["instances"]["created"] == n and c["instances"]["expired"] > 3
    got = by_key(r.stdout)
    assert got == want and sum(map(len, got.values())) > 20
    # monitor on the same file: the same verdicts
    o = tmp_path / "v.jsonl"
    m = run(rvc, "monitor", "--instances-by", "id", "--instance-expiry", "3", *args, "-i", f"file:{trace}",
            "-o", f"file:{o}")
    assert m.returncode == r.returncode, m.stderr
    assert o.read_text() == r.stdout
