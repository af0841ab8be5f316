"""rvc monitor's health for ROS 2 tools: --diagnostics publishes diagnostic_msgs/msg/DiagnosticArray
(one status per property, one for the monitor), and the monitor announces itself so that a dead
one is seen (docs/diagnostics.md).

Independent decoders of what rvc publishes (neither uses rvc's encoder):
- DDS: CycloneDDS's Python binding reads rt/diagnostics with an IdlStruct of DiagnosticArray
  declared here (as rosidl maps the .msg), with a ROS 2 subscriber's default QoS;
- Zenoh: each CDR payload is deserialized by rosbags with its own diagnostic_msgs types, and by
  the same IdlStruct; both must agree.
Liveliness: a cyclonedds reader that requests a 1.5 s lease (it matches only a writer offering at
most that) sees the writer lose liveliness after SIGKILL; a Zenoh liveliness subscriber sees the
token rvc/monitors/<name> appear, and go after SIGKILL.
Loopback only: the loopback-pinned XML of `rvc dds-config`; Zenoh on tcp/127.0.0.1, no scouting.
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
from test_python_peers import HANG_GUARD, free_port, wait_for, zsession

OK, WARN, ERROR, STALE = 0, 1, 2, 3
SPECS = ["--spec", "{ok}", "--spec", "{speed < 10}", "--level", "p2=warn"]
GOOD = json.dumps({"ok": True, "speed": 1})
BAD = json.dumps({"ok": False, "speed": 20})


def by_name(statuses):
    """{name: (level, message, hardware_id, {key: value})} of one decoded array."""
    return {s.name: (int(s.level), s.message, s.hardware_id, {kv.key: kv.value for kv in s.values})
            for s in statuses}


def check_violated(st, name, received_at_least):
    """The array after BAD: p1 ERROR (default level), p2 WARN (--level p2=warn), monitor OK."""
    p1, p2, mon = st[f"rvc: {name}/p1"], st[f"rvc: {name}/p2"], st[f"rvc: {name}/monitor"]
    assert (p1[0], p1[1]) == (ERROR, "violated")
    assert (p2[0], p2[1]) == (WARN, "violated")
    assert p1[3]["spec"] == "{ok}" and p2[3]["spec"] == "{speed < 10}"
    assert p1[3]["verdict"] == "false" and p1[3]["violations"] == "1"
    assert p1[3]["on_violation"] == "ERROR" and p2[3]["on_violation"] == "WARN"
    assert p1[2] and p1[2] == mon[2]  # hardware_id: the host
    assert mon[0] == OK and int(mon[3]["received"]) >= received_at_least
    assert int(mon[3]["rejected"]) == 0


# ---------------------------------------------------------------- DDS

def diagnostic_idl_types():
    """DiagnosticArray and std_msgs/String as cyclonedds IdlStructs, as rosidl maps the .msg files."""
    t = ros_idl_types()
    return t.DiagnosticArray_, t.String_


@pytest.fixture
def dds_types(rvc, tmp_path, monkeypatch):
    if "dds" not in transports_built(rvc):
        pytest.skip("rvc built without DDS")
    loopback_dds(rvc, tmp_path, monkeypatch)  # before any Python participant exists
    pytest.importorskip("cyclonedds")
    return diagnostic_idl_types()


def ros2_default_reader_qos():
    """What a ROS 2 subscription asks for by default (rclcpp: reliable, volatile, keep-last 10,
    liveliness automatic with an infinite lease), read as rmw_cyclonedds does (XCDR1)."""
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.util import duration
    return Qos(Policy.Reliability.Reliable(duration(milliseconds=100)), Policy.History.KeepLast(10),
               Policy.Durability.Volatile, Policy.DataRepresentation(use_cdrv0_representation=True))


def writer_qos():
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.util import duration
    return Qos(Policy.Reliability.Reliable(duration(seconds=30)), Policy.History.KeepAll, Policy.Durability.Volatile)


def test_dds_diagnostics_decode_with_cyclonedds(rvc, tmp_path, dds_types):
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    DiagnosticArray_, String_ = dds_types
    domain = 100 + os.getpid() % 50
    jsonl = tmp_path / "diag.jsonl"
    mon = subprocess.Popen([rvc, "monitor", *SPECS, "--input", "dds:/rvc_diag/in", "--output", f"file:{tmp_path}/v",
                            "--diagnostics", "dds:/diagnostics", "--diagnostics", f"file:{jsonl}",
                            "--name", "ddsmon", "--diagnostics-period", "0.2", "--domain", str(domain)],
                           stderr=subprocess.PIPE, text=True)
    try:
        dp = DomainParticipant(domain)
        reader = DataReader(dp, Topic(dp, "rt/diagnostics", DiagnosticArray_), qos=ros2_default_reader_qos())
        writer = DataWriter(dp, Topic(dp, "rt/rvc_diag/in", String_), qos=writer_qos())
        wait_for(lambda: dds_matched(writer) and dds_matched(reader), "rvc monitor to match both topics")
        arrays = []

        def until(pred):
            def poll():
                arrays.extend(reader.take(N=100))
                return any(pred(by_name(a.status)) for a in arrays)
            return poll

        # Before any message: the properties are STALE (no verdict), the monitor itself OK.
        wait_for(until(lambda st: st.get("rvc: ddsmon/p1", (None,))[0] == STALE
                       and st["rvc: ddsmon/monitor"][0] == OK), "a first array")
        for _ in range(3):
            writer.write(String_(data=GOOD))
        wait_for(until(lambda st: st["rvc: ddsmon/p1"][0] == OK and st["rvc: ddsmon/p2"][0] == OK), "both OK")
        writer.write(String_(data=BAD))
        # The array sent at the change may carry the counters of the tick before; a periodic one follows.
        wait_for(until(lambda st: st["rvc: ddsmon/p1"][0] == ERROR and st["rvc: ddsmon/monitor"][3]["received"] == "4"),
                 "p1 violated, with the 4 messages counted")
        last = next(st for st in map(lambda a: by_name(a.status), reversed(arrays))
                    if st["rvc: ddsmon/p1"][0] == ERROR and st["rvc: ddsmon/monitor"][3]["received"] == "4")
        check_violated(last, "ddsmon", 4)
        stamp = arrays[-1].header.stamp
        assert abs(stamp.sec + stamp.nanosec * 1e-9 - time.time()) < 3600  # wall clock, as diagnostic_updater
        mon.send_signal(signal.SIGTERM)
        _, err = mon.communicate(timeout=HANG_GUARD)
        assert mon.returncode == 1, err  # p1 was violated
        # The file output: the same arrays as JSON lines, the last with the final counters.
        final = json.loads(jsonl.read_text().splitlines()[-1])
        mon_status = next(s for s in final["status"] if s["name"] == "rvc: ddsmon/monitor")
        assert {kv["key"]: kv["value"] for kv in mon_status["values"]}["received"] == "4"
    finally:
        if mon.poll() is None:
            mon.kill()


def test_dds_writer_liveliness_lost_when_monitor_is_killed(rvc, tmp_path, dds_types):
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration
    _, String_ = dds_types
    domain = 150 + os.getpid() % 50
    mon = subprocess.Popen([rvc, "monitor", "--spec", "{ok}", "--input", "dds:/rvc_live/in",
                            "--output", "dds:/rvc_live/verdicts", "--liveliness-lease", "1", "--domain", str(domain)],
                           stderr=subprocess.PIPE, text=True)
    try:
        dp = DomainParticipant(domain)
        # Requesting a 1.5 s lease: only a writer offering at most that matches (a default
        # writer's infinite lease does not), so matching proves the lease rvc offers.
        qos = writer_qos() + Qos(Policy.Liveliness.Automatic(duration(milliseconds=1500)))
        reader = DataReader(dp, Topic(dp, "rt/rvc_live/verdicts", String_), qos=qos)
        wait_for(lambda: dds_matched(reader) == 1 and reader.get_liveliness_changed_status().alive_count == 1,
                 "rvc's verdict writer to match, alive")
        mon.send_signal(signal.SIGKILL)
        mon.wait(timeout=HANG_GUARD)
        wait_for(lambda: reader.get_liveliness_changed_status().alive_count == 0,
                 "the killed monitor's writer to lose liveliness")
    finally:
        if mon.poll() is None:
            mon.kill()


# ---------------------------------------------------------------- Zenoh

@pytest.fixture
def zenoh_rosbags(rvc):
    if "zenoh" not in transports_built(rvc):
        pytest.skip("rvc built without Zenoh")
    zenoh = pytest.importorskip("zenoh")
    typesys = pytest.importorskip("rosbags.typesys")
    pytest.importorskip("cyclonedds")  # its IdlStruct decodes the same payloads too
    return zenoh, typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)


def test_zenoh_diagnostics_decode_with_rosbags_and_token_goes_when_killed(rvc, tmp_path, zenoh_rosbags):
    zenoh, store = zenoh_rosbags
    DiagnosticArray_, _ = diagnostic_idl_types()
    ep = f"tcp/127.0.0.1:{free_port()}"
    mon = subprocess.Popen([rvc, "monitor", *SPECS, "--input", "zenoh:rvc/diag/in", "--output", f"file:{tmp_path}/v",
                            "--diagnostics", "zenoh:diagnostics", "--name", "zmon", "--diagnostics-period", "0.2",
                            "--stale-after", "1.5", "--mode", "peer", "--listen", ep, "--no-multicast-scouting"],
                           stderr=subprocess.PIPE, text=True)
    s = None
    try:
        time.sleep(0.3)  # let the monitor listen before Python connects to it
        s = zsession(zenoh, "peer", connect=[ep])
        tokens = []  # (kind, key) as the liveliness subscriber sees them
        token_sub = s.liveliness().declare_subscriber(
            "rvc/monitors/**", lambda sample: tokens.append((sample.kind, str(sample.key_expr))), history=True)
        arrays, idl_arrays = [], []  # the same payloads decoded by rosbags and by cyclonedds

        def on_array(sample):
            cdr = sample.payload.to_bytes()
            idl_arrays.append(DiagnosticArray_.deserialize(cdr))
            arrays.append(store.deserialize_cdr(cdr, "diagnostic_msgs/msg/DiagnosticArray"))
        diag_sub = s.declare_subscriber("diagnostics", on_array)
        pub = s.declare_publisher("rvc/diag/in")
        wait_for(lambda: bool(getattr(pub.matching_status, "matching", False)), "rvc monitor to match")
        wait_for(lambda: (zenoh.SampleKind.PUT, "rvc/monitors/zmon") in tokens, "rvc's liveliness token")

        def seen(pred):
            return lambda: any(pred(by_name(a.status)) for a in list(arrays))

        for _ in range(3):
            pub.put(GOOD)
        wait_for(seen(lambda st: st["rvc: zmon/p1"][0] == OK and st["rvc: zmon/p2"][0] == OK), "both OK")
        pub.put(BAD)

        def violated(st):
            return st["rvc: zmon/p1"][0] == ERROR and st["rvc: zmon/monitor"][3]["received"] == "4"
        wait_for(seen(violated), "p1 violated, with the 4 messages counted")
        check_violated(next(st for st in map(lambda a: by_name(a.status), reversed(list(arrays))) if violated(st)),
                       "zmon", 4)
        # Nothing more comes: after --stale-after the properties are STALE, the monitor WARNs.
        wait_for(seen(lambda st: st["rvc: zmon/p1"][0] == STALE and st["rvc: zmon/p2"][0] == STALE
                      and st["rvc: zmon/monitor"][0] == WARN), "STALE after 1.5 s of silence")
        stale = next(by_name(a.status) for a in reversed(list(arrays)) if by_name(a.status)["rvc: zmon/p1"][0] == STALE)
        assert stale["rvc: zmon/p1"][1].startswith("no message on zenoh:rvc/diag/in for ")
        assert stale["rvc: zmon/p1"][3]["verdict"] == "false"  # the last verdict is still shown
        n = min(len(arrays), len(idl_arrays))
        assert n >= 3 and [by_name(a.status) for a in arrays[:n]] == [by_name(a.status) for a in idl_arrays[:n]]
        assert (zenoh.SampleKind.DELETE, "rvc/monitors/zmon") not in tokens
        mon.send_signal(signal.SIGKILL)
        mon.wait(timeout=HANG_GUARD)
        wait_for(lambda: (zenoh.SampleKind.DELETE, "rvc/monitors/zmon") in tokens, "the token to go")
        diag_sub.undeclare()
        token_sub.undeclare()
    finally:
        if mon.poll() is None:
            mon.kill()
        if s is not None:
            s.close()
