"""rvc's participants interoperate with independent peers: the official
Zenoh Python binding (eclipse-zenoh) and CycloneDDS's Python binding.

- a Python publisher's messages are monitored by `rvc monitor`;
- `rvc replay`'s messages and rvc's verdicts are received by Python subscribers;
- Zenoh peer-to-peer and through `rvc router` in client mode.
Oracle: `rvc check` on the same messages, and the messages themselves.
Loopback only: Zenoh on explicit tcp/127.0.0.1 ports with multicast scouting
off; DDS with the loopback-pinned XML that `rvc dds-config` prints.
"""
import json
import os
import random
import socket
import struct
import subprocess
import threading
import time

import pytest

from conftest import transports_built
from rvc_testlib import dds_matched

HANG_GUARD = 60


def free_port():
    for _ in range(100):
        port = random.randint(20000, 29999)
        with socket.socket() as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    raise RuntimeError("no free port")


def messages(n=60):
    return [json.dumps({"p": i % 5 != 0, "speed": i % 7}) for i in range(n)]


def check_all(rvc, tmp_path, spec, lines):
    f = tmp_path / "oracle.jsonl"
    f.write_text("\n".join(lines) + "\n")
    return subprocess.run([rvc, "check", "--all", "--spec", spec, str(f)], capture_output=True, text=True).stdout


def wait_for(pred, what):
    deadline = time.time() + HANG_GUARD
    while time.time() < deadline:
        if pred():
            return
        time.sleep(0.02)
    raise AssertionError(f"timed out waiting for {what}")


# ---------------------------------------------------------------- Zenoh

@pytest.fixture
def zenoh_mod(rvc):
    if "zenoh" not in transports_built(rvc):
        pytest.skip("rvc built without Zenoh")
    return pytest.importorskip("zenoh")


def zsession(zenoh, mode, listen=(), connect=()):
    conf = zenoh.Config()
    conf.insert_json5("mode", f'"{mode}"')
    if mode != "client":
        conf.insert_json5("listen/endpoints", json.dumps(list(listen) or ["tcp/127.0.0.1:0"]))
    conf.insert_json5("connect/endpoints", json.dumps(list(connect)))
    conf.insert_json5("scouting/multicast/enabled", "false")
    return zenoh.open(conf)


class ZenohNet:
    """Endpoints for rvc and Python peers: peer-to-peer (rvc monitor listens)
    or all as clients of an `rvc router`."""

    def __init__(self, rvc, via_router):
        self.port = free_port()
        self.ep = f"tcp/127.0.0.1:{self.port}"
        self.router = None
        if via_router:
            self.router = subprocess.Popen([rvc, "router", "--listen", self.ep, "--no-multicast-scouting"],
                                           stderr=subprocess.PIPE, text=True)
            line = self.router.stderr.readline()  # "rvc router: <zid> listening on [...]"
            assert "listening" in line, line
            self.monitor = ["--mode", "client", "--connect", self.ep, "--no-multicast-scouting"]
            self.other = ["--mode", "client", "--connect", self.ep, "--no-multicast-scouting"]
            self.py = dict(mode="client", connect=[self.ep])
        else:
            self.monitor = ["--mode", "peer", "--listen", self.ep, "--no-multicast-scouting"]
            self.other = ["--mode", "peer", "--connect", self.ep, "--no-multicast-scouting"]
            self.py = dict(mode="peer", connect=[self.ep])

    def close(self):
        if self.router:
            self.router.terminate()
            self.router.wait(timeout=10)


@pytest.mark.parametrize("via_router", [False, True], ids=["p2p", "router"])
def test_python_publisher_is_monitored_and_verdicts_reach_python(rvc, tmp_path, zenoh_mod, via_router):
    zenoh = zenoh_mod
    net = ZenohNet(rvc, via_router)
    key, vkey = "rvc/py/in", "rvc/py/verdicts"
    lines = messages()
    spec = "{p} or {speed > 5}"
    verdicts, eos = [], threading.Event()
    mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", spec, "--input", f"zenoh:{key}",
                            "--output", f"zenoh:{vkey}", "--exit-on-eos", *net.monitor],
                           stderr=subprocess.PIPE, text=True)
    try:
        time.sleep(0.3)  # let the monitor listen before Python connects to it
        s = zsession(zenoh, **net.py)

        def on_verdict(sample):
            att = sample.attachment
            if att is not None and len(att.to_bytes()) >= 9 and att.to_bytes()[8] & 1:
                eos.set()
                return
            verdicts.append(sample.payload.to_bytes().decode())

        sub = s.declare_subscriber(vkey, on_verdict)
        pub = s.declare_publisher(key)
        wait_for(lambda: bool(getattr(pub.matching_status, "matching", False)), "rvc monitor to match")
        for i, l in enumerate(lines, 1):
            pub.put(l, attachment=struct.pack("<QB", i, 0))
        pub.put(b"", attachment=struct.pack("<QB", len(lines), 1))
        _, err = mon.communicate(timeout=HANG_GUARD)
        wait_for(eos.is_set, "the verdict stream's end-of-stream marker")
        stats = json.loads(err.strip().splitlines()[-1])
        assert stats["received"] == len(lines) and stats["gaps"] == 0
        assert "\n".join(verdicts) + "\n" == check_all(rvc, tmp_path, spec, lines)
        sub.undeclare()
        s.close()
    finally:
        if mon.poll() is None:
            mon.kill()
        net.close()


@pytest.mark.parametrize("via_router", [False, True], ids=["p2p", "router"])
def test_replay_reaches_a_python_subscriber(rvc, tmp_path, zenoh_mod, via_router):
    zenoh = zenoh_mod
    net = ZenohNet(rvc, via_router)
    key = "rvc/py/replayed"
    lines = messages(500)
    trace = tmp_path / "t.jsonl"
    trace.write_text("\n".join(lines) + "\n")
    got, eos = [], threading.Event()
    try:
        # Python listens (p2p) or connects to the router; replay waits for it to match.
        py_conf = dict(mode="peer", listen=[net.ep]) if not via_router else net.py
        s = zsession(zenoh, **py_conf)

        def on_sample(sample):
            seq, flags = struct.unpack("<QB", sample.attachment.to_bytes()[:9])
            if flags & 1:
                eos.set()
            else:
                got.append((seq, sample.payload.to_bytes().decode()))

        sub = s.declare_subscriber(key, on_sample)
        other = ["--mode", "peer", "--connect", net.ep, "--no-multicast-scouting"] if not via_router else net.other
        rep = subprocess.run([rvc, "replay", str(trace), "--to", f"zenoh:{key}", *other], capture_output=True,
                             text=True, timeout=HANG_GUARD)
        assert rep.returncode == 0, rep.stderr
        wait_for(eos.is_set, "end of stream")
        assert got == list(enumerate(lines, 1))
        sub.undeclare()
        s.close()
    finally:
        net.close()


def test_plain_python_publisher_without_attachments(rvc, tmp_path, zenoh_mod):
    """A publisher that knows nothing of rvc (no sequence numbers, no
    end-of-stream) is still monitored; the monitor stops on SIGTERM."""
    zenoh = zenoh_mod
    net = ZenohNet(rvc, False)
    out = tmp_path / "v.jsonl"
    lines = messages(40)
    mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", "{p}", "--input", "zenoh:rvc/plain",
                            "--output", f"file:{out}", *net.monitor], stderr=subprocess.PIPE, text=True)
    try:
        time.sleep(0.3)
        s = zsession(zenoh, **net.py)
        pub = s.declare_publisher("rvc/plain")
        wait_for(lambda: bool(getattr(pub.matching_status, "matching", False)), "rvc monitor to match")
        for l in lines:
            pub.put(l)
        wait_for(lambda: out.exists() and len(out.read_text().splitlines()) == len(lines) or mon.poll() is not None,
                 "verdicts")
        mon.terminate()
        _, err = mon.communicate(timeout=HANG_GUARD)
        stats = json.loads(err.strip().splitlines()[-1])
        assert stats["received"] == len(lines)
        assert out.read_text() == check_all(rvc, tmp_path, "{p}", lines)
        s.close()
    finally:
        if mon.poll() is None:
            mon.kill()


# ---------------------------------------------------------------- DDS

@pytest.fixture
def dds_env(rvc, tmp_path, monkeypatch):
    if "dds" not in transports_built(rvc):
        pytest.skip("rvc built without DDS")
    cfg = tmp_path / "cyclonedds.xml"
    subprocess.run([rvc, "dds-config", "-o", str(cfg)], check=True)
    xml = cfg.read_text()
    assert 'name="lo"' in xml and "<AllowMulticast>false</AllowMulticast>" in xml
    monkeypatch.setenv("CYCLONEDDS_URI", f"file://{cfg}")  # before any Python participant exists
    cyclonedds = pytest.importorskip("cyclonedds")
    from dataclasses import dataclass
    from cyclonedds.idl import IdlStruct

    @dataclass
    class String_(IdlStruct, typename="std_msgs::msg::dds_::String_"):
        data: str

    return String_


def dds_qos():
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.util import duration
    return Qos(Policy.Reliability.Reliable(duration(seconds=30)), Policy.History.KeepAll,
               Policy.Durability.Volatile)


def test_python_dds_publisher_is_monitored_and_verdicts_reach_python(rvc, tmp_path, dds_env):
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    String_ = dds_env
    domain = 150 + os.getpid() % 50
    lines = messages()
    spec = "{p} or {speed > 5}"
    mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", spec, "--input", "dds:/rvc_py/in",
                            "--output", "dds:/rvc_py/verdicts", "--domain", str(domain)],
                           stderr=subprocess.PIPE, text=True)
    try:
        dp = DomainParticipant(domain)
        reader = DataReader(dp, Topic(dp, "rt/rvc_py/verdicts", String_), qos=dds_qos())
        writer = DataWriter(dp, Topic(dp, "rt/rvc_py/in", String_), qos=dds_qos())
        wait_for(lambda: dds_matched(writer) and dds_matched(reader),
                 "rvc monitor to match both topics")
        for l in lines:
            writer.write(String_(data=l))
        got = []

        def collect():
            got.extend(s.data for s in reader.take(N=100))
            return len(got) >= len(lines)
        wait_for(collect, "verdicts")
        mon.terminate()
        _, err = mon.communicate(timeout=HANG_GUARD)
        stats = json.loads(err.strip().splitlines()[-1])
        assert stats["received"] == len(lines) and stats["checked"] == len(lines)
        assert "\n".join(got[:len(lines)]) + "\n" == check_all(rvc, tmp_path, spec, lines)
    finally:
        if mon.poll() is None:
            mon.kill()


def test_replay_reaches_a_python_dds_subscriber(rvc, tmp_path, dds_env):
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    String_ = dds_env
    domain = 200 + os.getpid() % 30
    lines = messages(300)
    trace = tmp_path / "t.jsonl"
    trace.write_text("\n".join(lines) + "\n")
    dp = DomainParticipant(domain)
    reader = DataReader(dp, Topic(dp, "rt/rvc_py/replayed", String_), qos=dds_qos())
    rep = subprocess.run([rvc, "replay", str(trace), "--to", "dds:/rvc_py/replayed", "--domain", str(domain)],
                         capture_output=True, text=True, timeout=HANG_GUARD)
    assert rep.returncode == 0, rep.stderr
    got = []

    def collect():
        got.extend(s.data for s in reader.take(N=1000))
        return len(got) >= len(lines) + 1
    wait_for(collect, "all messages and the end-of-stream marker")
    assert got[:len(lines)] == lines
    assert got[len(lines)].startswith("\x04rvc-eos")  # the documented marker, seen by a plain ROS 2 reader


def write_batch_setting(trace):
    """CycloneDDS's own account of the configuration it runs with (--dds-trace, category config)."""
    lines = [l for l in trace.read_text().splitlines() if "config: Domain/Internal/WriteBatch/#text:" in l]
    assert lines, "no WriteBatch line in the CycloneDDS trace"
    return lines[-1].split("#text:")[1].split()[0]


@pytest.mark.parametrize("flags", [[], ["--dds-write-batch"]], ids=["default", "flag"])
def test_replay_with_write_batching_delivers_at_the_publish_rate(rvc, tmp_path, dds_env, flags):
    """rvc replay packs samples into packets (by default, or --dds-write-batch),
    but a sample published before a pause must not wait for the next one: at a
    set --rate a subscriber in another process gets every sample when it is
    published, not all of them with the last packet. (In one process CycloneDDS
    delivers locally and never batches, so this needs two.) CycloneDDS's trace
    says batching is really on."""
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    String_ = dds_env
    domain = 180 + os.getpid() % 20
    lines = messages(6)
    trace = tmp_path / "t.jsonl"
    trace.write_text("\n".join(lines) + "\n")
    dp = DomainParticipant(domain)
    reader = DataReader(dp, Topic(dp, "rt/rvc_py/batched", String_), qos=dds_qos())
    rep = subprocess.Popen([rvc, "replay", str(trace), "--to", "dds:/rvc_py/batched", "--domain", str(domain),
                            "--rate", "4", "--no-progress", "--dds-trace", str(tmp_path / "trace.txt"), *flags],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    got, arrived = [], []

    def collect():
        for s in reader.take(N=100):
            got.append(s.data)
            arrived.append(time.monotonic())
        return len(got) >= len(lines) + 1
    try:
        wait_for(collect, "all messages and the end-of-stream marker")
    finally:
        out, err = rep.communicate(timeout=HANG_GUARD)
    assert rep.returncode == 0, err
    assert got[:len(lines)] == lines and got[len(lines)].startswith("\x04rvc-eos")
    # Published 0.25 s apart (1.25 s from first to last): held back in one
    # packet until the end of stream they would arrive within milliseconds.
    assert arrived[len(lines) - 1] - arrived[0] > 0.5, [round(t - arrived[0], 3) for t in arrived]
    assert write_batch_setting(tmp_path / "trace.txt") == "true"


def test_replay_no_dds_write_batch_sends_one_packet_per_sample(rvc, tmp_path, dds_env):
    """--no-dds-write-batch turns the replay's default batching off (CycloneDDS's
    trace shows the setting it runs with), and --dds-write-batch beside it is refused."""
    trace = tmp_path / "t.jsonl"
    trace.write_text("\n".join(messages(3)) + "\n")
    domain = 200 + os.getpid() % 20
    run = subprocess.run([rvc, "replay", str(trace), "--to", "dds:/rvc_py/unbatched", "--domain", str(domain),
                          "--wait-subscribers", "0", "--no-progress", "--no-dds-write-batch",
                          "--dds-trace", str(tmp_path / "trace.txt")],
                         capture_output=True, text=True, timeout=HANG_GUARD)
    assert run.returncode == 0, run.stderr
    assert write_batch_setting(tmp_path / "trace.txt") == "false"
    both = subprocess.run([rvc, "replay", str(trace), "--to", "dds:/rvc_py/unbatched", "--domain", str(domain),
                           "--no-dds-write-batch", "--dds-write-batch"], capture_output=True, text=True,
                          timeout=HANG_GUARD)
    assert both.returncode != 0 and "excludes" in both.stderr, both.stderr
