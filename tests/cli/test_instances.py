"""`rvc check --instances-by FIELD`: one monitor instance per key value
(docs/semantics.md, "Parametric instances"). Oracles: hand-computed traces,
and `rvc check` run separately on each key's sub-trace (filtered here in
Python) -- an instance must give exactly the verdicts a check of its own
messages gives."""
import json
import random
import subprocess

import pytest


def run(rvc, *args, stdin=None):
    return subprocess.run([rvc, *args], input=stdin, capture_output=True, text=True)


def write(path, objs):
    path.write_text("".join(json.dumps(o) + "\n" for o in objs))
    return str(path)


def by_instance(stdout, field="id"):
    out = {}
    for v in map(json.loads, stdout.splitlines()):
        assert set(v["instance"]) == {field}, v
        out.setdefault(v["instance"][field], []).append((v["time"], v["property"], v["value"]))
    return out


def plain(stdout):
    return [(v["time"], v["property"], v["value"]) for v in map(json.loads, stdout.splitlines())]


def counters(stderr):
    line = [l for l in stderr.splitlines() if l.startswith("{")][-1]
    c = json.loads(line)
    assert c["received"] == c["checked"] + c["rejected"] + sum(c["dropped"].values())
    return c


def test_hand_computed_two_instances(rvc, tmp_path):
    # a: T, F, T   b: T, T   (interleaved a b a b a)
    trace = write(tmp_path / "t.jsonl", [{"id": "a", "ok": True}, {"id": "b", "ok": True},
                                         {"id": "a", "ok": False}, {"id": "b", "ok": True},
                                         {"id": "a", "ok": True}])
    r = run(rvc, "check", "--instances-by", "id", "--spec", "historically[:1]{ok}", trace)
    # each instance steps 0, 1, 2 on its own messages: a: H[:1] over T,F,T = T,F,F; b: T,T
    lines = [json.loads(l) for l in r.stdout.splitlines()]
    assert [(v["instance"], v["time"], v["value"]) for v in lines] == [
        ({"id": "a"}, 0, True), ({"id": "b"}, 0, True), ({"id": "a"}, 1, False)]
    assert r.returncode == 1, r.stderr
    # without --instances-by the same trace is one stream: T,T,F,F,T -> no "instance"
    r = run(rvc, "check", "--spec", "historically[:1]{ok}", trace)
    assert "instance" not in r.stdout
    assert plain(r.stdout) == [(0, "p1", True), (2, "p1", False), (4, "p1", True)]


def test_nested_and_numeric_keys(rvc, tmp_path):
    trace = write(tmp_path / "t.jsonl", [{"vehicle": {"id": 17}, "v": 1}, {"vehicle": {"id": "17"}, "v": 5},
                                         {"vehicle": {"id": 17}, "v": 9}])
    r = run(rvc, "check", "--all", "--instances-by", "vehicle.id", "--spec", "{v < 4}", trace)
    got = [(json.dumps(json.loads(l)["instance"]), json.loads(l)["time"], json.loads(l)["value"])
           for l in r.stdout.splitlines()]
    # the number 17 and the string "17" are two keys, written as they came
    assert got == [('{"vehicle.id": 17}', 0, True), ('{"vehicle.id": "17"}', 0, False),
                   ('{"vehicle.id": 17}', 1, False)]


def fleet_trace(seed, n=400, keys=6):
    rnd = random.Random(seed)
    t = 0.0
    out = []
    for _ in range(n):
        t += rnd.choice([0.1, 0.25, 0.5])
        out.append({"time": round(t, 3), "id": f"v{rnd.randrange(keys)}", "speed": rnd.randrange(0, 40),
                    "brake": rnd.random() < 0.3, "gear": rnd.randrange(1, 4)})
    return out


SPECS = ["historically({speed > 30} -> once[0:1]{brake})", "{brake} since {speed < 10}",
         "forall[g]. ({gear: *g} -> once[1:2]{gear: *g})"]  # data references run inside each instance


@pytest.mark.parametrize("mode", [[], ["--all"], ["--dense"], ["--dense", "--all"]])
def test_equals_separate_checks_of_each_sub_trace(rvc, tmp_path, mode):
    msgs = fleet_trace(7)
    trace = write(tmp_path / "fleet.jsonl", msgs)
    args = [a for s in SPECS for a in ("--spec", s)]
    r = run(rvc, "check", *mode, "--stats", "--instances-by", "id", *args, trace)
    assert r.returncode in (0, 1), r.stderr
    got = by_instance(r.stdout)
    c = counters(r.stderr)
    assert c["checked"] == len(msgs) and c["rejected"] == 0
    assert c["instances"]["created"] == len({m["id"] for m in msgs})
    for key in sorted({m["id"] for m in msgs}):
        sub = write(tmp_path / f"{key}.jsonl", [m for m in msgs if m["id"] == key])
        want = run(rvc, "check", *mode, *args, sub)
        assert got.get(key, []) == plain(want.stdout), key


def test_expiry_starts_a_fresh_instance(rvc, tmp_path):
    msgs = fleet_trace(3, n=300, keys=4)
    # give v0 long pauses: drop its messages in two windows so its gaps exceed the expiry
    msgs = [m for m in msgs if not (m["id"] == "v0" and (20 < m["time"] < 30 or 50 < m["time"] < 58))]
    trace = write(tmp_path / "fleet.jsonl", msgs)
    expiry = 5.0
    r = run(rvc, "check", "--all", "--stats", "--instances-by", "id", "--instance-expiry", str(expiry),
            "--spec", SPECS[0], trace)
    got = by_instance(r.stdout)
    c = counters(r.stderr)
    # oracle: each key's sub-trace cut where a message comes more than `expiry` after the key's
    # previous one -- every piece checked on its own (steps restart at 0)
    want, pieces = {}, 0
    for key in sorted({m["id"] for m in msgs}):
        sub = [m for m in msgs if m["id"] == key]
        cuts = [0] + [i for i in range(1, len(sub)) if sub[i]["time"] - sub[i - 1]["time"] > expiry] + [len(sub)]
        for a, b in zip(cuts, cuts[1:]):
            pieces += 1
            p = write(tmp_path / f"{key}_{a}.jsonl", sub[a:b])
            want.setdefault(key, []).extend(plain(run(rvc, "check", "--all", "--spec", SPECS[0], p).stdout))
    assert pieces > 4  # v0 really was cut
    assert got == want
    assert c["instances"]["created"] == pieces
    # an instance expires when a message of any key comes more than `expiry` after its last one:
    # here every piece but the last of each key
    assert c["instances"]["expired"] == pieces - 4
    assert c["instances"]["live"] == 4


def test_max_instances_drops_new_keys_with_a_reason(rvc, tmp_path):
    msgs = [{"id": k, "ok": True} for k in ["a", "b", "c", "a", "c", "b", "d"]]
    trace = write(tmp_path / "t.jsonl", msgs)
    r = run(rvc, "check", "--stats", "--instances-by", "id", "--max-instances", "2", "--spec", "{ok}", trace)
    assert r.returncode == 3, r.stderr  # messages the run meant to check were dropped: not a pass
    c = counters(r.stderr)
    assert c["checked"] == 4 and c["dropped"] == {"instance_limit": 3}
    assert c["instances"]["refused_keys"] == 2
    assert "--max-instances 2" in r.stderr
    assert set(by_instance(r.stdout)) == {"a", "b"}


def test_message_without_key_is_rejected_and_counted(rvc, tmp_path):
    trace = write(tmp_path / "t.jsonl", [{"id": "a", "ok": True}, {"ok": False}, {"id": [1], "ok": True},
                                         {"id": "a", "ok": True}])
    r = run(rvc, "check", "--stats", "--instances-by", "id", "--spec", "{ok}", trace)
    assert r.returncode == 3, r.stderr
    assert "line 2: no key field 'id'" in r.stderr
    assert "line 3: key field 'id' is not a string or a number" in r.stderr
    c = counters(r.stderr)
    assert c["checked"] == 2 and c["rejected"] == 2 and c["received"] == 4


def test_instance_options_need_instances_by(rvc, tmp_path):
    trace = write(tmp_path / "t.jsonl", [{"ok": True}])
    r = run(rvc, "check", "--instance-expiry", "3", "--spec", "{ok}", trace)
    assert r.returncode == 2 and "--instances-by" in r.stderr


def test_results_database_keeps_instances_apart(rvc, tmp_path):
    import sqlite3
    trace = write(tmp_path / "t.jsonl", [{"id": "a", "ok": True}, {"id": "b", "ok": False},
                                         {"id": "a", "ok": False}, {"id": "b", "ok": False}])
    db = tmp_path / "r.db"
    r = run(rvc, "check", "--instances-by", "id", "--spec", "{ok}", "-o", f"sqlite:{db}", trace)
    assert r.returncode == 1, r.stderr
    rows = sqlite3.connect(db).execute("SELECT property, time, value FROM verdicts ORDER BY id").fetchall()
    # a verdict change per instance: b's second false is no change for b (though a turned false between)
    assert rows == [('p1 {"id":"a"}', 0, 1), ('p1 {"id":"b"}', 0, 0), ('p1 {"id":"a"}', 1, 0)]
    viol = sqlite3.connect(db).execute("SELECT property FROM violations ORDER BY id").fetchall()
    assert viol == [('p1 {"id":"b"}',), ('p1 {"id":"a"}',)]


def test_monitor_file_input_equals_check(rvc, tmp_path):
    msgs = fleet_trace(11, n=200, keys=4)
    trace = write(tmp_path / "fleet.jsonl", msgs)
    args = [a for s in SPECS for a in ("--spec", s)]
    want = run(rvc, "check", "--instances-by", "id", *args, trace)
    out = tmp_path / "out.jsonl"
    r = run(rvc, "monitor", "--instances-by", "id", *args, "-i", f"file:{trace}", "-o", f"file:{out}")
    assert r.returncode == want.returncode, r.stderr
    got = [l for l in out.read_text().splitlines() if '"instance"' in l]
    assert got and got == want.stdout.splitlines()


def test_max_data_values_is_per_instance(rvc, tmp_path):
    # each key binds two distinct gears: within --max-data-values 2 per instance, though the run has 4
    msgs = [{"id": k, "gear": g} for k, gs in (("a", (1, 2)), ("b", (3, 4))) for g in gs]
    trace = write(tmp_path / "t.jsonl", msgs)
    spec = ["--spec", "exists[g]. {gear: *g}", "--max-data-values", "2"]
    assert run(rvc, "check", "--instances-by", "id", *spec, trace).returncode == 0
    assert run(rvc, "check", *spec, trace).returncode == 5  # one stream: 4 values
    trace = write(tmp_path / "t3.jsonl", msgs + [{"id": "a", "gear": 9}])
    r = run(rvc, "check", "--instances-by", "id", *spec, trace)
    assert r.returncode == 5, r.stderr  # instance a's third value: the run stops, as without instances


def test_broken_lines_are_rejected_as_without_instances(rvc, tmp_path):
    p = tmp_path / "bad.jsonl"
    p.write_text('{"id":"a","ok":true}\n{"id":"a","ok":tru\n{"id":"c","ok":false}{"id":"d"}\nnot json\n'
                 '{"ok":true,"id":"b"}\n')
    r = run(rvc, "check", "--stats", "--instances-by", "id", "--spec", "{ok}", str(p))
    plain_run = run(rvc, "check", "--stats", "--spec", "{ok}", str(p))
    c, c0 = counters(r.stderr), counters(plain_run.stderr)
    assert (c["checked"], c["rejected"]) == (c0["checked"], c0["rejected"]) == (2, 3)
    # the same errors, by line; key "c" came only on a broken line: no instance for it
    assert [l for l in r.stderr.splitlines() if "skipped" in l] == \
           [l for l in plain_run.stderr.splitlines() if "skipped" in l]
    assert c["instances"]["created"] == 2 and set(by_instance(r.stdout)) == {"a", "b"}
