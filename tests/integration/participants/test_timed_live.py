"""Timing atoms on live topics (issue 26): the bag of tests/cli/test_timed_bag.py, published instead
over DDS on loopback by two `rvc replay --type` processes (imu falls silent between stamps 2.0 and
2.5, gear is steady), checked by `rvc monitor` with two named inputs. The verdicts are in stream time
(the messages' stamps), so the live run reports the gap at the same hand-computed instants as the
offline run of the bag: no clock, the monitor steps through the change instants between messages.
"""
import json
import os
import subprocess

import pytest

from conftest import transports_built
from test_python_peers import HANG_GUARD

STEER = "autoware_auto_vehicle_msgs/msg/SteeringReport"
GEAR = "autoware_auto_vehicle_msgs/msg/GearReport"
NS = 10**9
TICK = NS // 16

# The same properties and instants as the bag test (latency left out: live arrival is the wall clock).
PROPERTIES = {
    # (the timeline starts at the first message, imu's at 1.0: --origin first; test_timed_bag.py alike)
    "silence": ("{imu.@age <= 0.125}", [(1.0, True), (2.125, False), (2.5, True)]),
    "rate": ("{count[0:0.5](imu.@arrived) >= 4}", [(1.0, False), (1.1875, True), (2.3125, False), (2.6875, True)]),
    "angle": ("{min[0:0.25](imu.steering_tire_angle) > 0.05}", [(1.0, True), (2.25, False), (2.5, True)]),
    "gear": ("{gear.@age <= 0.125}", [(1.0, False), (1.03125, True)]),
}


@pytest.fixture
def dds(rvc):
    if "dds" not in transports_built(rvc):
        pytest.skip("rvc built without DDS")


def stamp(t):
    return {"sec": t // NS, "nanosec": t % NS}


def test_a_live_gap_gives_the_bags_verdicts(rvc, tmp_path, dds):
    imu = [NS + k * TICK for k in range(33) if not (2 * NS < NS + k * TICK < 2 * NS + NS // 2)]
    gear = [NS + NS // 32 + k * TICK for k in range(32)]
    (tmp_path / "imu.jsonl").write_text("".join(json.dumps({"stamp": stamp(t), "steering_tire_angle": 0.1}) + "\n"
                                                for t in imu))
    (tmp_path / "gear.jsonl").write_text("".join(json.dumps({"stamp": stamp(t), "report": 2}) + "\n" for t in gear))
    props = tmp_path / "props.json"
    props.write_text(json.dumps({"properties": [{"name": n, "spec": s} for n, (s, _) in PROPERTIES.items()]}))
    verdicts = tmp_path / "verdicts.jsonl"
    dds_flags = ["--domain", str(170 + os.getpid() % 30)]
    monitor = subprocess.Popen(
        [rvc, "monitor", "--dense", "--properties", str(props), "--input", "imu=dds:/sensing/imu", "--type", STEER,
         "--input", "gear=dds:/vehicle/gear", "--type", GEAR, "--sync", "merge", "--max-delay", "100",
         "--idle-timeout", "5", "--output", f"file:{verdicts}", *dds_flags], stderr=subprocess.PIPE, text=True)
    try:
        replays = [subprocess.Popen([rvc, "replay", str(tmp_path / f"{name}.jsonl"), "--to", f"dds:{topic}", "--type",
                                     type_name, "--wait-subscribers", "1", "--wait-timeout", "30", "--no-progress",
                                     *dds_flags], stderr=subprocess.PIPE, text=True)
                   for name, topic, type_name in [("imu", "/sensing/imu", STEER), ("gear", "/vehicle/gear", GEAR)]]
        for p in replays:
            _, err = p.communicate(timeout=HANG_GUARD)
            assert p.returncode == 0, err
        _, err = monitor.communicate(timeout=HANG_GUARD)
    finally:
        if monitor.poll() is None:
            monitor.kill()
    assert monitor.returncode == 1, err  # violated, nothing lost or rejected
    stats = json.loads([line for line in err.splitlines() if line.startswith('{"input"')][-1])
    assert stats["received"] == len(imu) + len(gear) and stats["rejected"] == 0, err
    got = {name: [] for name in PROPERTIES}
    for line in verdicts.read_text().splitlines():
        v = json.loads(line)
        got[v["property"]].append((v["time"], v["value"]))
    assert got == {name: expected for name, (_, expected) in PROPERTIES.items()}, err
