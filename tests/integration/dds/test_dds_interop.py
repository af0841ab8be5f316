"""Interop of rvc's dds: transport with other DDS/ROS 2 software, over loopback.

* Python cyclonedds (a different CycloneDDS build: the PyPI wheel's libddsc)
  publishes/subscribes std_msgs/msg/String on the ROS 2 topic name, to/from
  the C++ DdsSource/DdsSink driven by rvc_dds_probe.
* rosbags' ROS 2 CDR serialization of std_msgs/msg/String is byte-compatible
  with what CycloneDDS C puts on the wire, and rosbags-made CDR bytes injected
  verbatim onto the wire are read correctly by the C++ source.
* Participants (Python's and the probe's) only use loopback sockets.
"""

import ipaddress
import json
import os
import subprocess
import time
from dataclasses import dataclass

import pytest
from cyclonedds.core import ReadCondition, SampleState, ViewState, InstanceState, WaitSet
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import uint64
from cyclonedds.pub import DataWriter
from rvc_testlib import dds_matched
from cyclonedds.qos import Policy, Qos
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from rosbags.typesys import Stores, get_typestore

from conftest import HANG_GUARD_S, parse_probe_output, process_sockets, start_probe_sub

EOS_PREFIX = "\x04rvc-eos"
TYPESTORE = get_typestore(Stores.ROS2_HUMBLE)
RosString = TYPESTORE.types["std_msgs/msg/String"]


@dataclass
class String_(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    """ROS 2 std_msgs/msg/String as DDS sees it; keeps the raw CDR it was read from."""

    data: str

    @classmethod
    def deserialize(cls, data, has_header=True, use_version_2=None):
        obj = super().deserialize(data, has_header=has_header, use_version_2=use_version_2)
        obj.raw_cdr = bytes(data)
        return obj


@dataclass
class Frame_(IdlStruct, typename="rvc_msgs::msg::dds_::Frame_"):
    seq: uint64
    data: str


# rvc's default QoS: reliable (writer blocks up to 30 s), keep-all, volatile.
RVC_QOS = Qos(Policy.Reliability.Reliable(duration(seconds=30)), Policy.History.KeepAll, Policy.Durability.Volatile)


def wait_until(pred, what):
    deadline = time.monotonic() + HANG_GUARD_S
    while not pred():
        if time.monotonic() > deadline:
            raise AssertionError(f"hang guard: {what}")
        time.sleep(0.01)


def rosbags_cdr(text: str) -> bytes:
    return bytes(TYPESTORE.serialize_cdr(RosString(data=text), "std_msgs/msg/String"))


def strip_cdr_padding(raw: bytes) -> bytes:
    """CycloneDDS pads a sample to 4 bytes and records the pad length in the
    low two bits of the encapsulation options (DDS-XTypes 7.6.3.1.2); rosbags
    writes no padding. The payloads are identical once that is undone."""
    pad = raw[3] & 3
    return raw[:2] + b"\x00\x00" + (raw[4 : len(raw) - pad] if pad else raw[4:])


def take_all(reader, until):
    """Takes samples until until(samples) holds (hang-guarded)."""
    got = []
    ws = WaitSet(reader.participant)
    ws.attach(ReadCondition(reader, SampleState.Any | ViewState.Any | InstanceState.Any))
    deadline = time.monotonic() + HANG_GUARD_S
    while not until(got):
        if time.monotonic() > deadline:
            raise AssertionError(f"hang guard: received {len(got)} samples")
        ws.wait(duration(milliseconds=200))
        got.extend(s for s in reader.take(N=256) if hasattr(s, "data"))
    return got


def payloads():
    out = [json.dumps({"i": i, "verdict": "ok" if i % 3 else "violation"}) for i in range(300)]
    out += ['{"unicode":"caf\u00e9 \u2713"}', "", json.dumps({"big": "x" * 70000})]
    return out


# ---------------------------------------------------------------------------


def test_python_publisher_reaches_cpp_source(probe, domain, topic):
    proc = start_probe_sub(topic, domain)
    try:
        dp = DomainParticipant(domain)
        writer = DataWriter(dp, Topic(dp, "rt" + topic, String_), qos=RVC_QOS)
        wait_until(lambda: dds_matched(writer) >= 1, "probe reader never matched")
        sent = payloads()
        for p in sent:
            writer.write(String_(data=p))
        writer.write(String_(data=f"{EOS_PREFIX} last={len(sent)} count={len(sent)}"))
        assert writer.wait_for_acks(duration(seconds=HANG_GUARD_S))
        out, err = proc.communicate(timeout=HANG_GUARD_S + 30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    frames, counters = parse_probe_output(out)
    data = [f for f in frames if not f.eos]
    assert [f.payload.decode() for f in data] == sent
    assert [f.seq for f in data] == list(range(1, len(sent) + 1))
    assert frames[-1].eos and frames[-1].seq == len(sent)
    assert counters == {"received": len(sent), "gaps": 0, "duplicates": 0, "last_seq": len(sent)}


def test_eos_count_reveals_messages_the_source_never_saw(probe, domain, topic):
    # A ROS 2-side publisher that announces 10 messages but delivered 7: the
    # String type has no seq field, so the marker's count is what shows gaps.
    proc = start_probe_sub(topic, domain)
    try:
        dp = DomainParticipant(domain)
        writer = DataWriter(dp, Topic(dp, "rt" + topic, String_), qos=RVC_QOS)
        wait_until(lambda: dds_matched(writer) >= 1, "probe reader never matched")
        for i in range(7):
            writer.write(String_(data=json.dumps({"i": i})))
        writer.write(String_(data=f"{EOS_PREFIX} last=10 count=10"))
        out, err = proc.communicate(timeout=HANG_GUARD_S + 30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    _, counters = parse_probe_output(out)
    assert counters == {"received": 7, "gaps": 3, "duplicates": 0, "last_seq": 10}


def test_cpp_sink_reaches_python_subscriber_byte_compatible_with_rosbags(probe, domain, topic):
    dp = DomainParticipant(domain)
    reader = DataReader(dp, Topic(dp, "rt" + topic, String_), qos=RVC_QOS)
    sent = payloads()
    proc = subprocess.run(
        [probe, "pub", topic, "--domain", str(domain), "--timeout-ms", str(HANG_GUARD_S * 1000)],
        input="\n".join(sent) + "\n",
        capture_output=True,
        text=True,
        timeout=HANG_GUARD_S + 30,
    )
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout) == {"written": len(sent), "last_seq": len(sent)}
    got = take_all(reader, lambda g: any(s.data.startswith(EOS_PREFIX) for s in g))
    assert [s.data for s in got[:-1]] == sent
    assert got[-1].data == f"{EOS_PREFIX} last={len(sent)} count={len(sent)}"
    for s in got:
        # Wire bytes from CycloneDDS C == rosbags' ROS 2 CDR (modulo the
        # encapsulation's optional end padding), and rosbags decodes them.
        assert s.raw_cdr[:2] == b"\x00\x01", "expected XCDR1 little-endian (CDR_LE), as ROS 2 uses"
        assert strip_cdr_padding(s.raw_cdr) == rosbags_cdr(s.data)
        assert TYPESTORE.deserialize_cdr(s.raw_cdr, "std_msgs/msg/String").data == s.data


def test_rosbags_cdr_on_the_wire_reaches_cpp_source(probe, domain, topic):
    sent = ['{"from":"rosbags"}', "", "\u00fcnicode \u2713", "ab", "abc"]
    proc = start_probe_sub(topic, domain)
    try:
        dp = DomainParticipant(domain)
        writer = DataWriter(dp, Topic(dp, "rt" + topic, String_), qos=RVC_QOS)
        wait_until(lambda: dds_matched(writer) >= 1, "probe reader never matched")
        for text in sent + [f"{EOS_PREFIX} last={len(sent)}"]:
            sample = String_(data="(replaced)")
            cdr = rosbags_cdr(text)
            # DataWriter.write() puts whatever sample.serialize() returns on the
            # wire unchanged: here, rosbags' serialization instead of cyclone's.
            sample.serialize = lambda *a, _cdr=cdr, **k: _cdr
            writer.write(sample)
        out, err = proc.communicate(timeout=HANG_GUARD_S + 30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    frames, counters = parse_probe_output(out)
    assert [f.payload.decode() for f in frames if not f.eos] == sent
    assert counters["received"] == len(sent) and counters["gaps"] == 0


def test_frame_type_carries_publisher_seq(probe, domain, topic):
    proc = start_probe_sub(topic, domain, "--dds-type", "frame")
    try:
        dp = DomainParticipant(domain)
        writer = DataWriter(dp, Topic(dp, "rt" + topic, Frame_), qos=RVC_QOS)
        wait_until(lambda: dds_matched(writer) >= 1, "probe reader never matched")
        for seq in (1, 2, 4, 5, 5, 8):  # 3, 6, 7 missing; 5 repeated
            writer.write(Frame_(seq=seq, data=json.dumps({"seq": seq})))
        writer.write(Frame_(seq=9, data=f"{EOS_PREFIX} last=9 count=6"))
        out, err = proc.communicate(timeout=HANG_GUARD_S + 30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    frames, counters = parse_probe_output(out)
    assert [f.seq for f in frames] == [1, 2, 4, 5, 5, 8, 9]
    assert counters == {"received": 6, "gaps": 4, "duplicates": 1, "last_seq": 9}


def test_ros2_graph_sees_rt_topic_and_string_type(probe, domain, topic):
    # What `ros2 topic list -t` relies on: the discovered DDS publication's
    # topic and type names.
    dp = DomainParticipant(domain)
    reader = DataReader(dp, Topic(dp, "rt" + topic, String_), qos=RVC_QOS)
    proc = subprocess.Popen(
        [probe, "pub", topic, "--domain", str(domain)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
        stderr=subprocess.PIPE, text=True,
    )
    try:
        # The probe waits for stdin, so its writer is alive while we look.
        wait_until(lambda: dds_matched(reader), "probe publication never matched")
        pub = reader.get_matched_publication_data(reader.get_matched_publications()[0])
        out, err = proc.communicate("{}\n", timeout=HANG_GUARD_S + 30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    assert pub.topic_name == "rt" + topic
    assert pub.type_name == "std_msgs::msg::dds_::String_"
    assert [s.data for s in take_all(reader, lambda g: len(g) >= 2)][0] == "{}"


def test_plain_names_use_topic_as_is(probe, domain, topic):
    plain = "rvc_plain_" + topic.rsplit("/", 1)[1]
    dp = DomainParticipant(domain)
    reader = DataReader(dp, Topic(dp, plain, String_), qos=RVC_QOS)
    proc = subprocess.run(
        [probe, "pub", plain, "--domain", str(domain), "--no-ros2-names"], input='{"plain":1}\n',
        capture_output=True, text=True, timeout=HANG_GUARD_S + 30,
    )
    assert proc.returncode == 0, proc.stderr
    got = take_all(reader, lambda g: len(g) >= 2)
    assert got[0].data == '{"plain":1}'


def test_qos_errors_are_reported(probe, domain, topic):
    proc = subprocess.run([probe, "sub", topic, "--domain", str(domain), "--qos", "reliable,keep-last=zero"],
                          capture_output=True, text=True, timeout=HANG_GUARD_S)
    assert proc.returncode != 0
    assert "keep-last needs a depth" in proc.stderr


# Network safety ------------------------------------------------------------


def _assert_loopback_only(pid: int):
    socks = process_sockets(pid)
    assert socks, f"no sockets found for pid {pid}"
    bound_lo = 0
    for table, lip, lport, rip, rport in socks:
        where = f"pid {pid}: {table} {lip}:{lport} -> {rip}:{rport}"
        assert table.startswith("udp"), where
        local = ipaddress.ip_address(lip)
        assert local.is_loopback or local.is_unspecified, where
        assert rport == 0 or ipaddress.ip_address(rip).is_loopback, where
        if local.is_unspecified:
            # CycloneDDS binds only its unicast receive sockets to the wildcard
            # address: they must be DDSI unicast ports (7400 + 250 d + 10/11 +
            # 2 i, i <= 100) of a test domain (this process may hold several).
            assert lport >= 7400 and 10 <= (lport - 7400) % 250 <= 211, where
        else:
            bound_lo += 1
    assert bound_lo >= 1, f"pid {pid}: no socket bound to loopback"


def test_participants_only_use_loopback(probe, domain, topic):
    proc = start_probe_sub(topic, domain)
    try:
        dp = DomainParticipant(domain)
        writer = DataWriter(dp, Topic(dp, "rt" + topic, String_), qos=RVC_QOS)
        wait_until(lambda: dds_matched(writer) >= 1, "probe reader never matched")
        writer.write(String_(data="{}"))
        _assert_loopback_only(proc.pid)
        _assert_loopback_only(os.getpid())
        writer.write(String_(data=f"{EOS_PREFIX} last=1"))
        out, err = proc.communicate(timeout=HANG_GUARD_S + 30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
