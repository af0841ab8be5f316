"""rvc hz on live topics: a Python publisher sends std_msgs/msg/Header samples at a steady rate,
then stops. The DiagnosticArray rvc hz publishes goes OK while samples arrive, then ERROR with
status Timeout while nothing is published: on the timer, well before the next periodic report
(--period 30 here, so a Timeout found only at the next report would never be seen in time).
Independent decoders: cyclonedds Python (IdlStruct classes written here, the rosidl mapping of
diagnostic_msgs) on DDS, rosbags' deserializer on Zenoh. The Timeout's own stamp is checked
against the last sample's stamp (both on this host's clock): no earlier than the timeout.
Loopback only: `rvc dds-config` XML pinned to lo; Zenoh on tcp/127.0.0.1, multicast scouting off.
"""
import json
import os
import signal
import subprocess
import time

import pytest

from conftest import transports_built
from ros_idl_types import loopback_dds, ros_idl_types
from rvc_testlib import dds_matched
from test_python_peers import HANG_GUARD, dds_qos, free_port, wait_for, zsession

N = 30          # samples published
GAP = 0.05      # seconds between them (20 Hz)
TIMEOUT = 0.5   # rvc hz --timeout
GUARD = 15      # bound on waiting for the Timeout status: far below --period 30


def stamp_of(t):
    return t.sec + t.nanosec * 1e-9


def check_run(mon, arrays, topic, last_sent_stamp):
    """arrays: (header stamp, {name: (level, message, values)}) in arrival order."""
    name = f"rvc hz: {topic}"
    levels = [(st, s[name]) for st, s in arrays if name in s]
    ok = [x for x in levels if x[1][0] == 0]
    assert ok, levels
    timeout = [x for x in levels if x[1][0] == 2 and x[1][2].get("status") == "Timeout"]
    assert timeout, levels
    # OK came before the Timeout, and the Timeout no earlier than TIMEOUT after the last sample.
    assert levels.index(ok[0]) < levels.index(timeout[0])
    assert timeout[0][0] - last_sent_stamp > TIMEOUT
    values = timeout[0][1][2]
    assert values["received"] == str(N) and values["rejected"] == "0"
    assert values["window_size"] == "10" and values["timeout"] == "0.5"
    assert float(values["latency_mean_s"]) > 0  # header.stamp read: arrival after the stamp
    assert float(values["silence_s"]) > TIMEOUT
    print(f"{topic}: Timeout published at a silence of {values['silence_s']} s (timeout {TIMEOUT} s)")
    # SIGTERM flushes the final report and the per-topic line; the topic ended Timeout: exit 1.
    mon.send_signal(signal.SIGTERM)
    out, err = mon.communicate(timeout=HANG_GUARD)
    assert mon.returncode == 1, err
    final = [json.loads(l) for l in out.splitlines() if '"final":true' in l]
    assert len(final) == 1 and final[0]["received"] == N and final[0]["state"] == "Timeout"
    assert f"received {N} (checked {N}, rejected 0), final state Timeout" in err


# ---------------------------------------------------------------- DDS

@pytest.fixture
def dds_types(rvc, tmp_path, monkeypatch):
    if "dds" not in transports_built(rvc):
        pytest.skip("rvc built without DDS")
    loopback_dds(rvc, tmp_path, monkeypatch)  # before any Python participant exists
    pytest.importorskip("cyclonedds")
    t = ros_idl_types()
    return t.Time_, t.Header_, t.DiagnosticArray_


def test_dds_topic_goes_ok_then_timeout_on_diagnostics(rvc, dds_types):
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    Time_, Header_, DiagnosticArray_ = dds_types
    domain = 120 + os.getpid() % 30
    mon = subprocess.Popen([rvc, "hz", "dds:/rvc_hz/in", "--type", "std_msgs/msg/Header", "--timeout", str(TIMEOUT),
                            "--period", "30", "--json", "--diagnostics", "dds:/diagnostics", "--domain", str(domain),
                            "--duration", str(HANG_GUARD)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        dp = DomainParticipant(domain)
        reader = DataReader(dp, Topic(dp, "rt/diagnostics", DiagnosticArray_), qos=dds_qos())
        writer = DataWriter(dp, Topic(dp, "rt/rvc_hz/in", Header_), qos=dds_qos())
        wait_for(lambda: dds_matched(writer) and dds_matched(reader), "rvc hz to match both topics")
        arrays = []

        def collect():
            for s in reader.take(N=100):
                arrays.append((stamp_of(s.header.stamp),
                               {st.name: (st.level, st.message, {kv.key: kv.value for kv in st.values})
                                for st in s.status}))
        last = 0.0
        for i in range(N):
            now = time.time()
            stamp = Time_(sec=int(now), nanosec=int((now - int(now)) * 1e9))
            last = stamp_of(stamp)
            writer.write(Header_(stamp=stamp, frame_id=str(i)))
            collect()
            time.sleep(GAP)
        deadline = time.time() + GUARD

        def timed_out():
            collect()
            return any(s.get("rvc hz: dds:/rvc_hz/in", (0, "", {}))[2].get("status") == "Timeout" for _, s in arrays)
        while time.time() < deadline and not timed_out():
            time.sleep(0.05)
        check_run(mon, arrays, "dds:/rvc_hz/in", last)
    finally:
        if mon.poll() is None:
            mon.kill()


# ---------------------------------------------------------------- Zenoh

def test_zenoh_topic_goes_ok_then_timeout_on_diagnostics(rvc):
    if "zenoh" not in transports_built(rvc):
        pytest.skip("rvc built without Zenoh")
    zenoh = pytest.importorskip("zenoh")
    typesys = pytest.importorskip("rosbags.typesys")
    ts = typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)
    Time, Header = ts.types["builtin_interfaces/msg/Time"], ts.types["std_msgs/msg/Header"]
    ep = f"tcp/127.0.0.1:{free_port()}"
    mon = subprocess.Popen([rvc, "hz", "zenoh:rt/rvc_hz/in", "--type", "std_msgs/msg/Header", "--timeout",
                            str(TIMEOUT), "--period", "30", "--json", "--diagnostics", "zenoh:rvc_hz/diagnostics",
                            "--mode", "peer", "--listen", ep, "--no-multicast-scouting", "--duration", str(HANG_GUARD)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    s = None
    try:
        time.sleep(0.3)
        s = zsession(zenoh, mode="peer", connect=[ep])
        arrays = []

        def on_sample(sample):
            msg = ts.deserialize_cdr(bytes(sample.payload.to_bytes()), "diagnostic_msgs/msg/DiagnosticArray")
            arrays.append((stamp_of(msg.header.stamp),
                           {st.name: (int(st.level), st.message, {kv.key: kv.value for kv in st.values})
                            for st in msg.status}))
        sub = s.declare_subscriber("rvc_hz/diagnostics", on_sample)
        pub = s.declare_publisher("rt/rvc_hz/in")
        wait_for(lambda: bool(getattr(pub.matching_status, "matching", False)), "rvc hz to match")
        last = 0.0
        for i in range(N):
            now = time.time()
            stamp = Time(sec=int(now), nanosec=int((now - int(now)) * 1e9))
            last = stamp_of(stamp)
            pub.put(bytes(ts.serialize_cdr(Header(stamp=stamp, frame_id=str(i)), "std_msgs/msg/Header")))
            time.sleep(GAP)
        deadline = time.time() + GUARD
        while time.time() < deadline and not any(
                x.get("rvc hz: zenoh:rt/rvc_hz/in", (0, "", {}))[2].get("status") == "Timeout" for _, x in list(arrays)):
            time.sleep(0.05)
        check_run(mon, list(arrays), "zenoh:rt/rvc_hz/in", last)
        sub.undeclare()
    finally:
        if mon.poll() is None:
            mon.kill()
        if s is not None:
            s.close()
