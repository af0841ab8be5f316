"""Several typed topics synchronized into one stream (issue 12), over DDS on loopback.

A Table-3 style run: the paper's nine Autoware messages, typed (CDR, rt/ topics), at 25/10/5 Hz of
stamps with jitter, published by nine `rvc replay --type` processes at once, so the topics arrive
interleaved in no particular order. Three participants read them at the same time:
- `rvc sync --sync merge` publishes every event as one JSON object (to a file);
- `rvc monitor --sync merge` checks properties over the nine inputs in process (with message
  constants such as REVERSE) and writes the events it checked (--sets-output);
- `rvc monitor --sync approximate` (message_filters' ApproximateTime) does the same.
Oracles written here, not by rvc: the merged stream computed in Python from the published values
(every message one event, in stamp order, the other inputs' latest messages held) must equal both
merge outputs event for event; `rvc check` on that Python stream (numbers for the constants) must
give the in-process monitor's verdicts; the approximate sets must use each message at most once,
hold one message per input within a small spread, and `rvc check` on them must give that monitor's
verdicts. Every published message is received (0 lost).
"""
import json
import os
import random
import subprocess
import time

import pytest

from conftest import transports_built
from test_python_peers import HANG_GUARD

VEH = "autoware_auto_vehicle_msgs/msg/"
EXT = "tier4_external_api_msgs/msg/"
# name, topic, type, rate (Hz of stamps), value of message k
TOPICS = [
    ("steer", "/vehicle/status/steering_status", VEH + "SteeringReport", 25,
     lambda k, r: {"steering_tire_angle": r.randint(-40, 40) / 64}),
    ("gear", "/vehicle/status/gear_status", VEH + "GearReport", 25, lambda k, r: {"report": r.choice([2, 20, 22])}),
    ("mode", "/vehicle/status/control_mode", VEH + "ControlModeReport", 25, lambda k, r: {"mode": r.choice([1, 4])}),
    ("turn", "/vehicle/status/turn_indicators_status", VEH + "TurnIndicatorsReport", 25,
     lambda k, r: {"report": r.choice([1, 2, 3])}),
    ("hazard", "/vehicle/status/hazard_lights_status", VEH + "HazardLightsReport", 25,
     lambda k, r: {"report": r.choice([1, 2])}),
    ("engage", "/api/autoware/get/engage", VEH + "Engage", 10, lambda k, r: {"engage": r.random() < 0.7}),
    ("failsafe", "/api/fail_safe/state", EXT + "FailSafeStateStamped", 10,
     lambda k, r: {"state": {"state": r.choice([0, 1, 2])}}),
    ("emergency", "/api/autoware/get/emergency", EXT + "Emergency", 10, lambda k, r: {"emergency": r.random() < 0.2}),
    ("status", "/api/external/get/vehicle/status", EXT + "VehicleStatusStamped", 5, None),
]
SECONDS = 4
T0 = 1700000000

# Properties over the nine inputs: the monitor's (with message constants) and the same with numbers
# for `rvc check` on JSON, which has no types to take constants from.
SPECS = [
    ("{gear.report == REVERSE} -> {steer.steering_tire_angle < 0.5}",
     "{gear.report == 20} -> {steer.steering_tire_angle < 0.5}"),
    ("{emergency.emergency} -> once[0:5]{hazard.report == ENABLE}",
     "{emergency.emergency} -> once[0:5]{hazard.report == 2}"),
    ("historically({turn.report == ENABLE_LEFT} -> !{hazard.report == ENABLE})",
     "historically({turn.report == 2} -> !{hazard.report == 2})"),
    ("{mode.mode == AUTONOMOUS} -> {engage.engage}", "{mode.mode == 1} -> {engage.engage}"),
]


def status_value(k, r):
    return {"status": {"gear_shift": {"data": r.choice([2, 4])}, "twist": {"linear": {"x": r.randint(0, 80) / 8}}}}


def make_traces(tmp_path):
    """Per topic: JSON lines with stamps on the topic's rate plus up to ±4 ms of jitter, distinct over all topics."""
    r = random.Random(31)
    used, traces, messages = set(), {}, []
    for name, _, _, rate, value in TOPICS:
        lines = []
        for k in range(SECONDS * rate):
            while True:
                ns = int(k * 1e9 / rate) + r.randint(-4000, 4000) * 1000 + 5_000_000
                if ns not in used:
                    break
            used.add(ns)
            msg = {"stamp": {"sec": T0 + ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}}
            msg.update((value or status_value)(k, r))
            lines.append(msg)
            messages.append((T0 + ns / 1e9, ns, name, msg))
        path = tmp_path / f"{name}.jsonl"
        path.write_text("".join(json.dumps(m) + "\n" for m in lines))
        traces[name] = path
    return traces, messages


def seconds(stamp):
    """A builtin_interfaces/Time in seconds, computed as rvc computes it (the same double)."""
    return (float(stamp["sec"]) * 1e9 + float(stamp["nanosec"])) / 1e9


def python_merge(messages):
    """The merge oracle: each message an event at its stamp, every input's latest message held."""
    latest, events = {}, []
    for _, ns, name, msg in sorted(messages, key=lambda m: m[1]):
        latest[name] = msg
        event = {"time": seconds(msg["stamp"])}
        event.update((n, latest[n]) for n, *_ in TOPICS if n in latest)
        events.append(event)
    return events


def input_args():
    args = []
    for name, topic, type_name, _, _ in TOPICS:
        args += ["--input", f"{name}=dds:{topic}", "--type", type_name]
    return args


def read_jsonl(path):
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def within(expected, got):
    """Every field the test wrote has its value in what rvc wrote (which also holds the type's other
    fields, at their defaults)."""
    if isinstance(expected, dict):
        return isinstance(got, dict) and all(k in got and within(v, got[k]) for k, v in expected.items())
    return expected == got and type(expected) is type(got) or (
        isinstance(expected, (int, float)) and not isinstance(expected, bool) and expected == got)


@pytest.fixture
def dds(rvc):
    if "dds" not in transports_built(rvc):
        pytest.skip("rvc built without DDS")


def test_nine_typed_topics_merge_and_approximate(rvc, tmp_path, dds):
    domain = 130 + os.getpid() % 30
    dds_flags = ["--domain", str(domain)]
    traces, messages = make_traces(tmp_path)
    total = len(messages)
    merged_sync = tmp_path / "sync.jsonl"
    merged_mon, approx_sets = tmp_path / "merge-sets.jsonl", tmp_path / "approx-sets.jsonl"
    verdicts_merge, verdicts_approx = tmp_path / "merge-verdicts.jsonl", tmp_path / "approx-verdicts.jsonl"
    spec_args = [a for monitor_spec, _ in SPECS for a in ("--spec", monitor_spec)]
    # The whole run's stamps fit in the delay: nothing can be late, every event comes out in order.
    merge_flags = ["--sync", "merge", "--max-delay", "100"]
    # Typed topics carry no end-of-stream marker (a ROS 2 publisher sends none): the participants
    # end when the topics have been quiet for a while, and then release what they hold.
    common = ["--idle-timeout", "5"] + dds_flags
    procs = [
        subprocess.Popen([rvc, "sync", *input_args(), *merge_flags, "--output", f"file:{merged_sync}", *common],
                         stderr=subprocess.PIPE, text=True),
        subprocess.Popen([rvc, "monitor", "--all", *spec_args, *input_args(), *merge_flags, "--sets-output",
                          f"file:{merged_mon}", "--output", f"file:{verdicts_merge}", *common],
                         stderr=subprocess.PIPE, text=True),
        subprocess.Popen([rvc, "monitor", "--all", *spec_args, *input_args(), "--sync", "approximate",
                          "--sync-queue", "200", "--sets-output", f"file:{approx_sets}", "--output",
                          f"file:{verdicts_approx}", *common], stderr=subprocess.PIPE, text=True),
    ]
    try:
        replays = [subprocess.Popen([rvc, "replay", str(traces[name]), "--to", f"dds:{topic}", "--type", type_name,
                                     "--wait-subscribers", "3", "--wait-timeout", "30", "--no-progress", *dds_flags],
                                    stderr=subprocess.PIPE, text=True)
                   for name, topic, type_name, _, _ in TOPICS]
        for p in replays:
            _, err = p.communicate(timeout=HANG_GUARD)
            assert p.returncode == 0, err
        errs = []
        for p in procs:
            _, err = p.communicate(timeout=HANG_GUARD)
            errs.append(err)
        codes = [p.returncode for p in procs]
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
    stats = [json.loads([l for l in e.splitlines() if l.startswith('{"input"')][-1]) for e in errs]
    for code, s, err in zip(codes, stats, errs):
        assert code in (0, 1), err  # 1: a property was violated; never lost (4), rejected (3), incomplete (6)
        assert s["received"] == total and s["gaps"] == 0 and s["duplicates"] == 0, err
        assert [i["received"] for i in s["inputs"]] == [SECONDS * t[3] for t in TOPICS], err

    # Merge: both participants produce exactly the Python-merged stream.
    expected = python_merge(messages)
    assert len(expected) == total
    got_sync, got_mon = read_jsonl(merged_sync), read_jsonl(merged_mon)
    assert len(got_sync) == len(expected)
    for i, (want, got) in enumerate(zip(expected, got_sync)):
        assert set(got) == set(want) and within(want, got), f"event {i}: {got} is not {want}"
    assert got_mon == got_sync
    assert stats[0]["sync"]["sets"] == total and stats[1]["sync"]["sets"] == total

    # Verdicts of the in-process monitor = rvc check on the Python stream, numbers for constants.
    oracle = tmp_path / "oracle.jsonl"
    oracle.write_text("".join(json.dumps(e) + "\n" for e in expected))
    check_specs = [a for _, check_spec in SPECS for a in ("--spec", check_spec)]
    check = subprocess.run([rvc, "check", "--all", *check_specs, str(oracle)], capture_output=True, text=True)
    assert check.returncode in (0, 1), check.stderr
    assert read_jsonl(verdicts_merge) == [json.loads(l) for l in check.stdout.splitlines()]
    assert any(not v["value"] for v in read_jsonl(verdicts_merge)), "no property was violated: a weak test"

    # Approximate: one message per input per set, each message used once, small spread; the
    # monitor's verdicts are those of `rvc check` on the sets it reports.
    sets = read_jsonl(approx_sets)
    assert SECONDS * 5 - 2 <= len(sets) <= SECONDS * 5  # the 5 Hz topic bounds the sets; the last may wait
    used = set()
    for s in sets:
        assert set(s) == {"time"} | {n for n, *_ in TOPICS}
        stamps = [seconds(v["stamp"]) for k, v in s.items() if k != "time"]
        assert max(stamps) - min(stamps) < 0.1
        assert s["time"] == max(stamps)
        for k, v in s.items():
            if k != "time":
                key = (k, v["stamp"]["sec"], v["stamp"]["nanosec"])
                assert key not in used
                used.add(key)
    check = subprocess.run([rvc, "check", "--all", *check_specs, str(approx_sets)], capture_output=True, text=True)
    assert read_jsonl(verdicts_approx) == [json.loads(l) for l in check.stdout.splitlines()]
    per_input = {i["name"]: i for i in stats[2]["sync"]["inputs"]}
    assert per_input["status"]["used"] == len(sets)


def test_named_inputs_are_checked_before_anything_runs(rvc, tmp_path):
    """Usage errors name the problem: a field of no input (with its column), a --type before any
    --input, an unknown --stamp input, a mix of names."""
    base = [rvc, "monitor", "--input", "a=dds:/a", "--input", "b=dds:/b"]
    r = subprocess.run(base + ["--spec", "{a.x} and {speed > 3}"], capture_output=True, text=True)
    assert r.returncode == 2 and "'speed' names no input" in r.stderr and "a, b" in r.stderr, r.stderr
    r = subprocess.run([rvc, "monitor", "--type", VEH + "GearReport", "--input", "a=dds:/a", "--spec", "{a.report}"],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "comes before any --input" in r.stderr, r.stderr
    r = subprocess.run(base + ["--spec", "{a.x}", "--stamp", "c=arrival"], capture_output=True, text=True)
    assert r.returncode == 2 and "--stamp names input 'c'" in r.stderr, r.stderr
    r = subprocess.run([rvc, "monitor", "--input", "dds:/a", "--spec", "{x}", "--sync", "approximate"],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "synchronize several inputs" in r.stderr, r.stderr
    r = subprocess.run(base + ["--input", "c=", "--spec", "{a.x}"], capture_output=True, text=True)
    assert r.returncode == 2 and "no URI after 'c='" in r.stderr, r.stderr
    r = subprocess.run(base + ["--input", "c=file:x.jsonl", "--spec", "{a.x}"], capture_output=True, text=True)
    assert r.returncode == 2 and "not a mix" in r.stderr, r.stderr


def test_typed_sets_are_read_by_a_typed_monitor(rvc, tmp_path, dds):
    """rvc sync --set-type: the sets published as a ROS 2 message of the inputs' types (its .msg
    written for subscribers); `rvc monitor --type` on that topic gives the verdicts `rvc check`
    gives on the same sync's JSON sets."""
    domain = 70 + os.getpid() % 30
    dds_flags = ["--domain", str(domain)]
    traces, _ = make_traces(tmp_path)
    chosen = [t for t in TOPICS if t[0] in ("gear", "steer")]
    sets_json, verdicts, defs = tmp_path / "sets.jsonl", tmp_path / "verdicts.jsonl", tmp_path / "defs"
    inputs = [a for name, topic, type_name, *_ in chosen for a in ("--input", f"{name}=dds:{topic}", "--type",
                                                                     type_name)]
    # Replays at full speed deliver whole topics at once: a queue that holds them all.
    sync = subprocess.Popen([rvc, "sync", *inputs, "--sync", "approximate", "--sync-queue", "200", "--set-type",
                             "rvc_sync/msg/Set",
                             "--set-type-dir", str(defs), "--output", "dds:/rv/synced", "--output",
                             f"file:{sets_json}", "--wait-subscribers", "1", "--idle-timeout", "5", *dds_flags],
                            stderr=subprocess.PIPE, text=True)
    # The definition is written before the outputs wait for their subscriber.
    deadline = HANG_GUARD
    while not (defs / "rvc_sync" / "msg" / "Set.msg").exists() and deadline > 0:
        time.sleep(0.1)
        deadline -= 0.1
    spec = "{gear.report == REVERSE} -> {steer.steering_tire_angle < 0.3}"
    mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", spec, "--input", "dds:/rv/synced", "--type",
                            "rvc_sync/msg/Set", "--msg-path", str(defs), "--output", f"file:{verdicts}",
                            "--idle-timeout", "8", *dds_flags], stderr=subprocess.PIPE, text=True)
    try:
        replays = [subprocess.Popen([rvc, "replay", str(traces[name]), "--to", f"dds:{topic}", "--type", type_name,
                                     "--wait-timeout", "30", "--no-progress", *dds_flags],
                                    stderr=subprocess.PIPE, text=True) for name, topic, type_name, *_ in chosen]
        for p in replays:
            _, err = p.communicate(timeout=HANG_GUARD)
            assert p.returncode == 0, err
        _, sync_err = sync.communicate(timeout=HANG_GUARD)
        _, mon_err = mon.communicate(timeout=HANG_GUARD)
    finally:
        for p in (sync, mon):
            if p.poll() is None:
                p.kill()
    assert sync.returncode == 0, sync_err
    assert "float64 time" in (defs / "rvc_sync" / "msg" / "Set.msg").read_text()
    sets = read_jsonl(sets_json)
    assert len(sets) >= SECONDS * 25 - 2, sync_err
    check = subprocess.run([rvc, "check", "--all", "--spec", "{gear.report == 20} -> {steer.steering_tire_angle < 0.3}",
                            str(sets_json)], capture_output=True, text=True)
    assert read_jsonl(verdicts) == [json.loads(l) for l in check.stdout.splitlines()], mon_err
    assert any(not json.loads(l)["value"] for l in check.stdout.splitlines()), "no violation: a weak test"
