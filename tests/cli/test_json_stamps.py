"""Stamps of JSON messages as ROS 2 JSON writes them: a builtin_interfaces/Time object at a path
(`--time-field header.stamp`, `--stamp NAME=stamp`), ROS 1's secs/nsecs too. Oracle: the merged
stream and the times worked out by hand below."""
import json
import subprocess


def run(args):
    return subprocess.run(args, capture_output=True, text=True, timeout=60)


def lines(path, rows):
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
    return str(path)


def test_sync_merges_json_inputs_by_their_time_objects(rvc, tmp_path):
    a = lines(tmp_path / "a.jsonl", [{"stamp": {"sec": 1, "nanosec": 0}, "x": 1},
                                     {"stamp": {"sec": 2, "nanosec": 250000000}, "x": 3}])
    b = lines(tmp_path / "b.jsonl", [{"stamp": {"secs": 1, "nsecs": 500000000}, "y": 2}])
    r = run([rvc, "sync", "--input", f"a=file:{a}", "--input", f"b=file:{b}", "--stamp", "a=stamp",
             "--stamp", "b=stamp", "--output", "-"])
    assert r.returncode == 0, r.stderr
    got = [(s["time"], s.get("a", {}).get("x"), s.get("b", {}).get("y")) for s in map(json.loads, r.stdout.splitlines())]
    assert got == [(1.0, 1, None), (1.5, 1, 2), (2.25, 3, 2)]


def test_dense_time_from_a_nested_time_object(rvc, tmp_path):
    trace = lines(tmp_path / "t.jsonl", [
        {"header": {"stamp": {"sec": 1, "nanosec": 500000000}}, "x": 1},
        {"header": {"stamp": "noon"}, "x": 0},                 # rejected, named; the rest goes on
        {"header": {"stamp": {"nanosec": 5}}, "x": 0},          # rejected: no sec
        {"header": {"stamp": {"sec": 3, "nanosec": 0}}, "x": 0},
    ])
    r = run([rvc, "check", "--dense", "--time-field", "header.stamp", "--spec", "{x >= 1}", trace])
    assert r.returncode == 1, r.stderr  # violated (which outranks "messages were rejected")
    assert "line 2: time field \"header.stamp\" must be a number of seconds or a Time {sec, nanosec}, not a string" \
        in r.stderr, r.stderr
    assert "line 3: time field \"header.stamp\" is an object without \"sec\"" in r.stderr, r.stderr
    assert "2 messages checked, 2 rejected" in r.stderr, r.stderr
    # The two valid messages with their times as plain seconds (1.5 and 3) give the same verdicts.
    plain = lines(tmp_path / "plain.jsonl", [{"time": 1.5, "x": 1}, {"time": 3, "x": 0}])
    p = run([rvc, "check", "--dense", "--spec", "{x >= 1}", plain])
    assert p.stdout == r.stdout and len(r.stdout.splitlines()) >= 2, (p.stdout, r.stdout)
