"""ROS time from /clock, live (issue 26): `rvc monitor --dense --clock ros=dds:/clock` ticks as a
simulator's /clock (rosgraph_msgs/Clock, cyclonedds Python) passes the properties' deadlines.

The data publisher sends alive at 0.5 and alive:false at 1.0, then stays silent while /clock runs
from 0 to 25 s of simulated time in about a second (25 times faster than real time). By hand:
alive holds on [0.5, 1.0), so once[0:2]{alive} falls at 3.0 and once[0:20]{alive} at 21.0.

- Ordering: before its next message (stamped 25.0) the data publisher waits for both falls and
  records whether they had arrived; with the ros clock they must have, at exactly 3.0 and 21.0.
- The same run on the stamps clock (real-time speed from the last stamp): the fall at 21.0 is 20
  wall seconds after the last message, far beyond the ~1 s /clock takes, so it is missing at the
  resume and comes only with the next message. The difference is /clock's.
- /clock is no checked input: received and checked count the data only; clock_messages counts
  /clock; a /clock going back (a simulator reset) is ignored and counted as clock_backwards.
Over Zenoh, /clock alternates rmw_zenoh's CDR samples and JSON Clocks; the same falls must come
before the resume. Loopback only: Zenoh on tcp/127.0.0.1 with multicast scouting off; DDS with `rvc dds-config`'s loopback-pinned XML.
"""
import json
import os
import struct
import subprocess
import threading
import time

import pytest

from conftest import transports_built
from ros_idl_types import loopback_dds, ros_idl_types
from rvc_testlib import dds_matched
from test_python_peers import ZenohNet, dds_qos, wait_for, zsession

HANG_GUARD = 20  # seconds the resume waits for the falls before giving up (the test then fails)
PROPERTIES = {"short": "once[0:2]{alive}", "long": "once[0:20]{alive}"}
FALLS = [("short", 3.0, False), ("long", 21.0, False)]
CLOCK_STEP = 0.05  # simulated seconds per /clock message, one every 2 ms of real time
CLOCK_END = 25.0


@pytest.fixture
def ros_types(rvc, tmp_path, monkeypatch):
    if "dds" not in transports_built(rvc):
        pytest.skip("rvc built without DDS")
    loopback_dds(rvc, tmp_path, monkeypatch)  # before any Python participant exists
    pytest.importorskip("cyclonedds")
    t = ros_idl_types()
    return t.String_, t.Time_, t.Clock_


class Collected:
    def __init__(self):
        self.lock = threading.Lock()
        self.verdicts = []

    def add(self, text):
        with self.lock:
            self.verdicts.append(json.loads(text))

    def has(self, name, t, value):
        with self.lock:
            return any(v["property"] == name and v["time"] == t and v["value"] == value for v in self.verdicts)

    def changes(self, name, before):
        """The property's verdicts before `before`, as (time, value) changes."""
        out = []
        with self.lock:
            for v in self.verdicts:
                if v["property"] == name and v["time"] < before and (not out or out[-1][1] != v["value"]):
                    out.append((v["time"], v["value"]))
        return out


def run(rvc, tmp_path, ros_types, clock):
    """One run: returns (falls missing at the resume, collected verdicts, final stats, stderr)."""
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    String_, Time_, Clock_ = ros_types
    domain = 100 + os.getpid() % 50
    props = tmp_path / "props.json"
    props.write_text(json.dumps({"properties": [{"name": n, "spec": s} for n, s in PROPERTIES.items()]}))
    mon = subprocess.Popen([rvc, "monitor", "--dense", "--clock", clock, "--properties", str(props),
                            "--input", "dds:/rvc_rosclock/in", "--output", "dds:/rvc_rosclock/verdicts",
                            "--domain", str(domain)], stderr=subprocess.PIPE, text=True)
    try:
        dp = DomainParticipant(domain)
        reader = DataReader(dp, Topic(dp, "rt/rvc_rosclock/verdicts", String_), qos=dds_qos())
        writer = DataWriter(dp, Topic(dp, "rt/rvc_rosclock/in", String_), qos=dds_qos())
        clock_writer = DataWriter(dp, Topic(dp, "rt/clock", Clock_), qos=dds_qos())
        ros = clock.startswith("ros=")
        wait_for(lambda: dds_matched(writer) and dds_matched(reader) and (not ros or dds_matched(clock_writer)),
                 "rvc monitor to match its topics")
        collected = Collected()
        stop = threading.Event()

        def collect():  # a reader thread: verdicts are seen while the publishers go on
            while not stop.is_set():
                for s in reader.take(N=100):
                    collected.add(s.data)
                time.sleep(0.001)

        def tick(t):
            sec = int(t)
            clock_writer.write(Clock_(clock=Time_(sec=sec, nanosec=round((t - sec) * 1e9))))

        t = threading.Thread(target=collect)
        t.start()
        try:
            writer.write(String_(data=json.dumps({"time": 0.5, "alive": True})))
            writer.write(String_(data=json.dumps({"time": 1.0, "alive": False})))
            # The simulator's clock, far faster than real time (steps are multiples of 1/20 s,
            # computed as k/20 so that 3.0 and 21.0 are exact).
            steps = round(CLOCK_END / CLOCK_STEP)
            for k in range(steps + 1):
                tick(k / 20)
                time.sleep(0.002)
            deadline = time.monotonic() + (HANG_GUARD if ros else 0)
            while time.monotonic() < deadline and not all(collected.has(*f) for f in FALLS):
                time.sleep(0.002)
            missing = [f for f in FALLS if not collected.has(*f)]
            writer.write(String_(data=json.dumps({"time": CLOCK_END, "alive": True})))
            tick(1.0)  # a simulator reset: /clock goes back
            time.sleep(0.5)  # the last verdicts and clocks in flight
        finally:
            stop.set()
            t.join()
        mon.terminate()
        _, err = mon.communicate(timeout=60)
        return missing, collected, json.loads(err.strip().splitlines()[-1]), err, steps + 2
    finally:
        if mon.poll() is None:
            mon.kill()


def test_ros_clock_ticks_as_clock_passes_the_deadlines(rvc, tmp_path, ros_types):
    missing, collected, stats, err, clocks = run(rvc, tmp_path, ros_types, "ros=dds:/clock")
    assert not missing, f"falls not received before the data publisher resumed: {missing}\n{err}"
    # By hand: true from the first message at 0.5 (the timeline starts there), falling exactly at 3.0 and 21.0.
    assert collected.changes("short", CLOCK_END) == [(0.5, True), (3.0, False)]
    assert collected.changes("long", CLOCK_END) == [(0.5, True), (21.0, False)]
    assert stats["clock"] == "ros", stats
    assert stats["received"] == 3 == stats["checked"], stats  # /clock is not checked
    assert stats["clock_messages"] == clocks, stats  # reliable, keep-all: every one arrives
    assert stats["clock_backwards"] == 1, stats
    assert stats["late_to_clock"] == 0, stats
    assert "/clock went back from 25 to 1" in err


def test_stamps_clock_runs_at_real_time_speed(rvc, tmp_path, ros_types):
    missing, collected, stats, err, _ = run(rvc, tmp_path, ros_types, "stamps")
    # 3.0 is two wall seconds after the last message: it may or may not be out; 21.0 is twenty.
    assert ("long", 21.0, False) in missing, err
    assert collected.has("long", 21.0, False)  # ... came with the next message
    assert stats["clock"] == "stamps" and "clock_messages" not in stats, stats


def test_zenoh_ros_clock_takes_cdr_and_json(rvc, tmp_path):
    if "zenoh" not in transports_built(rvc):
        pytest.skip("rvc built without Zenoh")
    zenoh = pytest.importorskip("zenoh")
    net = ZenohNet(rvc, via_router=False)
    key, ckey, vkey = "rvc/rosclock/in", "rvc/rosclock/clock", "rvc/rosclock/verdicts"
    props = tmp_path / "props.json"
    props.write_text(json.dumps({"properties": [{"name": n, "spec": s} for n, s in PROPERTIES.items()]}))
    collected = Collected()
    mon = subprocess.Popen([rvc, "monitor", "--dense", "--clock", f"ros=zenoh:{ckey}", "--properties", str(props),
                            "--input", f"zenoh:{key}", "--output", f"zenoh:{vkey}", "--exit-on-eos", *net.monitor],
                           stderr=subprocess.PIPE, text=True)
    try:
        time.sleep(0.3)  # let the monitor listen before Python connects to it
        s = zsession(zenoh, **net.py)

        def on_verdict(sample):
            att = sample.attachment
            if att is not None and len(att.to_bytes()) >= 9 and att.to_bytes()[8] & 1:
                return  # the verdict stream's end-of-stream marker
            collected.add(sample.payload.to_bytes().decode())

        sub = s.declare_subscriber(vkey, on_verdict)
        pub, cpub = s.declare_publisher(key), s.declare_publisher(ckey)
        wait_for(lambda: all(getattr(p.matching_status, "matching", False) for p in (pub, cpub)),
                 "rvc monitor to match")
        pub.put(json.dumps({"time": 0.5, "alive": True}), attachment=struct.pack("<QB", 1, 0))
        pub.put(json.dumps({"time": 1.0, "alive": False}), attachment=struct.pack("<QB", 2, 0))
        for k in range(round(CLOCK_END / CLOCK_STEP) + 1):
            sec, nanosec = divmod(k * 50_000_000, 1_000_000_000)
            if k % 2:  # CDR, little endian: header, int32 sec, uint32 nanosec
                cpub.put(b"\x00\x01\x00\x00" + struct.pack("<iI", sec, nanosec))
            else:
                cpub.put(json.dumps({"clock": {"sec": sec, "nanosec": nanosec}}))
            time.sleep(0.002)
        deadline = time.monotonic() + HANG_GUARD
        while time.monotonic() < deadline and not all(collected.has(*f) for f in FALLS):
            time.sleep(0.002)
        missing = [f for f in FALLS if not collected.has(*f)]
        pub.put(json.dumps({"time": CLOCK_END, "alive": True}), attachment=struct.pack("<QB", 3, 0))
        pub.put(b"", attachment=struct.pack("<QB", 3, 1))
        _, err = mon.communicate(timeout=60)
        sub.undeclare()
        s.close()
        stats = json.loads(err.strip().splitlines()[-1])
        assert not missing, f"falls not received before the data publisher resumed: {missing}\n{err}"
        assert collected.changes("short", CLOCK_END) == [(0.5, True), (3.0, False)]
        assert stats["received"] == 3 == stats["checked"], stats
        assert stats["clock_messages"] >= 1 and stats["clock_malformed"] == 0, stats
    finally:
        if mon.poll() is None:
            mon.kill()
        net.close()


def test_clock_messages_do_not_hold_off_the_idle_timeout(rvc, tmp_path):
    """/clock is no data: a simulator whose clock runs on while the checked input is silent does not
    keep the monitor alive past --idle-timeout (it ends by idle-timeout while /clock is published)."""
    if "zenoh" not in transports_built(rvc):
        pytest.skip("rvc built without Zenoh")
    zenoh = pytest.importorskip("zenoh")
    net = ZenohNet(rvc, via_router=False)
    key, ckey = "rvc/rosclock_idle/in", "rvc/rosclock_idle/clock"
    mon = subprocess.Popen([rvc, "monitor", "--dense", "--clock", f"ros=zenoh:{ckey}", "--spec", "once[0:2]{alive}",
                            "--input", f"zenoh:{key}", "--idle-timeout", "1", *net.monitor],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        time.sleep(0.3)
        s = zsession(zenoh, **net.py)
        pub, cpub = s.declare_publisher(key), s.declare_publisher(ckey)
        wait_for(lambda: all(getattr(p.matching_status, "matching", False) for p in (pub, cpub)),
                 "rvc monitor to match")
        pub.put(json.dumps({"time": 0.5, "alive": True}), attachment=struct.pack("<QB", 1, 0))
        k = 0
        deadline = time.monotonic() + HANG_GUARD
        while mon.poll() is None and time.monotonic() < deadline:  # /clock on, data silent
            k += 1
            cpub.put(json.dumps({"clock": k * 0.01}))
            time.sleep(0.01)
        still_running = mon.poll() is None
        s.close()
        if still_running:
            mon.kill()
        _, err = mon.communicate(timeout=30)
        assert not still_running, "the monitor did not end by --idle-timeout while /clock ran on"
        assert "ended by idle-timeout" in err or '"received":1' in err, err
        stats = json.loads(err.strip().splitlines()[-1])
        assert stats["received"] == 1 == stats["checked"] and stats["clock_messages"] >= 1, stats
    finally:
        if mon.poll() is None:
            mon.kill()
        net.close()


@pytest.mark.parametrize("value, why", [
    ("ros=", "not an empty URI"),
    ("ros=mcap:x.mcap", "not 'mcap:x.mcap'"),
    ("ros=http:x", "unknown endpoint scheme"),
    ("ros=dds:", "names no topic"),
    ("ros", "auto, wall, stamps, off or ros=URI"),
    ("sim", "auto, wall, stamps, off or ros=URI"),
])
def test_bad_ros_clock_values_exit_2(rvc, value, why):
    r = subprocess.run([rvc, "monitor", "--dense", "--clock", value, "--spec", "{p}", "--input", "file:/dev/null"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 2, r.stderr
    assert why in r.stderr, r.stderr
