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
