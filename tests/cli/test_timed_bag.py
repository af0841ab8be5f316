"""A recorded gap is found without a clock (issue 26): a ROS 2 bag (MCAP, written by rosbags) with
two topics, one of which falls silent for half a second, checked with timing atoms. The instants
are hand-computed: every stamp is a multiple of 1/64 s, so they are exact in binary and rvc must
report them exactly. `rvc check BAG` and `rvc monitor --input mcap:BAG` give the same verdicts.
"""
import json
import os
import subprocess

import pytest

from conftest import transports_built

pytestmark = pytest.mark.needs_rust  # the MCAP reader is in the Rust library

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEFS = os.path.join(ROOT, "src", "msg", "definitions")
GEAR = "autoware_auto_vehicle_msgs/msg/GearReport"
STEER = "autoware_auto_vehicle_msgs/msg/SteeringReport"
NS = 10**9
TICK = NS // 16  # 62.5 ms: both topics publish at 16 Hz


@pytest.fixture
def bag(rvc, tmp_path):
    if "zenoh" not in transports_built(rvc):
        pytest.fail("this rvc was built without its Rust library (RVC_WITH_ZENOH=OFF): no MCAP")
    from rosbags.rosbag2 import Writer
    from rosbags.rosbag2.enums import StoragePlugin
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg
    ts = get_typestore(Stores.ROS2_HUMBLE)
    for name in (GEAR, STEER):
        with open(os.path.join(DEFS, name.split("/")[0], "msg", name.split("/")[-1] + ".msg")) as f:
            ts.register(get_types_from_msg(f.read(), name))
    Time = ts.types["builtin_interfaces/msg/Time"]
    # imu (a SteeringReport): stamps 1.0, 1.0625, ..., 2.0, then silent until 2.5, then on to 3.0.
    # From 2.5 on it is logged (arrives) 0.25 s after its stamp, before that 1/64 s after.
    imu = [NS + k * TICK for k in range(33) if not (2 * NS < NS + k * TICK < 2 * NS + NS // 2)]
    gear = [NS + NS // 32 + k * TICK for k in range(32)]  # steady, between imu's stamps
    events = []
    for t in imu:
        late = NS // 4 if t >= 2 * NS + NS // 2 else NS // 64
        events.append((t + late, "imu", ts.types[STEER](stamp=Time(sec=t // NS, nanosec=t % NS),
                                                        steering_tire_angle=0.1), STEER))
    for t in gear:
        events.append((t + NS // 64, "gear", ts.types[GEAR](stamp=Time(sec=t // NS, nanosec=t % NS), report=2), GEAR))
    folder = tmp_path / "drive"
    with Writer(folder, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conns = {"imu": w.add_connection("/sensing/imu", STEER, typestore=ts),
                 "gear": w.add_connection("/vehicle/gear", GEAR, typestore=ts)}
        for log, topic, msg, name in sorted(events, key=lambda e: e[0]):
            w.write(conns[topic], log, ts.serialize_cdr(msg, name))
    return str(next(folder.glob("*.mcap")))


PROPERTIES = {
    # (the timeline starts at the first message, imu's at 1.0: --origin first)
    # silence: imu's last message before the gap is at 2.0, so false from 2.0 + 0.125 until 2.5
    "silence": ("{imu.@age <= 0.125}", [(1.0, True), (2.125, False), (2.5, True)]),
    # rate: at least 4 imu messages in the last 0.5 s (the window (t-0.5, t]); the fourth-last before
    # the gap (1.8125) leaves at 2.3125; after it the fourth message is at 2.6875
    "rate": ("{count[0:0.5](imu.@arrived) >= 4}", [(1.0, False), (1.1875, True), (2.3125, False), (2.6875, True)]),
    # latency: arrival (log time) - stamp is 1/64 s, then 0.25 s from 2.5 on; unknown before any message
    "latency": ("{imu.@latency < 0.125}", [(1.0, True), (2.5, False)]),
    # a typed field's window: imu's angle (0.1) has a sample in (t-0.25, t] except from 2.0 + 0.25 to 2.5
    "angle": ("{min[0:0.25](imu.steering_tire_angle) > 0.05}", [(1.0, True), (2.25, False), (2.5, True)]),
    # the steady topic never falls silent for 0.125 s: one verdict, true from its first message
    "gear": ("{gear.@age <= 0.125}", [(1.0, False), (1.03125, True)]),
}


def verdicts(stdout):
    out = {name: [] for name in PROPERTIES}
    for line in stdout.splitlines():
        v = json.loads(line)
        if "property" in v:
            out[v["property"]].append((v["time"], v["value"]))
    return out


def test_a_gap_in_one_topic_is_reported_at_the_exact_instants(rvc, tmp_path, bag):
    props = tmp_path / "props.json"
    props.write_text(json.dumps({"properties": [{"name": n, "spec": s} for n, (s, _) in PROPERTIES.items()]}))
    topics = ["--topic", "imu=/sensing/imu", "--topic", "gear=/vehicle/gear"]
    want = {name: expected for name, (_, expected) in PROPERTIES.items()}
    check = subprocess.run([rvc, "check", "--dense", "--properties", str(props), bag, *topics],
                           capture_output=True, text=True, timeout=120)
    assert check.returncode == 1, check.stderr  # violated: the gap
    assert verdicts(check.stdout) == want, check.stderr
    monitor = subprocess.run([rvc, "monitor", "--dense", "--properties", str(props), "--input", f"mcap:{bag}", *topics],
                             capture_output=True, text=True, timeout=120)
    assert verdicts(monitor.stdout) == want, monitor.stderr


def test_an_aggregate_of_a_field_the_type_lacks_is_a_spec_error(rvc, bag):
    r = subprocess.run([rvc, "check", "--dense", "--spec", "{imu.@age < 1} and {avg[0:1](imu.steering) > 0}", bag,
                        "--topic", "imu=/sensing/imu", "--topic", "gear=/vehicle/gear"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "no field 'steering'" in r.stderr and "column 21" in r.stderr, r.stderr
