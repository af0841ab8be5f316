"""Bounded future (eventually, always, until, next) on typed input: a ROS 2 bag of one topic (sqlite3 and
MCAP, written by rosbags) and `monitor --input bag:`. The checker's end-of-stream marker is no field of the
type: it was planned as one and every such property was refused ("no field 'rvc-end-of-stream' in
std_msgs/msg/String", exit 2). Oracles: `rvc check` of the same messages as JSON lines, and a hand-computed
case."""
import json
import subprocess

import pytest

pytestmark = pytest.mark.needs_rust

STORAGES = ["sqlite3", "mcap"]


def run(rvc, *args):
    return subprocess.run([rvc, *args], capture_output=True, text=True, timeout=60)


def write_bag(tmp_path, storage, type_name, msgs, name="bag"):
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore
    ts = get_typestore(Stores.ROS2_HUMBLE)
    cls = ts.types[type_name]
    folder = tmp_path / f"{name}_{storage}"
    plugin = StoragePlugin.SQLITE3 if storage == "sqlite3" else StoragePlugin.MCAP
    with Writer(folder, version=8, storage_plugin=plugin) as w:
        c = w.add_connection("/t", cls.__msgtype__, typestore=ts)
        for i, m in enumerate(msgs):
            w.write(c, 1_000_000 + i, ts.serialize_cdr(cls(**m), cls.__msgtype__))
    return str(folder)


def jsonl(tmp_path, msgs):
    p = tmp_path / "same.jsonl"
    p.write_text("".join(json.dumps(m) + "\n" for m in msgs))
    return str(p)


def monitor_bag(rvc, tmp_path, bag, *args):
    out = tmp_path / "v.jsonl"
    r = run(rvc, "monitor", "--input", f"bag:{bag}", "-o", f"file:{out}", *args)
    return r, out.read_text() if out.exists() else ""


@pytest.mark.parametrize("storage", STORAGES)
def test_hand_computed_eventually_on_a_bag(rvc, tmp_path, storage):
    bag = write_bag(tmp_path, storage, "std_msgs/msg/String", [{"data": d} for d in "abaca"])
    # eventually[0:1] at step i: step i or i+1 is "c" -> F F T T F (the last step has no next)
    want = [{"time": 0, "property": "p1", "value": False, "known_at": 1},
            {"time": 2, "property": "p1", "value": True, "known_at": 3},
            {"time": 4, "property": "p1", "value": False, "known_at": 4}]
    r = run(rvc, "check", bag, "--spec", 'eventually[0:1]{data: "c"}')
    assert r.returncode == 1, r.stderr
    assert [json.loads(l) for l in r.stdout.splitlines()] == want
    r, out = monitor_bag(rvc, tmp_path, bag, "--spec", 'eventually[0:1]{data: "c"}')
    assert r.returncode == 1, r.stderr
    assert [json.loads(l) for l in out.splitlines()] == want


SPECS = ["eventually[0:2]{data > 7}", "always[0:1]{data < 9}", "{data > 2} until[0:3] {data > 8}",
         "next {data > 5}", "historically(eventually[1:2]{data > 4})"]
DENSE_SPECS = ["eventually[0:2]{data > 30}", "always[0:1]{data < 50}", "historically(eventually[1:2]{data > 4})",
               "eventually[0.5:1](always[0:0.5]{data < 40})"]  # (dense time has no until/next yet)


@pytest.mark.parametrize("storage", STORAGES)
@pytest.mark.parametrize("mode", [["--all"], ["--dense", "--time-field", "data"], ["--robustness", "--all"]])
def test_future_on_a_bag_equals_check_on_json_lines(rvc, tmp_path, storage, mode):
    import random
    rnd = random.Random(5)
    msgs = [{"data": float(rnd.randrange(0, 10))} for _ in range(60)]
    if "--dense" in mode:  # the value is its own time: strictly increasing
        msgs = [{"data": float(i) + rnd.choice([0.0, 0.5])} for i in range(60)]
    bag = write_bag(tmp_path, storage, "std_msgs/msg/Float64", msgs)
    trace = jsonl(tmp_path, msgs)
    for spec in SPECS if "--dense" not in mode else DENSE_SPECS:
        want = run(rvc, "check", *mode, "--spec", spec, trace)
        assert want.returncode in (0, 1), want.stderr
        got = run(rvc, "check", bag, *mode, "--spec", spec)
        assert (got.returncode, got.stdout) == (want.returncode, want.stdout), (spec, got.stderr)
        r, out = monitor_bag(rvc, tmp_path, bag, *mode, "--spec", spec)
        assert (r.returncode, out) == (want.returncode, want.stdout), (spec, r.stderr)
