"""ROS 2 over rmw_zenoh: samples in rmw_zenoh_cpp's format (ros2/rmw_zenoh docs/design.md), produced
here by the official Zenoh Python binding (eclipse-zenoh) and serialized by rosbags:

  data key    <domain>/<topic>/<pkg>::msg::dds_::<Name>_/RIHS01_<hash>
  attachment  int64 seq LE, int64 source timestamp LE, GID length 16, 16 GID bytes
  graph       liveliness tokens @ros2_lv/<domain>/<zid>/<node>/<entity>/<kind>/%/<ns>/<node>/<topic>/<type>/<hash>/<qos>

The test plays the ROS 2 system: it declares the node and publisher tokens, then publishes. Oracles:
loss per publisher computed by hand from the sequence numbers the test drops; verdicts equal to
`rvc check` on the same messages as JSON and to a direct evaluation of the formula in Python; the
graph listing equals the tokens the test declared. Loopback only: tcp/127.0.0.1, no multicast scouting.
"""
import json
import os
import struct
import subprocess
import time

import pytest

from test_python_peers import HANG_GUARD, free_port, wait_for, zsession
from test_typed_zenoh import GEAR, PARK, REVERSE, gear_samples, store, zenoh_mod  # noqa: F401 (fixtures)

TOPIC = "/vehicle/status/gear_status"
DDS_GEAR = "autoware_auto_vehicle_msgs::msg::dds_::GearReport_"
HASH = "RIHS01_" + "ab" * 32  # rvc does not check REP-2016 hashes: any hash of the right type matches
QOS = "::,10:,:,:,,"


def gid_of(n):
    return bytes([n] * 16)


def attachment(seq, gid, stamp_ns=1_700_000_000_000_000_000):
    return struct.pack("<qqB", seq, stamp_ns + seq, 16) + gid


def publisher_id(gid):
    """rvc's documented fold of a GID into its 64-bit publisher id (FNV-1a), as the counters print it."""
    h = 1469598103934665603
    for b in gid:
        h = ((h ^ b) * 1099511628211) & (2**64 - 1)
    return "%016x" % (h or 1)


def mangle(name):
    return name.replace("/", "%") if name else "%"


class RosSystem:
    """A stand-in for an rmw_zenoh ROS 2 process: one Zenoh session listening on loopback,
    liveliness tokens for its nodes and endpoints, rmw_zenoh-format publishers."""

    def __init__(self, zenoh, domain=0):
        self.zenoh, self.domain = zenoh, domain
        self.port = free_port()
        self.ep = f"tcp/127.0.0.1:{self.port}"
        self.s = zsession(zenoh, mode="peer", listen=[self.ep])
        self.zid = str(self.s.info.zid())
        self.tokens = []
        self.next_id = 10

    def token(self, kind, node, topic=None, dds_type=None, domain=None):
        domain = self.domain if domain is None else domain
        self.next_id += 1
        key = f"@ros2_lv/{domain}/{self.zid}/0/{self.next_id if topic else 0}/{kind}/%/%/{node}"
        if topic:
            key += f"/{mangle(topic)}/{dds_type}/{HASH}/{QOS}"
        self.tokens.append(self.s.liveliness().declare_token(key))
        return key

    def publisher(self, topic, dds_type):
        key = f"{self.domain}{topic}/{dds_type}/{HASH}"
        return self.s.declare_publisher(key, congestion_control=self.zenoh.CongestionControl.BLOCK)

    def rvc_flags(self):
        return ["--mode", "peer", "--connect", self.ep, "--no-multicast-scouting"]

    def close(self):
        for t in self.tokens:
            t.undeclare()
        self.s.close()


@pytest.fixture
def ros(zenoh_mod):
    systems = []

    def make(domain=0):
        systems.append(RosSystem(zenoh_mod, domain))
        return systems[-1]

    yield make
    for s in systems:
        s.close()


def final_stats(stderr):
    return json.loads([l for l in stderr.splitlines() if l.startswith("{")][-1])


def matched(pub):
    return bool(getattr(pub.matching_status, "matching", False))


def holds(reports):
    """historically({report == REVERSE} -> once[1:2]{report == PARK}), one step per message, by hand."""
    out, ok = [], True
    for i, r in enumerate(reports):
        if r == REVERSE and not any(reports[k] == PARK for k in range(max(0, i - 2), i)):
            ok = False
        out.append(ok)
    return out


SPEC = "historically({report == REVERSE} -> once[1:2]{report == PARK})"


def test_loss_is_counted_per_publisher_gid_and_type_comes_from_the_graph(rvc, tmp_path, ros, store):
    sys_ = ros()
    sys_.token("NN", "gear_node")
    sys_.token("MP", "gear_node", TOPIC, DDS_GEAR)
    pub = sys_.publisher(TOPIC, DDS_GEAR)
    # No --type: rvc reads it from the MP token. --idle-timeout ends the run (rmw_zenoh has no end marker).
    mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", SPEC, "--input", f"rmw_zenoh:{TOPIC}",
                            "--idle-timeout", "1.5", *sys_.rvc_flags()],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        wait_for(lambda: matched(pub) or mon.poll() is not None, "rvc monitor to subscribe")
        assert mon.poll() is None, mon.communicate()[1]
        samples = gear_samples(store, 90, seed=11)
        a, b = gid_of(0xA1), gid_of(0xB2)
        dropped_b = {7, 8, 20}          # never sent: lost for publisher B only
        sent = []                        # (payload, json) in the order rvc receives them
        for i in range(30):              # A: 1..30, B: 1..30 without dropped_b, interleaved
            raw, obj = samples[i]
            pub.put(raw, attachment=attachment(i + 1, a))
            sent.append(obj)
            if i + 1 not in dropped_b:
                raw, obj = samples[30 + i]
                pub.put(raw, attachment=attachment(i + 1, b))
                sent.append(obj)
        for i in range(10):              # A again, numbering from 1: a restarted publisher (same GID)
            raw, obj = samples[60 + i]
            pub.put(raw, attachment=attachment(i + 1, a))
            sent.append(obj)
        out, err = mon.communicate(timeout=HANG_GUARD)
    finally:
        if mon.poll() is None:
            mon.kill()
    assert f"rmw_zenoh:{TOPIC}: type {GEAR} (announced in the ROS 2 graph)" in err, err
    s = final_stats(err)
    n = len(sent)
    assert n == 30 + 27 + 10
    assert (s["received"], s["checked"], s["rejected"]) == (n, n, 0), err
    assert (s["gaps"], s["duplicates"], s["publishers"], s["publisher_restarts"]) == (3, 0, 2, 1), err
    by = {p["publisher"]: p for p in s["by_publisher"]}
    assert set(by) == {publisher_id(a), publisher_id(b)}, err
    pa, pb = by[publisher_id(a)], by[publisher_id(b)]
    assert (pa["received"], pa["gaps"], pa["restarts"], pa["last_seq"]) == (40, 0, 1, 10), err
    assert (pb["received"], pb["gaps"], pb["restarts"], pb["last_seq"]) == (27, 3, 0, 30), err
    # Verdicts: every message is a step, in arrival order.
    values = [json.loads(l)["value"] for l in out.splitlines()]
    assert values == holds([o["report"] for o in sent])
    f = tmp_path / "oracle.jsonl"
    f.write_text("".join(json.dumps(o) + "\n" for o in sent))
    r = subprocess.run([rvc, "check", "--all", "--spec", SPEC.replace("REVERSE", str(REVERSE)).replace("PARK", str(PARK)),
                        str(f)], capture_output=True, text=True)
    assert out == r.stdout
    # Loss outranks nothing worse here: a gap is exit 4 unless a property was violated (1).
    assert mon.returncode == (1 if False in values else 4), err


def test_topics_lists_the_graph_like_ros2_topic_list(rvc, ros):
    sys_ = ros(domain=7)
    sys_.token("NN", "talker")
    sys_.token("MP", "talker", "/chatter", "std_msgs::msg::dds_::String_")
    sys_.token("NN", "listener")
    sys_.token("MS", "listener", "/chatter", "std_msgs::msg::dds_::String_")
    sys_.token("MS", "listener", "/robot1/vehicle/status", DDS_GEAR)
    sys_.token("SS", "adder", "/add_two_ints", "example_interfaces::srv::dds_::AddTwoInts_")  # a service: not a topic
    sys_.token("MP", "elsewhere", "/other_domain", "std_msgs::msg::dds_::String_", domain=0)  # ROS_DOMAIN_ID 7 only
    env = dict(os.environ, ROS_DOMAIN_ID="7")
    r = subprocess.run([rvc, "topics", "-t", *sys_.rvc_flags()], capture_output=True, text=True, env=env,
                       timeout=HANG_GUARD)
    assert r.returncode == 0, r.stderr
    assert r.stdout == ("/chatter [std_msgs/msg/String]\n"
                        "/robot1/vehicle/status [autoware_auto_vehicle_msgs/msg/GearReport]\n"), r.stdout
    r = subprocess.run([rvc, "topics", "rmw_zenoh:", "-v", *sys_.rvc_flags()], capture_output=True, text=True,
                       env=env, timeout=HANG_GUARD)
    assert r.returncode == 0, r.stderr
    assert r.stdout == ("Published topics:\n"
                        " * /chatter [std_msgs/msg/String] 1 publisher\n\n"
                        "Subscribed topics:\n"
                        " * /chatter [std_msgs/msg/String] 1 subscriber\n"
                        " * /robot1/vehicle/status [autoware_auto_vehicle_msgs/msg/GearReport] 1 subscriber\n\n"), r.stdout
    # Nothing on another domain: exit 6, not an empty success.
    r = subprocess.run([rvc, "topics", "--wait", "0.5", *sys_.rvc_flags()], capture_output=True, text=True,
                       env=dict(os.environ, ROS_DOMAIN_ID="8"), timeout=HANG_GUARD)
    assert r.returncode == 6 and "no ROS 2 topic announced on domain 8" in r.stderr, r.stderr


def test_echo_without_type_and_a_topic_the_graph_does_not_know(rvc, ros, store):
    sys_ = ros()
    sys_.token("MP", "gear_node", TOPIC, DDS_GEAR)
    pub = sys_.publisher(TOPIC, DDS_GEAR)
    echo = subprocess.Popen([rvc, "echo", f"rmw_zenoh:{TOPIC}", "-n", "5", *sys_.rvc_flags()],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        wait_for(lambda: matched(pub) or echo.poll() is not None, "rvc echo to subscribe")
        samples = gear_samples(store, 5, seed=4)
        for i, (raw, _) in enumerate(samples, 1):
            pub.put(raw, attachment=attachment(i, gid_of(1)))
        out, err = echo.communicate(timeout=HANG_GUARD)
    finally:
        if echo.poll() is None:
            echo.kill()
    assert echo.returncode == 0, err
    assert [json.loads(l) for l in out.splitlines()] == [o for _, o in samples]
    # No token for this topic: rvc cannot know the type and says what to do.
    r = subprocess.run([rvc, "echo", "rmw_zenoh:/not/announced", "-n", "1", *sys_.rvc_flags()],
                       capture_output=True, text=True, timeout=HANG_GUARD)
    assert r.returncode == 2
    assert "rmw_zenoh:/not/announced: no publisher or subscription of this topic announced" in r.stderr, r.stderr
    assert "give --type" in r.stderr
    # Two types announced on one topic: rvc does not guess.
    sys_.token("MP", "a", "/two/types", "std_msgs::msg::dds_::String_")
    sys_.token("MP", "b", "/two/types", DDS_GEAR)
    r = subprocess.run([rvc, "echo", "rmw_zenoh:/two/types", "-n", "1", *sys_.rvc_flags()],
                       capture_output=True, text=True, timeout=HANG_GUARD)
    assert r.returncode == 2
    assert ("rmw_zenoh:/two/types: the graph announces several types (autoware_auto_vehicle_msgs/msg/GearReport, "
            "std_msgs/msg/String): choose one with --type") in r.stderr, r.stderr


def test_verdicts_published_in_rmw_zenoh_format_with_graph_tokens(rvc, tmp_path, ros, zenoh_mod):
    sys_ = ros()
    got = []
    sub = sys_.s.declare_subscriber("0/rv/verdicts/std_msgs::msg::dds_::String_/*",
                                    lambda smp: got.append((str(smp.key_expr), smp.payload.to_bytes(),
                                                            smp.attachment.to_bytes() if smp.attachment else b"")))
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(json.dumps({"x": x}) + "\n" for x in [1, 5, 2, 7, 3]))
    inp = f"zenoh:rvc_test/rmwz/{free_port()}"
    mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", "{x < 6}", "--input", inp, "--exit-on-eos",
                            "--output", "rmw_zenoh:/rv/verdicts", *sys_.rvc_flags()],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        # The graph shows rvc's publisher of /rv/verdicts (what `ros2 topic list` on rmw_zenoh reads).
        def rvc_publisher():
            keys = [str(r.ok.key_expr) for r in sys_.s.liveliness().get("@ros2_lv/0/**", timeout=1.0) if r.ok]
            return [k for k in keys if "/MP/" in k and "/%rv%verdicts/std_msgs::msg::dds_::String_/" in k]
        wait_for(lambda: rvc_publisher() or mon.poll() is not None, "rvc's publisher token")
        assert mon.poll() is None, mon.communicate()[1]
        assert rvc_publisher()[0].endswith("/rvc/%rv%verdicts/std_msgs::msg::dds_::String_/RIHS01_"
                                           "df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18/" + QOS)
        r = subprocess.run([rvc, "replay", str(trace), "--to", inp, "--wait-timeout", "30", *sys_.rvc_flags()],
                           capture_output=True, text=True, timeout=HANG_GUARD)
        assert r.returncode == 0, r.stderr
        out, err = mon.communicate(timeout=HANG_GUARD)
    finally:
        if mon.poll() is None:
            mon.kill()
    assert mon.returncode == 1, err
    wait_for(lambda: len(got) >= 5, "5 verdicts")
    sub.undeclare()
    texts = []
    for i, (key, payload, att) in enumerate(got, 1):
        assert key.endswith("/RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18")
        assert payload[:4] == b"\x00\x01\x00\x00"  # CDR little endian
        (n,) = struct.unpack_from("<I", payload, 4)
        texts.append(payload[8:8 + n - 1].decode())
        seq, _stamp, gid_len = struct.unpack_from("<qqB", att)
        assert (seq, gid_len, len(att)) == (i, 16, 33)
    assert len({att[17:] for _, _, att in got}) == 1  # one GID
    assert [json.loads(t)["value"] for t in texts] == [True, True, True, False, True]


def test_several_named_inputs_take_their_types_from_the_graph(rvc, ros, store):
    sys_ = ros()
    sys_.token("MP", "gear_node", TOPIC, DDS_GEAR)
    sys_.token("MP", "chatter_node", "/chatter", "std_msgs::msg::dds_::String_")
    gear_pub = sys_.publisher(TOPIC, DDS_GEAR)
    chat_pub = sys_.publisher("/chatter", "std_msgs::msg::dds_::String_")
    mon = subprocess.Popen([rvc, "monitor", "--spec", "{gear.report != 0} && {chat.data == \"ok\"}",
                            "--input", f"gear=rmw_zenoh:{TOPIC}", "--input", "chat=rmw_zenoh:/chatter",
                            "--stamp", "chat=arrival", "--idle-timeout", "1.5", *sys_.rvc_flags()],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        wait_for(lambda: (matched(gear_pub) and matched(chat_pub)) or mon.poll() is not None, "both inputs")
        for i, (raw, _) in enumerate(gear_samples(store, 4, seed=5), 1):
            gear_pub.put(raw, attachment=attachment(i, gid_of(1)))
        text = b"ok"
        chat_pub.put(b"\x00\x01\x00\x00" + struct.pack("<I", len(text) + 1) + text + b"\x00",
                     attachment=attachment(1, gid_of(2)))
        out, err = mon.communicate(timeout=HANG_GUARD)
    finally:
        if mon.poll() is None:
            mon.kill()
    assert f"rmw_zenoh:{TOPIC}: type {GEAR} (announced in the ROS 2 graph)" in err, err
    assert "rmw_zenoh:/chatter: type std_msgs/msg/String (announced in the ROS 2 graph)" in err, err
    s = final_stats(err)
    by = {i["name"]: i for i in s["inputs"]}
    assert (by["gear"]["received"], by["chat"]["received"], s["rejected"]) == (4, 1, 0), err
    shares = {p["publisher"]: p["received"] for p in s["by_publisher"]}
    assert shares == {publisher_id(gid_of(1)): 4, publisher_id(gid_of(2)): 1}, err
