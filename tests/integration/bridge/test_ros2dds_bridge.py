"""The real zenoh-bridge-ros2dds between ROS 2 (DDS) and rvc (Zenoh).

The bridge is rvc-ros2dds-bridge (tools/ros2dds-bridge): Eclipse's zenoh-plugin-ros2dds 1.10.2 from
crates.io, linked into a Zenoh router, as zenoh-bridge-ros2dds runs it. ROS 2 nodes are played by
cyclonedds-Python: typed samples (rosidl's `pkg::msg::dds_::Name_` types on `rt/` topics, XCDR1)
and the node's `ros_discovery_info` announcement (ros_node.py), without which the plugin bridges
nothing.

- DDS -> plugin -> `rvc monitor --input zenoh:KEY --type T`: the verdicts equal a hand-computed
  oracle (a violation included) and every sample is counted;
- what the plugin puts on Zenoh (key, payload, attachment) equals what `rvc bridge --type` forwards
  for the same DDS samples, and what docs/ros2-types.md says: the key is the ROS name without its
  leading `/`, the payload the whole CDR sample (encapsulation header included; decoded by
  cyclonedds-Python back into what was written), no attachment;
- the reverse: `rvc monitor --on-violation ... --command-type std_msgs/msg/Bool` on Zenoh -> plugin
  -> a ROS 2 subscription in cyclonedds-Python receives exactly one command per onset;
- the bridge process stays on loopback (its sockets, from `ss`), and refuses a config that would not.
Network: the bridge's CycloneDDS uses rvc's loopback-pinned XML (`rvc dds-config`, checked to name
`lo`), its Zenoh side listens on one tcp/127.0.0.1 port with multicast scouting off (the bridge
refuses anything else); every DDS participant is in a domain of its own, drawn per module.
"""
import json
import os
import random
import signal
import subprocess
import threading
import time

import pytest

from conftest import transports_built
from ros_idl_types import ros_idl_types
from ros_node import announce_node
from rvc_testlib import dds_matched
from test_python_peers import HANG_GUARD, free_port, wait_for, zsession

GEAR = "autoware_auto_vehicle_msgs/msg/GearReport"
# Each test has topics of its own (a namespace): the plugin 1.10.2 forwards every sample twice on a
# topic whose route it removed (its last node left) and created again in the same process (the
# removed route's publisher and matching listener stay alive: seen here, docs/zenoh.md).
GEAR_TOPIC = "/{ns}/vehicle/status/gear_status"
HAZARD_TOPIC = "/{ns}/vehicle/hazard_cmd"
DRIVE, REVERSE, PARK = 2, 20, 22

# One trace, its verdicts worked out by hand. Discrete time: message i is time i.
# p = historically({report == REVERSE} -> once[0:2]{report == PARK})
#   t0 PARK    -> no reverse: holds
#   t1 REVERSE -> PARK at t0 is within [t-2, t]: holds
#   t2 REVERSE -> PARK at t0 still within: holds
#   t3 DRIVE   -> holds
#   t4 REVERSE -> t2..t4 = REVERSE, DRIVE, REVERSE: no PARK, violated; historically stays false
#   t5 PARK, t6 DRIVE -> false
REPORTS = [PARK, REVERSE, REVERSE, DRIVE, REVERSE, PARK, DRIVE]
SPEC = "historically({report == REVERSE} -> once[0:2]{report == PARK})"
EXPECTED = [(0, True), (1, True), (2, True), (3, True), (4, False), (5, False), (6, False)]


@pytest.fixture(scope="module")
def ros(rvc):
    if not {"dds", "zenoh"} <= set(transports_built(rvc)):
        pytest.skip("rvc built without Zenoh or DDS")
    pytest.importorskip("cyclonedds")
    t = ros_idl_types()
    return {"Time": t.Time_, "Gear": t.GearReport_, "Bool": t.Bool_}


class Bridge:
    def __init__(self, proc, endpoint, domain, zid, log):
        self.proc, self.endpoint, self.domain, self.zid, self.log = proc, endpoint, domain, zid, log

    def log_text(self):
        return self.log.read_text(errors="replace")


@pytest.fixture(scope="module")
def bridge(bridge_bin, rvc, ros, tmp_path_factory):
    d = tmp_path_factory.mktemp("ros2dds")
    xml = d / "cyclonedds.xml"
    subprocess.run([rvc, "dds-config", "-o", str(xml)], check=True)
    text = xml.read_text()
    assert 'name="lo"' in text and "<AllowMulticast>false</AllowMulticast>" in text
    # Every CycloneDDS of this module (the bridge's vendored one, cyclonedds-Python's) reads it; set
    # before the first Python participant exists.
    old_uri = os.environ.get("CYCLONEDDS_URI")
    os.environ["CYCLONEDDS_URI"] = f"file://{xml}"
    port, domain = free_port(), random.randint(1, 200)
    endpoint = f"tcp/127.0.0.1:{port}"
    cfg = d / "bridge.json5"
    cfg.write_text(json.dumps({
        "mode": "router",
        "listen": {"endpoints": [endpoint]},
        "connect": {"endpoints": []},
        "scouting": {"multicast": {"enabled": False}},
        "plugins": {"ros2dds": {"domain": domain, "nodename": "rvc_test_bridge"}},
    }, indent=2))
    log = d / "bridge.log"
    # ROS_DISTRO: the GID layout of ros_discovery_info (16 bytes from Iron on, as ros_node.py writes).
    # Zenoh's log goes to stdout with the `ready` line: a thread keeps copying it to bridge.log.
    proc = subprocess.Popen([bridge_bin, str(cfg)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env={**os.environ, "ROS_DISTRO": "jazzy", "NO_COLOR": "1",
                                 "RUST_LOG": os.environ.get("RUST_LOG", "warn")})
    ready = threading.Event()

    def copy_output():
        with open(log, "w") as logf:
            for line in proc.stdout:
                logf.write(line)
                logf.flush()
                if line.startswith("ready "):
                    ready.zid = line.split()[1]
                    ready.set()

    threading.Thread(target=copy_output, daemon=True).start()
    ready.wait(HANG_GUARD)
    try:
        assert ready.is_set(), f"bridge did not start: {log.read_text()}"
        yield Bridge(proc, endpoint, domain, ready.zid, log)
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(20)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        exited = proc.returncode
        if old_uri is None:
            os.environ.pop("CYCLONEDDS_URI", None)
        else:
            os.environ["CYCLONEDDS_URI"] = old_uri
    assert exited == 0, f"the bridge did not stop cleanly on SIGINT ({exited}): {log.read_text()[-3000:]}"


def xcdr1_qos():
    """Reliable, keep-all (nothing replaced before the bridge took it), XCDR1 as rmw_cyclonedds."""
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.util import duration
    return Qos(Policy.Reliability.Reliable(duration(seconds=30)), Policy.History.KeepAll,
               Policy.Durability.Volatile, Policy.DataRepresentation(use_cdrv0_representation=True))


def gear(ros, i, report):
    return ros["Gear"](stamp=ros["Time"](sec=100 + i, nanosec=500), report=report)


def zenoh_args(bridge):
    return ["--mode", "client", "--connect", bridge.endpoint, "--no-multicast-scouting"]


class Lines:
    """Collects a process's stdout lines on a thread (the test waits for a count, never a time)."""

    def __init__(self, stream):
        self.lines = []
        self._t = threading.Thread(target=self._run, args=(stream,), daemon=True)
        self._t.start()

    def _run(self, stream):
        for line in stream:
            self.lines.append(line)


def stop(proc):
    proc.send_signal(signal.SIGINT)
    try:
        return proc.wait(HANG_GUARD)
    except subprocess.TimeoutExpired:
        proc.kill()
        raise


def stats_of(stderr_text):
    return json.loads([l for l in stderr_text.splitlines() if l.startswith("{")][-1])


def test_ros2_publisher_through_the_plugin_is_monitored(rvc, ros, bridge, tmp_path):
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic

    topic = GEAR_TOPIC.format(ns="monitored")

    dp = DomainParticipant(bridge.domain)
    writer = DataWriter(dp, Topic(dp, "rt" + topic, ros["Gear"]), qos=xcdr1_qos())
    node = announce_node(dp, "gear_publisher", writers=[writer])  # noqa: F841 (alive = node exists)
    err = tmp_path / "monitor.err"
    with open(err, "w") as errf:
        mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", SPEC, "--input", "zenoh:" + topic[1:],
                                "--type", GEAR, *zenoh_args(bridge)], stdout=subprocess.PIPE, stderr=errf, text=True)
    try:
        out = Lines(mon.stdout)
        # The plugin creates its DDS reader only once a Zenoh subscriber (rvc's) matches its key, so
        # this match is the whole path being ready.
        wait_for(lambda: dds_matched(writer) >= 1, "the plugin's DDS reader (needs rvc subscribed via Zenoh)")
        for i, report in enumerate(REPORTS):
            writer.write(gear(ros, i, report))
        wait_for(lambda: len(out.lines) >= len(REPORTS), f"{len(REPORTS)} verdicts: {err.read_text()}"
                 f"\nbridge: {bridge.log_text()}")
        rc = stop(mon)
    finally:
        if mon.poll() is None:
            mon.kill()
    verdicts = [json.loads(l) for l in out.lines]
    assert [(v["time"], v["value"]) for v in verdicts] == EXPECTED, out.lines
    assert {v["property"] for v in verdicts} == {"p1"}
    stats = stats_of(err.read_text())
    assert stats["received"] == stats["checked"] == len(REPORTS) and stats["rejected"] == 0, stats
    assert rc == 1  # the violation at t4


def test_key_and_payload_are_what_rvc_bridge_forwards(rvc, ros, bridge):
    """The same DDS samples through the plugin and through `rvc bridge --type`, received by an
    eclipse-zenoh subscriber on the router: same key, same payload bytes."""
    zenoh = pytest.importorskip("zenoh")
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic

    topic = GEAR_TOPIC.format(ns="compared")
    key = topic[1:]
    got, lock = [], threading.Lock()

    def on_sample(s):
        att = s.attachment.to_bytes() if s.attachment is not None else None
        with lock:
            got.append((str(s.key_expr), s.payload.to_bytes(), att))

    zs = zsession(zenoh, mode="client", connect=[bridge.endpoint])
    sub = zs.declare_subscriber(key, on_sample)  # noqa: F841
    rb = subprocess.Popen([rvc, "bridge", "--type", GEAR, "dds:" + topic, "zenoh:" + key,
                           "--domain", str(bridge.domain), *zenoh_args(bridge)],
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    dp = DomainParticipant(bridge.domain)
    try:
        writer = DataWriter(dp, Topic(dp, "rt" + topic, ros["Gear"]), qos=xcdr1_qos())
        node = announce_node(dp, "gear_publisher", writers=[writer])  # noqa: F841
        wait_for(lambda: dds_matched(writer) >= 2, "the plugin's and rvc bridge's DDS readers")
        sent = [gear(ros, i, r) for i, r in enumerate([DRIVE, REVERSE, PARK])]
        for m in sent:
            writer.write(m)
        wait_for(lambda: len(got) >= 2 * len(sent), "both bridges' samples")
        stop(rb)
    finally:
        if rb.poll() is None:
            rb.kill()
        zs.close()
    plugin = [g for g in got if g[2] is None]
    ours = [g for g in got if g[2] is not None]
    assert len(plugin) == len(ours) == len(sent), got
    assert {k for k, _, _ in got} == {key}  # the ROS name without its leading '/'
    assert [p for _, p, _ in plugin] == [p for _, p, _ in ours]  # byte for byte
    for (_, payload, _), m in zip(plugin, sent):
        assert payload[:4] == b"\x00\x01\x00\x00"  # CDR little endian encapsulation header, XCDR1
        assert ros["Gear"].deserialize(payload) == m  # the whole sample, header included
    assert all(len(a) == 17 for _, _, a in ours)  # rvc's seq/flags/publisher attachment (docs/zenoh.md)


def test_enforcer_command_reaches_a_ros2_subscription_through_the_plugin(rvc, ros, bridge, tmp_path, capfd):
    """The loop: ROS 2 gears -> plugin -> rvc monitor -> its command on Zenoh (CDR std_msgs/Bool)
    -> plugin -> a ROS 2 subscription. One violation onset (t4): exactly one command, and nothing
    else: the plugin forwards any payload, and an end-of-stream marker's empty one reached the
    subscription's CycloneDDS as a malformed packet, repeated by the reliable writer (what this
    participant's CycloneDDS prints on stderr, captured here)."""
    zenoh = pytest.importorskip("zenoh")
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    topic, hazard = GEAR_TOPIC.format(ns="loop"), HAZARD_TOPIC.format(ns="loop")
    dp = DomainParticipant(bridge.domain)
    writer = DataWriter(dp, Topic(dp, "rt" + topic, ros["Gear"]), qos=xcdr1_qos())
    reader = DataReader(dp, Topic(dp, "rt" + hazard, ros["Bool"]), qos=xcdr1_qos())
    node = announce_node(dp, "vehicle", writers=[writer], readers=[reader])  # noqa: F841
    # The plugin's route to the subscription: its DDS writer, then its Zenoh subscriber (a remote
    # Zenoh publisher on the key matches it only then).
    wait_for(lambda: dds_matched(reader) >= 1, "the plugin's DDS writer for the subscription")
    zs = zsession(zenoh, mode="client", connect=[bridge.endpoint])
    probe = zs.declare_publisher(hazard[1:])
    wait_for(lambda: bool(probe.matching_status.matching), "the plugin's Zenoh subscriber")
    probe.undeclare()
    zs.close()
    err = tmp_path / "monitor.err"
    with open(err, "w") as errf:
        mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", SPEC, "--input", "zenoh:" + topic[1:],
                                "--type", GEAR, "--on-violation", 'p1=zenoh:%s:{"data":true}' % hazard[1:],
                                "--command-type", "std_msgs/msg/Bool", *zenoh_args(bridge)],
                               stdout=subprocess.PIPE, stderr=errf, text=True)
    try:
        out = Lines(mon.stdout)
        wait_for(lambda: dds_matched(writer) >= 1, "the plugin's DDS reader (needs rvc subscribed via Zenoh)")
        for i, report in enumerate(REPORTS):
            writer.write(gear(ros, i, report))
        wait_for(lambda: len(out.lines) >= len(REPORTS), f"{len(REPORTS)} verdicts: {err.read_text()}")
        received = []
        wait_for(lambda: received.extend(reader.take(N=10)) or len(received) >= 1, "the command on DDS")
        rc = stop(mon)
    finally:
        if mon.poll() is None:
            mon.kill()
    # What else arrives after the run ended (the monitor's end-of-stream on the command key).
    time.sleep(1.0)
    received.extend(reader.take(N=10))
    assert [(json.loads(l)["time"], json.loads(l)["value"]) for l in out.lines] == EXPECTED
    assert received == [ros["Bool"](data=True)], received
    assert rc == 1
    assert "malformed packet" not in capfd.readouterr().err


def test_the_bridge_process_stays_on_loopback(bridge):
    """Its sockets (ss): TCP only on 127.0.0.1 (the one listen port and links to it), no Zenoh
    scouting socket (UDP 7446), UDP bound to 127.0.0.1 or, for CycloneDDS's receive sockets, the
    wildcard address (CycloneDDS's known limitation, docs/dds.md: nothing is sent from them and no
    peer learns of them); nothing bound to an outer address."""
    out = subprocess.run(["ss", "-tuanpH"], capture_output=True, text=True, check=True).stdout
    mine = [l.split() for l in out.splitlines() if f"pid={bridge.proc.pid}," in l]
    assert mine, "no sockets found for the bridge (ss without -p rights?)"
    port = bridge.endpoint.rsplit(":", 1)[1]
    tcp_listen = [f[4] for f in mine if f[0] == "tcp" and f[1] == "LISTEN"]
    assert tcp_listen == [f"127.0.0.1:{port}"], mine
    for f in mine:
        local, peer = f[4], f[5]
        host = local.rsplit(":", 1)[0]
        if f[0] == "tcp":
            assert host == "127.0.0.1" and peer.split(":")[0] in ("127.0.0.1", "0.0.0.0", "*"), f
        else:
            assert host in ("127.0.0.1", "0.0.0.0", "*"), f
            assert not local.endswith(":7446"), f  # Zenoh's scouting port: multicast scouting is off


@pytest.mark.parametrize("config, env, message", [
    ({"listen": {"endpoints": ["tcp/0.0.0.0:7447"]}}, {}, "endpoint 'tcp/0.0.0.0:7447' is not on loopback"),
    ({"connect": {"endpoints": ["tcp/192.0.2.1:7447"]}}, {}, "endpoint 'tcp/192.0.2.1:7447' is not on loopback"),
    ({"listen": {"endpoints": []}}, {}, "listen.endpoints is empty"),
    ({"scouting": {"multicast": {"enabled": True}}}, {}, "scouting.multicast.enabled must be false"),
    ({"plugins": {}}, {}, "no plugins.ros2dds object"),
    ({}, {"CYCLONEDDS_URI": ""}, "CYCLONEDDS_URI is not set"),
], ids=["listen-any", "connect-outer", "listen-empty", "scouting", "no-plugin", "no-dds-pin"])
def test_the_bridge_refuses_configs_that_leave_loopback(bridge_bin, tmp_path, config, env, message):
    """Exit 2 with the reason, before anything is opened."""
    base = {"mode": "router", "listen": {"endpoints": ["tcp/127.0.0.1:7447"]},
            "scouting": {"multicast": {"enabled": False}}, "plugins": {"ros2dds": {}}}
    cfg = tmp_path / "bridge.json5"
    cfg.write_text(json.dumps({**base, **config}))
    r = subprocess.run([bridge_bin, str(cfg)], capture_output=True, text=True, timeout=HANG_GUARD,
                       env={**os.environ, "CYCLONEDDS_URI": "file:///dev/null", **env})
    assert r.returncode == 2 and message in r.stderr, r.stderr
    assert r.stdout == ""  # never ready
