"""No silent loss (issue 25, item 6), the offline input kinds: one file (`rvc check`, `rvc monitor
--input file:`), several files synchronized (merge and approximate), a ROS 2 bag (one topic, two
topics whose log order is not their stamp order). On random traces with malformed lines, lines
without their time, stamps that go back or repeat and unknown fields, every run must account for
every message it received:

    received == checked + rejected + sum(dropped.values())

and its exit status must say so: a run that rejected or lost (late, replaced) a message is not a
clean pass (3), one that checked nothing is incomplete (6). The properties always hold (`{x >= 0} or
!{x >= 0}`: also before a field has a value, as in dense time's first interval), so 0 is the only
clean answer. The counts themselves come from an oracle written here in
Python (which lines are valid JSON objects, which times go back), not from rvc.
"""
import json
import random
import subprocess

import pytest

from loss_oracle import assert_accounted, counters, oracle_merge, oracle_single, random_lines
from test_mcap import typestore  # noqa: F401  (the fixture, for the bag cases)

SEEDS = range(6)
HOLDS = "{x >= 0} or !{x >= 0}"  # holds at every step, dense time's first interval too


def run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, timeout=120, **kw)


def write(path, lines):
    path.write_text("".join(line + "\n" for line in lines))
    return str(path)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("dense", [False, True])
def test_one_file(rvc, tmp_path, seed, dense):
    rng = random.Random(seed)
    lines = random_lines(rng, rng.randint(0, 60))
    trace = write(tmp_path / "t.jsonl", lines)
    mode = ["--dense"] if dense else []
    received, checked, rejected = oracle_single(lines, dense)
    r = run([rvc, "check", "--stats", *mode, "--spec", HOLDS, trace])
    c = counters(r.stderr)
    assert (c["received"], c["checked"], c["rejected"], c["dropped"]) == (received, checked, rejected, {}), r.stderr
    assert_accounted(c, r.returncode, "check")
    m = run([rvc, "monitor", *mode, "--spec", HOLDS, "--input", f"file:{trace}"])
    mc = counters(m.stderr)
    assert (mc["received"], mc["checked"], mc["rejected"]) == (received, checked, rejected), m.stderr
    assert m.returncode == r.returncode or (received == 0 and m.returncode == 6), (r.stderr, m.stderr)
    assert_accounted(mc, m.returncode, "monitor")


@pytest.mark.parametrize("seed", SEEDS)
def test_several_files_merged(rvc, tmp_path, seed):
    rng = random.Random(100 + seed)
    files = [random_lines(rng, rng.randint(1, 80), t0=rng.random()) for _ in range(rng.randint(2, 3))]
    names = "abc"[:len(files)]
    args = []
    for name, lines in zip(names, files):
        args += ["--input", f"{name}=file:{write(tmp_path / (name + '.jsonl'), lines)}"]
    spec = f"{{{names[0]}.x >= 0}} or !{{{names[0]}.x >= 0}}"
    received, checked, rejected, replaced = oracle_merge(files)
    for mode in ([], ["--dense"]):
        r = run([rvc, "monitor", *mode, "--spec", spec, *args])
        c = counters(r.stderr)
        assert (c["received"], c["checked"], c["rejected"]) == (received, checked, rejected), r.stderr
        assert c["dropped"] == ({"replaced": replaced} if replaced else {}), r.stderr
        assert_accounted(c, r.returncode, "merge")
    r = run([rvc, "monitor", "--sync", "approximate", "--spec", spec, *args])
    c = counters(r.stderr)
    assert (c["received"], c["rejected"]) == (received, rejected), r.stderr
    assert_accounted(c, r.returncode, "approximate")


def bag_with_disorder(tmp_path, ts, rng, name):
    """Gear and steer topics; steer's stamps lag its log time by a random amount (late in the merge)."""
    from rosbags.rosbag2 import Writer
    from rosbags.rosbag2.enums import StoragePlugin
    from test_mcap import GEAR, GEAR_TOPIC, STEER, STEER_TOPIC
    Time = ts.types["builtin_interfaces/msg/Time"]
    folder = tmp_path / name
    t0 = 1_700_000_000 * 10**9
    n = rng.randint(5, 40)
    with Writer(folder, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        cg = w.add_connection(GEAR_TOPIC, GEAR, typestore=ts)
        cs = w.add_connection(STEER_TOPIC, STEER, typestore=ts)
        for k in range(n):
            log = t0 + k * 100_000_000
            st = Time(sec=log // 10**9, nanosec=log % 10**9)
            w.write(cg, log, ts.serialize_cdr(ts.types[GEAR](stamp=st, report=2), GEAR))
            lag = rng.choice([0, 0, 0, 37, 143, 389]) * 10**6  # no two steer stamps equal
            s = log + 10**6 - lag
            msg = ts.types[STEER](stamp=Time(sec=s // 10**9, nanosec=s % 10**9), steering_tire_angle=0.1)
            w.write(cs, log + 10**6, ts.serialize_cdr(msg, STEER))
    return str(next(folder.glob("*.mcap"))), 2 * n


@pytest.mark.needs_rust
@pytest.mark.parametrize("seed", SEEDS)
def test_bags(rvc, tmp_path, typestore, seed):  # noqa: F811
    from test_mcap import GEAR_TOPIC, STEER_TOPIC
    rng = random.Random(200 + seed)
    bag, messages = bag_with_disorder(tmp_path, typestore, rng, f"bag{seed}")
    r = run([rvc, "check", "--stats", "--spec", "{report == 2}", bag, "--topic", GEAR_TOPIC])
    c = counters(r.stderr)
    assert (c["received"], c["checked"]) == (messages // 2, messages // 2), r.stderr
    assert_accounted(c, r.returncode, "bag, one topic")
    topics = ["--topic", f"gear={GEAR_TOPIC}", "--topic", f"steer={STEER_TOPIC}"]
    spec = "{gear.report == 2} or {steer.steering_tire_angle < 0.5}"
    for late in ("drop", "process"):
        r = run([rvc, "check", "--stats", "--spec", spec, bag, *topics, "--late", late])
        c = counters(r.stderr)
        assert c["received"] == messages, r.stderr
        assert_accounted(c, r.returncode, f"bag, two topics, --late {late}")
        if late == "process":
            assert c["checked"] == messages and c["dropped"] == {}, r.stderr  # no late, no repeated stamp
        m = run([rvc, "monitor", "--spec", spec, "--input", f"mcap:{bag}", *topics, "--late", late])
        mc = json.loads(m.stderr.strip().splitlines()[-1])
        assert (mc["received"], mc["checked"], mc["dropped"]) == (c["received"], c["checked"], c["dropped"]), m.stderr
        assert m.returncode == r.returncode, m.stderr
