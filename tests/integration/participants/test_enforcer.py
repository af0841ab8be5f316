"""The enforcer: `rvc monitor --on-violation PROPERTY=URI:PAYLOAD` publishes a command when a property
becomes violated (one per onset: a change to false, or a first verdict false), at most one per
`--debounce` seconds per action, as JSON or, with `--command-type`, as a CDR sample of a ROS 2 type.

Independent peers receive the commands: the Zenoh Python binding (eclipse-zenoh), rosbags' CDR
deserializer for typed payloads, and CycloneDDS's Python binding on a typed DDS topic.
Oracle: the onsets and verdicts computed by hand for each trace (written out below).
Loopback only: Zenoh on an explicit tcp/127.0.0.1 port with multicast scouting off; DDS with rvc's
default loopback configuration and, for the Python reader, the XML of `rvc dds-config` (pinned to lo).
"""
import json
import os
import struct
import subprocess
import threading
import time

import pytest

from conftest import transports_built
from test_python_peers import HANG_GUARD, dds_qos, free_port, wait_for, zsession

IN, VERDICTS = "rvc/enf/in", "rvc/enf/verdicts"

# Trace A (indices 0..19): ok is false at 2-4, 7-8 and 12-15.
TRACE_A = [i not in (2, 3, 4, 7, 8, 12, 13, 14, 15) for i in range(20)]
# {ok}: false exactly where ok is; onsets at 2, 7, 12 (three runs of 3, 2 and 4 false messages).
OK_CHANGES = [(0, True), (2, False), (5, True), (7, False), (9, True), (12, False), (16, True)]
# historically[0:2]{ok}: false while a false ok is among the last 3 messages: 2..10 (4 -> 6 and 7 -> 10
# join up) and 12..17; onsets at 2 and 12.
HIST_CHANGES = [(0, True), (2, False), (11, True), (12, False), (18, True)]


def stats_line(err):
    """The monitor's counters (its last JSON line on stderr; the enforcer's summary follows it)."""
    return json.loads([l for l in err.splitlines() if l.startswith('{"input"')][-1])


@pytest.fixture
def zenoh_mod(rvc):
    if "zenoh" not in transports_built(rvc):
        pytest.skip("rvc built without Zenoh")
    return pytest.importorskip("zenoh")


class Recorder:
    """A Zenoh subscriber keeping (seq, payload bytes) of each sample and the end-of-stream marker."""

    def __init__(self, session, key):
        self.samples, self.eos_seq, self.eos = [], None, threading.Event()
        self.sub = session.declare_subscriber(key, self._on)

    def _on(self, sample):
        att = sample.attachment.to_bytes() if sample.attachment is not None else b""
        seq, flags = struct.unpack("<QB", att[:9]) if len(att) >= 9 else (0, 0)
        if flags & 1:
            self.eos_seq = seq
            self.eos.set()
        else:
            self.samples.append((seq, sample.payload.to_bytes()))

    def payloads(self):
        return [p for _, p in self.samples]


def run_zenoh(rvc, zenoh, specs, actions, values, extra=(), pause=None):
    """rvc monitor on zenoh:IN (listening on a loopback port) with verdicts on zenoh:VERDICTS; a Python
    peer subscribes to the verdicts and to each action's key, publishes {"ok": v} for each value (after
    sleeping pause(i) seconds before message i, if given), then the end-of-stream marker. Returns
    (exit code, stderr, verdicts as (time, property, value), {key: Recorder})."""
    ep = f"tcp/127.0.0.1:{free_port()}"
    cmd = [rvc, "monitor", "--input", f"zenoh:{IN}", "--output", f"zenoh:{VERDICTS}", "--exit-on-eos",
           "--wait-subscribers", "1", "--wait-timeout", "20", "--mode", "peer", "--listen", ep,
           "--no-multicast-scouting", *extra]
    for s in specs:
        cmd += ["--spec", s]
    keys = []
    for a in actions:
        cmd += ["--on-violation", a]
        keys.append(a.split("=", 1)[1].split(":")[1])
    mon = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    s = None
    try:
        time.sleep(0.3)  # let the monitor listen before Python connects to it
        s = zsession(zenoh, mode="peer", connect=[ep])
        verdicts = Recorder(s, VERDICTS)
        commands = {k: Recorder(s, k) for k in keys}
        pub = s.declare_publisher(IN)
        # The monitor subscribes to its input only once its verdict and command keys have a subscriber.
        wait_for(lambda: bool(getattr(pub.matching_status, "matching", False)), "rvc monitor to match")
        for i, v in enumerate(values):
            if pause:
                time.sleep(pause(i))
            pub.put(json.dumps({"ok": v}), attachment=struct.pack("<QB", i + 1, 0))
        pub.put(b"", attachment=struct.pack("<QB", len(values), 1))
        _, err = mon.communicate(timeout=HANG_GUARD)
        # Typed commands end without a marker; the verdicts' marker comes after them on the same link.
        typed = "--command-type" in extra
        for r in [verdicts, *([] if typed else commands.values())]:
            wait_for(r.eos.is_set, "the end-of-stream markers of the verdicts and commands")
        got = [json.loads(p) for p in verdicts.payloads()]
        return mon.returncode, err, [(v["time"], v["property"], v["value"]) for v in got], commands
    finally:
        if mon.poll() is None:
            mon.kill()
        if s is not None:
            s.close()


# ---------------------------------------------------------------- JSON commands over Zenoh

def test_one_command_per_onset_over_zenoh(rvc, zenoh_mod):
    """Trace A: {ok} becomes violated 3 times (runs of 3, 2 and 4 false messages), historically[0:2]{ok}
    twice. Each action's key gets exactly one command per onset, with its payload byte for byte and
    sequence numbers 1..n, then an end-of-stream marker carrying n; the verdicts agree."""
    stop, hazard = '{"stop":true,"reason":"p1"}', '{"hazard_lights":"on"}'
    rc, err, verdicts, cmds = run_zenoh(
        rvc, zenoh_mod, ["{ok}", "historically[0:2]{ok}"],
        [f"p1=zenoh:rvc/enf/stop:{stop}", f"p2=zenoh:rvc/enf/hazard:{hazard}"], TRACE_A)
    assert rc == 1, err
    assert [(t, v) for t, p, v in verdicts if p == "p1"] == OK_CHANGES
    assert [(t, v) for t, p, v in verdicts if p == "p2"] == HIST_CHANGES
    assert cmds["rvc/enf/stop"].samples == [(1, stop.encode()), (2, stop.encode()), (3, stop.encode())]
    assert cmds["rvc/enf/hazard"].samples == [(1, hazard.encode()), (2, hazard.encode())]
    assert cmds["rvc/enf/stop"].eos_seq == 3 and cmds["rvc/enf/hazard"].eos_seq == 2
    stats = stats_line(err)
    assert stats["received"] == 20 and stats["gaps"] == 0, err
    assert "rvc monitor: 5 commands sent on violation (0 debounced)" in err, err


def test_a_first_verdict_false_is_an_onset_and_two_actions_share_a_property(rvc, zenoh_mod):
    """A trace that starts violated (4 false messages): the first verdict is false and fires, the other
    3 of that run fire nothing more; a later onset (index 6) fires again. Two actions on p1 both fire."""
    values = [False, False, False, False, True, True, False, False, True]
    rc, err, verdicts, cmds = run_zenoh(
        rvc, zenoh_mod, ["{ok}"], ['p1=zenoh:rvc/enf/a:{"n":1}', 'p1=zenoh:rvc/enf/b:{"n":2}'], values)
    assert rc == 1, err
    assert verdicts == [(0, "p1", False), (4, "p1", True), (6, "p1", False), (8, "p1", True)]
    assert cmds["rvc/enf/a"].payloads() == [b'{"n":1}', b'{"n":1}']
    assert cmds["rvc/enf/b"].payloads() == [b'{"n":2}', b'{"n":2}']
    assert "rvc monitor: 4 commands sent on violation (0 debounced)" in err, err


def test_no_violation_sends_no_command(rvc, zenoh_mod):
    rc, err, verdicts, cmds = run_zenoh(rvc, zenoh_mod, ["{ok}"], ['p1=zenoh:rvc/enf/quiet:{"stop":true}'],
                                        [True] * 8)
    assert rc == 0, err
    assert verdicts == [(0, "p1", True)]
    assert cmds["rvc/enf/quiet"].samples == [] and cmds["rvc/enf/quiet"].eos_seq == 0
    assert "rvc monitor: 0 commands sent on violation (0 debounced)" in err, err


# ---------------------------------------------------------------- --debounce

# Three onsets (indices 1, 3, 5), each one message long.
DEBOUNCE_TRACE = [True, False, True, False, True, False, True]


def test_debounce_keeps_one_command_for_onsets_within_the_interval(rvc, zenoh_mod):
    """--debounce 30: the 3 onsets come 0.3 s apart, well within 30 s: only the first fires, the other
    two are counted as debounced; the verdicts still report every onset."""
    rc, err, verdicts, cmds = run_zenoh(rvc, zenoh_mod, ["{ok}"], ['p1=zenoh:rvc/enf/deb:{"stop":true}'],
                                        DEBOUNCE_TRACE, extra=["--debounce", "30"], pause=lambda i: 0.15)
    assert rc == 1, err
    assert [t for t, _, v in verdicts if not v] == [1, 3, 5]
    assert cmds["rvc/enf/deb"].samples == [(1, b'{"stop":true}')] and cmds["rvc/enf/deb"].eos_seq == 1
    assert "rvc monitor: 1 command sent on violation (2 debounced)" in err, err


def test_debounce_lets_an_onset_after_the_interval_through(rvc, zenoh_mod):
    """--debounce 1: onsets at about 0 s, 0.1 s and 2.6 s (the publisher sleeps 2.5 s before index 5):
    the second is debounced, the third is 2.6 s after the last command and fires."""
    rc, err, verdicts, cmds = run_zenoh(rvc, zenoh_mod, ["{ok}"], ['p1=zenoh:rvc/enf/deb2:{"stop":true}'],
                                        DEBOUNCE_TRACE, extra=["--debounce", "1"],
                                        pause=lambda i: 2.5 if i == 5 else 0.05)
    assert rc == 1, err
    assert [t for t, _, v in verdicts if not v] == [1, 3, 5]
    assert cmds["rvc/enf/deb2"].payloads() == [b'{"stop":true}'] * 2
    assert "rvc monitor: 2 commands sent on violation (1 debounced)" in err, err


# ---------------------------------------------------------------- typed commands

@pytest.fixture
def rosbags_store():
    typesys = pytest.importorskip("rosbags.typesys")
    return typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)


def test_typed_command_over_zenoh_is_a_cdr_bool(rvc, zenoh_mod, rosbags_store):
    """--command-type std_msgs/msg/Bool: the payload {"data":true} goes out as a CDR sample (encapsulation
    header included, as zenoh-bridge-ros2dds forwards ROS 2 samples) that rosbags decodes to data=True."""
    rc, err, verdicts, cmds = run_zenoh(rvc, zenoh_mod, ["{ok}"], ['p1=zenoh:rvc/enf/estop:{"data":true}'],
                                        [True, False, False, True, False],
                                        extra=["--command-type", "std_msgs/msg/Bool"])
    assert rc == 1, err
    assert [(t, v) for t, _, v in verdicts] == [(0, True), (1, False), (3, True), (4, False)]
    raw = cmds["rvc/enf/estop"].payloads()
    assert len(raw) == 2 and raw[0] == raw[1]
    # No end-of-stream marker: through zenoh-bridge-ros2dds its empty payload would be an empty,
    # malformed sample for ROS 2 subscribers (tests/integration/bridge).
    assert cmds["rvc/enf/estop"].eos_seq is None and not cmds["rvc/enf/estop"].eos.is_set()
    msg = rosbags_store.deserialize_cdr(raw[0], "std_msgs/msg/Bool")
    assert msg.data is True
    # The same bytes as rosbags' own serialization of Bool(data=True) (00 01 00 00 01), up to at most
    # 3 bytes of CDR's trailing padding (zeros).
    ref = bytes(rosbags_store.serialize_cdr(rosbags_store.types["std_msgs/msg/Bool"](data=True),
                                            "std_msgs/msg/Bool"))
    assert ref == b"\x00\x01\x00\x00\x01"
    assert raw[0] == ref + b"\x00" * (len(raw[0]) - len(ref)) and len(raw[0]) - len(ref) < 4, raw[0]


@pytest.fixture
def dds_bool(rvc, tmp_path, monkeypatch):
    if "dds" not in transports_built(rvc):
        pytest.skip("rvc built without DDS")
    cfg = tmp_path / "cyclonedds.xml"
    subprocess.run([rvc, "dds-config", "-o", str(cfg)], check=True)
    xml = cfg.read_text()
    assert 'name="lo"' in xml and "<AllowMulticast>false</AllowMulticast>" in xml
    monkeypatch.setenv("CYCLONEDDS_URI", f"file://{cfg}")  # before any Python participant exists
    pytest.importorskip("cyclonedds")
    from dataclasses import dataclass

    from cyclonedds.idl import IdlStruct

    @dataclass
    class Bool_(IdlStruct, typename="std_msgs::msg::dds_::Bool_"):
        data: bool

    return Bool_


def test_typed_command_over_dds_reaches_a_python_reader(rvc, tmp_path, dds_bool):
    """--command-type std_msgs/msg/Bool on dds:/vehicle/emergency_stop: a CycloneDDS Python reader of
    std_msgs::msg::dds_::Bool_ on rt/vehicle/emergency_stop (as a ROS 2 node sees it) reads one
    Bool(data=True) per onset. The input is a file, so the run is deterministic; the monitor waits for
    the reader (--wait-subscribers 1) and, at the end, for its acknowledgements."""
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    domain = 40 + os.getpid() % 40
    trace = tmp_path / "trace.jsonl"
    trace.write_text("".join(json.dumps({"ok": v}) + "\n" for v in TRACE_A))
    dp = DomainParticipant(domain)
    qos = dds_qos() + Qos(Policy.DataRepresentation(use_cdrv0_representation=True))  # XCDR1, as rmw_cyclonedds
    reader = DataReader(dp, Topic(dp, "rt/vehicle/emergency_stop", dds_bool), qos=qos)
    r = subprocess.run([rvc, "monitor", "--input", f"file:{trace}", "--spec", "{ok}", "--on-violation",
                        'p1=dds:/vehicle/emergency_stop:{"data":true}', "--command-type", "std_msgs/msg/Bool",
                        "--wait-subscribers", "1", "--wait-timeout", "20", "--domain", str(domain)],
                       capture_output=True, text=True, timeout=HANG_GUARD)
    assert r.returncode == 1, r.stderr
    assert [(v["time"], v["value"]) for v in map(json.loads, r.stdout.splitlines())] == OK_CHANGES
    assert "rvc monitor: 3 commands sent on violation (0 debounced)" in r.stderr, r.stderr
    got = []

    def collect():
        got.extend(reader.take(N=10))
        return len(got) >= 3
    wait_for(collect, "the 3 typed commands")
    time.sleep(0.3)
    got.extend(reader.take(N=10))
    assert [s.data for s in got] == [True, True, True]


# ---------------------------------------------------------------- file: endpoint

def test_file_commands_are_exact_lines(rvc, tmp_path):
    """A file input and a file: command endpoint: one line per onset, the payload as given (with
    --command-type a file still gets the JSON text); the verdict lines agree."""
    trace = tmp_path / "trace.jsonl"
    trace.write_text("".join(json.dumps({"ok": v}) + "\n" for v in TRACE_A))
    stop, hazard = tmp_path / "stop.jsonl", tmp_path / "hazard.jsonl"
    r = subprocess.run([rvc, "monitor", "--input", f"file:{trace}", "--spec", "{ok}", "--spec",
                        "historically[0:2]{ok}", "--on-violation", f'p1=file:{stop}:{{"stop": true, "why": "a:b"}}',
                        "--on-violation", f'p2=file:{hazard}:{{"data":true}}', "--command-type",
                        "std_msgs/msg/Bool"], capture_output=True, text=True, timeout=HANG_GUARD)
    assert r.returncode == 1, r.stderr
    assert stop.read_text() == '{"stop": true, "why": "a:b"}\n' * 3
    assert hazard.read_text() == '{"data":true}\n' * 2
    verdicts = [json.loads(l) for l in r.stdout.splitlines()]
    assert [(v["time"], v["value"]) for v in verdicts if v["property"] == "p1"] == OK_CHANGES
    assert [(v["time"], v["value"]) for v in verdicts if v["property"] == "p2"] == HIST_CHANGES
    assert "rvc monitor: 5 commands sent on violation (0 debounced)" in r.stderr


def test_file_commands_with_debounce_and_all_verdicts(rvc, tmp_path):
    """--all reports every false verdict (9 for trace A), but commands still follow the 3 onsets;
    --debounce 30 on a file run (which takes milliseconds) leaves only the first."""
    trace = tmp_path / "trace.jsonl"
    trace.write_text("".join(json.dumps({"ok": v}) + "\n" for v in TRACE_A))
    for debounce, want in (("0", 3), ("30", 1)):
        cmd = tmp_path / f"cmd{debounce}.jsonl"
        r = subprocess.run([rvc, "monitor", "--all", "--input", f"file:{trace}", "--spec", "{ok}", "--on-violation",
                            f"p1=file:{cmd}:STOP", "--debounce", debounce], capture_output=True, text=True,
                           timeout=HANG_GUARD)
        assert r.returncode == 1, r.stderr
        assert sum(not json.loads(l)["value"] for l in r.stdout.splitlines()) == 9
        assert cmd.read_text() == "STOP\n" * want
        assert f"({3 - want} debounced)" in r.stderr, r.stderr


# ---------------------------------------------------------------- usage errors

@pytest.mark.parametrize("action, extra, message", [
    ('p3=file:c.jsonl:{"a":1}', [], "--on-violation p3: no property of that name (the properties: p1, p2)"),
    ('p1=udp:host:{"a":1}', [], "commands go to zenoh:KEY, dds:TOPIC or file:PATH, not 'udp:'"),
    ('=file:c.jsonl:{"a":1}', [], "expected PROPERTY=URI:PAYLOAD"),
    ("p1=file:c.jsonl", [], "expected PROPERTY=URI:PAYLOAD, e.g. p1=zenoh:vehicle/hazard:{\"on\":true} "
                            "(no ':' before the payload)"),
    ('{"stop":true}', [], "expected PROPERTY=URI:PAYLOAD"),
    ('p1=zenoh::{"a":1}', [], "(no key or topic after 'zenoh:')"),
    ('p1=zenoh:rvc/enf/x:{"data":"yes"}', ["--command-type", "std_msgs/msg/Bool"],
     'payload as std_msgs/msg/Bool: field data: expected true or false, got "yes"'),
    ('p1=zenoh:rvc/enf/x:{"stop":true}', ["--command-type", "std_msgs/msg/Bool"],
     "payload as std_msgs/msg/Bool: unknown field 'stop'"),
    ('p1=zenoh:rvc/enf/x:stop', ["--command-type", "std_msgs/msg/Bool"], "payload as std_msgs/msg/Bool: not JSON"),
    ('p1=zenoh:rvc/enf/x:{"data":true}', ["--command-type", "std_msgs/msg/NoSuchType"],
     "unknown message type std_msgs/msg/NoSuchType"),
], ids=["unknown-property", "unknown-scheme", "empty-property", "no-payload", "no-property", "no-key",
        "bad-field-value", "unknown-field", "not-json", "unknown-type"])
def test_usage_errors(rvc, tmp_path, action, extra, message):
    trace = tmp_path / "trace.jsonl"
    trace.write_text('{"ok": false}\n')
    r = subprocess.run([rvc, "monitor", "--input", f"file:{trace}", "--spec", "{ok}", "--spec", "once{ok}",
                        "--on-violation", action, *extra, "--no-multicast-scouting"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=30)
    assert r.returncode == 2, r.stderr
    assert message in r.stderr, r.stderr
    assert r.stdout == ""  # refused before checking anything
    assert not (tmp_path / "c.jsonl").exists()
