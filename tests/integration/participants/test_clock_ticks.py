"""Dense time on a clock, live (issue 26): `rvc monitor --dense --clock stamps` reports a bounded
operator's fall or rise while the publisher is silent, at its exact instant, over Zenoh
(eclipse-zenoh) and DDS (cyclonedds Python).

One scenario per transport: a Python publisher goes steady, stops, slows down, bursts, stops
again and resumes. Stamps are multiples of 1/1024 s, sent on schedule (sleeping until the run's
start + stamp); the bounds are too, so every change instant is one of them.

- Ordering: before each resume the publisher waits for the verdicts of the silence (hand-computed:
  property, instant, value) and records whether they had arrived; they must have, so they were
  received before the publisher resumed. Without ticks none can arrive (the monitor only moves
  with messages), which the same run with `--clock off` shows.
- Values: every verdict up to the last message equals Reelay's (PyPI `reelay`, dense timed monitor)
  on the same messages with heartbeats (empty messages) every 1/1024 s, where Reelay is exact and
  which contain every tick instant: ticks are heartbeats.
Loopback only: Zenoh on tcp/127.0.0.1 with multicast scouting off; DDS with `rvc dds-config`'s
loopback-pinned XML.
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
from test_python_peers import ZenohNet, dds_qos, free_port, wait_for, zsession  # noqa: F401 (fixtures below)

reelay = pytest.importorskip("reelay")

HANG_GUARD = 20  # seconds a resume waits for verdicts before giving up (the test then fails)
GRID = 1 / 1024

PROPERTIES = {
    "alive": "once[0:0.1875]{alive}",           # falls 0.1875 after alive was last true
    "ok": "historically[0:0.3125]{ok}",          # rises 0.3125 after ok turns true
    "run": "{run} since[0:0.4375] {start}",      # falls 0.4375 after start was last true
    "fresh": "{@age <= 0.25}",                    # a timing atom: falls 0.25 after every last message
}
# What Reelay checks for a timing atom: a proposition this test computes itself at every message
# and heartbeat (dense: true on [last, last + 0.25), docs/semantics.md).
ORACLE = {"fresh": "{young}"}
AGE = 0.25


def scenario():
    """[(stamp, fields, verdicts that must have arrived before this message is sent)]."""
    out = []
    for k in range(1, 9):  # steady, 8 Hz
        out.append((0.125 * k, {"alive": k < 8, "ok": True, "run": True, "start": k == 1}, []))
    # stop: alive turned false at 1.0 and silence until 2.0
    out.append((2.0, {"alive": True, "ok": False, "start": True},
                [("alive", 1.1875, False), ("fresh", 1.25, False)]))   # 1.0 + 0.1875, 1.0 + 0.25
    out.append((2.5, {"ok": True, "start": False}, [("fresh", 2.25, False)]))  # slow: 2 Hz
    out.append((3.0, {"alive": True}, [("ok", 2.8125, True),        # 2.5 + 0.3125
                                      ("run", 2.9375, False),       # 2.5 + 0.4375
                                      ("fresh", 2.75, False)]))
    for k in range(1, 21):  # a burst, sent at once
        out.append((3.0 + k * GRID, {"alive": k < 20}, []))
    # stop again: alive false at 3 + 20/1024, silence until 4.0
    out.append((4.0, {"alive": True, "start": True}, [("alive", 3.0 + 20 * GRID + 0.1875, False),
                                                      ("fresh", 3.0 + 20 * GRID + AGE, False)]))
    for k in range(1, 4):
        out.append((4.0 + 0.125 * k, {"alive": True}, []))
    return out


def heartbeats(events):
    """The messages with an empty message at every multiple of GRID between them (none at a message)."""
    out, times = [], {e["time"] for e in events}
    t, k = 0.0, 0
    last = events[-1]["time"]
    beats = []
    while t < last:
        if t not in times:
            beats.append({"time": t})
        k += 1
        t = k * GRID
    out = sorted(events + beats, key=lambda e: e["time"])
    last_message = None
    for e in out:  # the timing atom, computed here: every stamp and AGE are multiples of GRID
        if e["time"] in times:
            last_message = e["time"]
        e["young"] = last_message is not None and e["time"] - last_message < AGE
    return out


def reelay_changes(spec, events):
    m = reelay.dense_timed_monitor(pattern=spec)
    events = [dict(e) for e in events]
    out = []
    for e in heartbeats(events):
        for r in m.update(dict(e)):
            if not out or out[-1][1] != r["value"]:
                out.append((r["time"], r["value"]))
    return out


def condensed(verdicts, name, before):
    out = []
    for v in verdicts:
        if v["property"] == name and v["time"] < before and (not out or out[-1][1] != v["value"]):
            out.append((v["time"], v["value"]))
    return out


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


def play(publish, collected, wait=True):
    """Publishes the scenario on schedule; returns the awaited verdicts that had not arrived at their resume."""
    missing, events = [], []
    start = time.monotonic()
    for stamp, fields, awaited in scenario():
        if awaited:
            deadline = time.monotonic() + (HANG_GUARD if wait else 0)
            while wait and time.monotonic() < deadline and not all(collected.has(*a) for a in awaited):
                time.sleep(0.002)
            missing += [a for a in awaited if not collected.has(*a)]
        delay = start + stamp - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        message = dict(fields, time=stamp)
        events.append(message)
        publish(json.dumps(message))
    return missing, events


def monitor_args(props_path, clock):
    # --origin zero: the oracle is Reelay, whose timeline starts at 0
    return ["monitor", "--dense", "--origin", "zero", "--clock", clock, "--properties", str(props_path)]


def write_properties(tmp_path):
    p = tmp_path / "props.json"
    p.write_text(json.dumps({"properties": [{"name": n, "spec": s} for n, s in PROPERTIES.items()]}))
    return p


def check_run(events, collected, stats):
    assert stats["clock"] == "stamps" and stats["late_to_clock"] == 0, stats
    assert stats["received"] == len(events) == stats["checked"], stats
    last = events[-1]["time"]
    for name, spec in PROPERTIES.items():
        assert condensed(collected.verdicts, name, last) == reelay_changes(ORACLE.get(name, spec), events), name


# ---------------------------------------------------------------- Zenoh

@pytest.fixture
def zenoh_mod(rvc):
    if "zenoh" not in transports_built(rvc):
        pytest.skip("rvc built without Zenoh")
    return pytest.importorskip("zenoh")


def zenoh_run(rvc, tmp_path, zenoh, clock):
    net = ZenohNet(rvc, via_router=False)
    key, vkey = "rvc/tick/in", "rvc/tick/verdicts"
    collected = Collected()
    mon = subprocess.Popen([rvc, *monitor_args(write_properties(tmp_path), clock), "--input", f"zenoh:{key}",
                            "--output", f"zenoh:{vkey}", "--exit-on-eos", *net.monitor],
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
        pub = s.declare_publisher(key)
        wait_for(lambda: bool(getattr(pub.matching_status, "matching", False)), "rvc monitor to match")
        seq = [0]

        def publish(text):
            seq[0] += 1
            pub.put(text, attachment=struct.pack("<QB", seq[0], 0))

        missing, events = play(publish, collected, wait=clock != "off")
        pub.put(b"", attachment=struct.pack("<QB", seq[0], 1))
        _, err = mon.communicate(timeout=60)
        time.sleep(0.2)  # the last verdicts in flight
        sub.undeclare()
        s.close()
        return missing, events, collected, json.loads(err.strip().splitlines()[-1]), err
    finally:
        if mon.poll() is None:
            mon.kill()
        net.close()


def test_zenoh_silences_are_reported_before_the_publisher_resumes(rvc, tmp_path, zenoh_mod):
    missing, events, collected, stats, err = zenoh_run(rvc, tmp_path, zenoh_mod, "stamps")
    assert not missing, f"verdicts not received before the publisher resumed: {missing}\n{err}"
    check_run(events, collected, stats)


def test_zenoh_without_a_clock_silences_wait_for_the_next_message(rvc, tmp_path, zenoh_mod):
    missing, _, collected, stats, _ = zenoh_run(rvc, tmp_path, zenoh_mod, "off")
    awaited = [a for _, _, aw in scenario() for a in aw]
    assert missing == awaited  # none had come when the publisher resumed ...
    assert all(collected.has(*a) for a in awaited)  # ... all came with the next message
    assert "clock" not in stats


# ---------------------------------------------------------------- DDS

@pytest.fixture
def dds_env(rvc, tmp_path, monkeypatch):
    if "dds" not in transports_built(rvc):
        pytest.skip("rvc built without DDS")
    loopback_dds(rvc, tmp_path, monkeypatch)  # before any Python participant exists
    pytest.importorskip("cyclonedds")
    return ros_idl_types().String_


def test_dds_silences_are_reported_before_the_publisher_resumes(rvc, tmp_path, dds_env):
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    String_ = dds_env
    domain = 150 + os.getpid() % 50
    collected = Collected()
    mon = subprocess.Popen([rvc, *monitor_args(write_properties(tmp_path), "stamps"), "--input", "dds:/rvc_tick/in",
                            "--output", "dds:/rvc_tick/verdicts", "--domain", str(domain)],
                           stderr=subprocess.PIPE, text=True)
    try:
        dp = DomainParticipant(domain)
        reader = DataReader(dp, Topic(dp, "rt/rvc_tick/verdicts", String_), qos=dds_qos())
        writer = DataWriter(dp, Topic(dp, "rt/rvc_tick/in", String_), qos=dds_qos())
        wait_for(lambda: dds_matched(writer) and dds_matched(reader), "rvc monitor to match both topics")
        stop = threading.Event()

        def collect():  # a reader thread: verdicts are seen while the publisher sleeps
            while not stop.is_set():
                for s in reader.take(N=100):
                    collected.add(s.data)
                time.sleep(0.001)

        t = threading.Thread(target=collect)
        t.start()
        try:
            missing, events = play(lambda text: writer.write(String_(data=text)), collected)
            time.sleep(0.3)  # the last verdicts in flight
        finally:
            stop.set()
            t.join()
        mon.terminate()
        _, err = mon.communicate(timeout=60)
        assert not missing, f"verdicts not received before the publisher resumed: {missing}\n{err}"
        check_run(events, collected, json.loads(err.strip().splitlines()[-1]))
    finally:
        if mon.poll() is None:
            mon.kill()
