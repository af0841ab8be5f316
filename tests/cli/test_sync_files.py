"""Several file inputs merged by stamp (issue 25, item 1): the files are read in stamp order (a
k-way merge), not raced by two reader threads, so a run gives the same events every time and none
is late. Oracle: the merge written out here in Python (each message an event at its stamp, the other
input's latest message held) and the property evaluated on it by hand."""
import json
import random
import subprocess

import pytest

from test_mcap import typestore  # noqa: F401  (the fixture: rosbags' types for the bag test)


def run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, timeout=120, **kw)


def counters(stderr):
    return json.loads([line for line in stderr.splitlines() if line.startswith('{"input"')][-1])


def write(path, rows):
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
    return str(path)


def traces(tmp_path, seed):
    """a: many messages with early stamps; b: few, stamped among a's. Read by racing threads, the
    small file is done long after a's later stamps went out (its messages late: dropped)."""
    rng = random.Random(seed)
    a = [{"time": 2 * k, "ok": rng.random() < 0.9} for k in range(20000)]
    b = [{"time": 2 * k * 97 + 1, "alarm": rng.random() < 0.3} for k in range(200)]
    return write(tmp_path / "a.jsonl", a), write(tmp_path / "b.jsonl", b), a, b


def python_verdicts(a, b):
    """{b.alarm} -> {a.ok} at every event of the merge (a field not yet seen is false)."""
    latest, out = {}, []
    for t, name, msg in sorted([(m["time"], "a", m) for m in a] + [(m["time"], "b", m) for m in b]):
        latest[name] = msg
        alarm = latest.get("b", {}).get("alarm", False)
        ok = latest.get("a", {}).get("ok", False)
        out.append((not alarm) or ok)
    return out


def test_two_files_merge_in_stamp_order_every_run(rvc, tmp_path):
    fa, fb, a, b = traces(tmp_path, 3)
    want = python_verdicts(a, b)
    assert not all(want)  # the property is violated somewhere: a run that misses it exits 0
    for attempt in range(3):
        r = run([rvc, "monitor", "--all", "--spec", "{b.alarm} -> {a.ok}", "--input", f"a=file:{fa}",
                 "--input", f"b=file:{fb}"])
        got = [json.loads(line)["value"] for line in r.stdout.splitlines()]
        assert got == want, (attempt, r.stderr[-2000:])
        assert r.returncode == 1, r.stderr
        c = counters(r.stderr)
        assert c["received"] == len(a) + len(b) and c["checked"] == len(a) + len(b), c
        assert c["dropped"] == {} and c["rejected"] == 0, c
        assert c["sync"]["sets"] == len(a) + len(b), c
    # rvc sync: the same events, published
    r = run([rvc, "sync", "--input", f"a=file:{fa}", "--input", f"b=file:{fb}"])
    assert r.returncode == 0, r.stderr
    assert [s["time"] for s in map(json.loads, r.stdout.splitlines())] == sorted(
        [m["time"] for m in a] + [m["time"] for m in b])


def test_a_file_whose_stamps_go_back_is_refused_at_that_line(rvc, tmp_path):
    fa = write(tmp_path / "a.jsonl", [{"time": 1, "ok": True}, {"time": 5, "ok": True}, {"time": 3, "ok": False},
                                      {"time": 7, "ok": True}])
    fb = write(tmp_path / "b.jsonl", [{"time": 2, "alarm": True}, {"time": 6, "alarm": True}])
    r = run([rvc, "monitor", "--all", "--spec", "{b.alarm} -> {a.ok}", "--input", f"a=file:{fa}",
             "--input", f"b=file:{fb}"])
    assert "input a line 3: stamp 3 is before the previous message's 5" in r.stderr, r.stderr
    assert r.returncode == 3, r.stderr  # no violation: the rejected line was the only bad one
    c = counters(r.stderr)
    assert (c["received"], c["checked"], c["rejected"], c["dropped"]) == (6, 5, 1, {}), c
    assert [json.loads(line)["value"] for line in r.stdout.splitlines()] == [True] * 5


def late_bag(tmp_path, typestore):
    """Two topics whose log order is not their stamp order: steer's stamps lag up to 0.27 s."""
    from rosbags.rosbag2 import Writer
    from rosbags.rosbag2.enums import StoragePlugin
    from test_mcap import GEAR, GEAR_TOPIC, STEER, STEER_TOPIC
    Time = typestore.types["builtin_interfaces/msg/Time"]
    folder = tmp_path / "late"
    t0 = 1_700_000_000 * 10**9
    rows = []
    for k in range(40):
        log = t0 + k * 100_000_000
        rows.append((log, "gear", log, 20 if k % 9 == 4 else 2))
        rows.append((log + 1, "steer", log - (270_000_000 if k % 10 == 5 else 0) + 50_000_000, 0.1))
    with Writer(folder, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        cg = w.add_connection(GEAR_TOPIC, GEAR, typestore=typestore)
        cs = w.add_connection(STEER_TOPIC, STEER, typestore=typestore)
        for log, name, stamp, value in rows:
            st = Time(sec=stamp // 10**9, nanosec=stamp % 10**9)
            if name == "gear":
                w.write(cg, log, typestore.serialize_cdr(typestore.types[GEAR](stamp=st, report=value), GEAR))
            else:
                msg = typestore.types[STEER](stamp=st, steering_tire_angle=value)
                w.write(cs, log, typestore.serialize_cdr(msg, STEER))
    return str(next(folder.glob("*.mcap")))


@pytest.mark.needs_rust
def test_late_messages_of_a_bag_are_warned_counted_and_not_a_pass(rvc, tmp_path, typestore):
    from test_mcap import GEAR_TOPIC, STEER_TOPIC
    bag = late_bag(tmp_path, typestore)
    topics = ["--topic", f"gear={GEAR_TOPIC}", "--topic", f"steer={STEER_TOPIC}"]
    spec = "{gear.report == 20} -> {steer.steering_tire_angle < 0.3}"
    r = run([rvc, "check", "--stats", "--spec", spec, bag, *topics, "--max-delay", "0.1"])
    c = counters(r.stderr)
    late = c["dropped"].get("late", 0)
    assert late > 0, r.stderr
    assert r.returncode == 3, r.stderr  # no violation, but messages were skipped: not a clean pass
    assert "dropped as late" in r.stderr and f"{late} message{'s' if late > 1 else ''} dropped, not checked" in r.stderr, r.stderr
    assert c["received"] == 80 and c["checked"] + late == 80, c
    # --late process: every message checked, nothing dropped, a clean pass
    r = run([rvc, "check", "--stats", "--spec", spec, bag, *topics, "--max-delay", "0.1", "--late", "process"])
    c = counters(r.stderr)
    assert r.returncode == 0 and (c["received"], c["checked"], c["dropped"]) == (80, 80, {}), r.stderr
    assert "checked late, as the next event" in r.stderr, r.stderr
