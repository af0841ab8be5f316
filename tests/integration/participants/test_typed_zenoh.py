"""Typed ROS 2 input over Zenoh: `rvc monitor --type` reads CDR payloads (as zenoh-bridge-ros2dds
forwards them: the full sample, header included) published by the official Zenoh Python binding,
serialized by rosbags. Oracle: `rvc check` on the same messages written as JSON by the test (from
the values it generated), with the message constants written as their numbers.
Loopback only: explicit tcp/127.0.0.1 port, multicast scouting off.
"""
import json
import random
import struct
import subprocess
import time

import pytest

from conftest import transports_built
from test_python_peers import HANG_GUARD, free_port, wait_for, zsession

GEAR = "autoware_auto_vehicle_msgs/msg/GearReport"
REVERSE, PARK, DRIVE = 20, 22, 2


@pytest.fixture
def zenoh_mod(rvc):
    if "zenoh" not in transports_built(rvc):
        pytest.skip("rvc built without Zenoh")
    return pytest.importorskip("zenoh")


@pytest.fixture
def store(rvc):
    typesys = pytest.importorskip("rosbags.typesys")
    ts = typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)
    text = subprocess.run([rvc, "msg", "show", GEAR], capture_output=True, text=True, check=True).stdout
    top = "\n".join(l for l in text.splitlines() if not l.startswith(("#", "\t")))
    ts.register(typesys.get_types_from_msg(top, GEAR))
    return ts


def gear_samples(ts, n, seed=3):
    rng = random.Random(seed)
    Time, Gear = ts.types["builtin_interfaces/msg/Time"], ts.types[GEAR]
    out = []
    for i in range(n):
        report = rng.choice([REVERSE, PARK, DRIVE, DRIVE, 1])
        stamp = Time(sec=1000 + i // 10, nanosec=(i % 10) * 100_000_000)
        raw = bytes(ts.serialize_cdr(Gear(stamp=stamp, report=report), GEAR, little_endian=rng.random() < 0.8))
        out.append((raw, {"stamp": {"sec": stamp.sec, "nanosec": stamp.nanosec}, "report": report}))
    return out


def run_monitor(rvc, zenoh, spec, payloads, *extra):
    port = free_port()
    ep = f"tcp/127.0.0.1:{port}"
    mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", spec, "--input", "zenoh:rt/vehicle/status/gear_status",
                            "--type", GEAR, "--exit-on-eos", "--mode", "peer", "--listen", ep,
                            "--no-multicast-scouting", *extra],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        time.sleep(0.3)
        s = zsession(zenoh, mode="peer", connect=[ep])
        pub = s.declare_publisher("rt/vehicle/status/gear_status")
        wait_for(lambda: bool(getattr(pub.matching_status, "matching", False)), "rvc monitor to match")
        for i, p in enumerate(payloads, 1):
            pub.put(p, attachment=struct.pack("<QB", i, 0))
        pub.put(b"", attachment=struct.pack("<QB", len(payloads), 1))
        out, err = mon.communicate(timeout=HANG_GUARD)
        s.close()
        return mon.returncode, out, err
    finally:
        if mon.poll() is None:
            mon.kill()


def check_json(rvc, tmp_path, spec, objs):
    f = tmp_path / "oracle.jsonl"
    f.write_text("".join(json.dumps(o) + "\n" for o in objs))
    r = subprocess.run([rvc, "check", "--all", "--spec", spec, str(f)], capture_output=True, text=True)
    return r.returncode, r.stdout


def test_typed_samples_with_constants_equal_check_on_json(rvc, tmp_path, zenoh_mod, store):
    samples = gear_samples(store, 300)
    spec = "historically({report == REVERSE} -> once[0:5]{report: PARK})"
    rc, out, err = run_monitor(rvc, zenoh_mod, spec, [raw for raw, _ in samples])
    stats = json.loads(err.strip().splitlines()[-1])
    assert stats["received"] == 300 and stats["checked"] == 300 and stats["rejected"] == 0, err
    want_rc, want = check_json(rvc, tmp_path, "historically({report == %d} -> once[0:5]{report: %d})" % (REVERSE, PARK),
                               [o for _, o in samples])
    assert out == want
    assert rc == want_rc == 1  # the random gears violate it somewhere


def test_bad_samples_are_rejected_with_seq_and_offset_and_nothing_valid_is_lost(rvc, tmp_path, zenoh_mod, store):
    samples = gear_samples(store, 40, seed=8)
    payloads = [raw for raw, _ in samples]
    payloads.insert(10, payloads[3][:9])          # seq 11: cut inside stamp.nanosec
    payloads.insert(20, b"{\"report\": 20}")      # seq 21: JSON, not CDR
    spec = "{report != NEUTRAL}"
    rc, out, err = run_monitor(rvc, zenoh_mod, spec, payloads)
    stats = json.loads(err.strip().splitlines()[-1])
    assert stats["received"] == 42 and stats["rejected"] == 2 and stats["checked"] == 40, err
    assert "seq 11: bad autoware_auto_vehicle_msgs/msg/GearReport sample: truncated sample in field " \
           "stamp.nanosec at byte 8" in err, err
    assert "seq 21: bad autoware_auto_vehicle_msgs/msg/GearReport sample: unsupported CDR representation" in err
    _, want = check_json(rvc, tmp_path, "{report != 1}", [o for _, o in samples])
    assert out == want
    assert rc == 1  # a rejected message is outranked by the violation


def test_fields_and_constants_are_checked_against_the_type(rvc):
    r = subprocess.run([rvc, "monitor", "--spec", "once{gear.report == REVERSE}", "--input", "zenoh:rt/x",
                        "--type", GEAR, "--no-multicast-scouting"], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2
    assert "no field 'gear' in autoware_auto_vehicle_msgs/msg/GearReport; its fields: stamp, report" in r.stderr
    assert "  once{gear.report == REVERSE}\n       ^\n" in r.stderr, r.stderr  # column 6: the field
    r = subprocess.run([rvc, "monitor", "--spec", "{report == REVERS}", "--input", "zenoh:rt/x",
                        "--type", GEAR, "--no-multicast-scouting"], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2
    assert "'REVERS' is not a constant of autoware_auto_vehicle_msgs/msg/GearReport (its constants: NONE, " \
           "NEUTRAL, DRIVE" in r.stderr, r.stderr
    r = subprocess.run([rvc, "monitor", "--spec", "{report}", "--input", "file:x.jsonl", "--type", GEAR],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and "--type reads typed samples from a dds: topic" in r.stderr, r.stderr


def test_bounded_future_on_typed_samples_equals_check_on_json(rvc, tmp_path, zenoh_mod, store):
    """`eventually` on `monitor --type` was refused at start: "no field 'rvc-end-of-stream' in ..." (issue 36)."""
    samples = gear_samples(store, 120, seed=4)
    spec = "{report == REVERSE} -> eventually[0:3]{report: PARK}"
    rc, out, err = run_monitor(rvc, zenoh_mod, spec, [raw for raw, _ in samples])
    stats = json.loads(err.strip().splitlines()[-1])
    assert stats["received"] == 120 and stats["checked"] == 120, err
    want_rc, want = check_json(rvc, tmp_path, "{report == %d} -> eventually[0:3]{report: %d}" % (REVERSE, PARK),
                               [o for _, o in samples])
    assert out == want and out
    assert rc == want_rc == 1
