"""Typed ROS 2 topics over DDS: rvc subscribes to and publishes samples of a ROS 2 type
(pkg::msg::dds_::Name_ on rt/...) from the type's .msg definition, with no generated code.

Independent peer: CycloneDDS's Python binding (cyclonedds on PyPI), with the types declared as
IdlStruct classes the way rosidl maps .msg to IDL, writing XCDR1 as rmw_cyclonedds does.
- a Python publisher's samples are echoed by `rvc echo --type` exactly (every kind of field:
  nested types two deep, bounded/unbounded sequences, fixed arrays, bounded strings, 64-bit
  integers, an empty message) and checked by `rvc monitor --type` (oracle: `rvc check` on the
  values the test wrote, as JSON);
- `rvc replay --type` samples are read by a Python subscriber with the values of the JSON lines;
- a bad JSON line in `rvc replay --type` is named and skipped (exit 3), the rest still arrives.
Loopback only: the loopback-pinned XML of `rvc dds-config` for the Python participant.
"""
import json
import os
import random
import subprocess
import time

import pytest

from conftest import transports_built
from rvc_testlib import dds_matched
from test_python_peers import HANG_GUARD, dds_qos, wait_for

MSGS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "dds", "msgs")
MIXED = "rvc_test_msgs/msg/Mixed"
GEAR = "autoware_auto_vehicle_msgs/msg/GearReport"


@pytest.fixture
def types(rvc, tmp_path, monkeypatch):
    if "dds" not in transports_built(rvc):
        pytest.skip("rvc built without DDS")
    cfg = tmp_path / "cyclonedds.xml"
    subprocess.run([rvc, "dds-config", "-o", str(cfg)], check=True)
    monkeypatch.setenv("CYCLONEDDS_URI", f"file://{cfg}")  # before any Python participant exists
    pytest.importorskip("cyclonedds")
    from dataclasses import dataclass

    from cyclonedds.idl import IdlStruct
    from cyclonedds.idl.types import (array, bounded_str, float32, float64, int8, int16, int32, int64, sequence,
                                      uint8, uint16, uint32, uint64)

    @dataclass
    class Time_(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
        sec: int32
        nanosec: uint32

    @dataclass
    class Deep_(IdlStruct, typename="rvc_test_msgs::msg::dds_::Deep_"):
        id: int64
        code: bounded_str[5]

    @dataclass
    class Inner_(IdlStruct, typename="rvc_test_msgs::msg::dds_::Inner_"):
        x: float32
        label: str
        raw: array[uint8, 2]
        deep: Deep_

    @dataclass
    class Nothing_(IdlStruct, typename="rvc_test_msgs::msg::dds_::Nothing_"):
        structure_needs_at_least_one_member: uint8

    @dataclass
    class Mixed_(IdlStruct, typename="rvc_test_msgs::msg::dds_::Mixed_"):
        stamp: Time_
        ok: bool
        b: uint8
        c: uint8
        i8: int8
        u8: uint8
        i16: int16
        u16: uint16
        i32: int32
        u32: uint32
        i64: int64
        big: uint64
        f: float32
        d: float64
        name: str
        tag: bounded_str[8]
        pos: array[float64, 3]
        samples: sequence[int16]
        inners: sequence[Inner_, 2]
        flags: sequence[bool]
        words: sequence[bounded_str[4]]
        codes: array[bounded_str[3], 2]
        pair: array[Inner_, 2]
        many: sequence[Inner_]
        names: array[str, 2]
        more: sequence[str, 3]
        counts: sequence[uint32, 4]
        nothing: Nothing_
        deep: Deep_

    @dataclass
    class GearReport_(IdlStruct, typename="autoware_auto_vehicle_msgs::msg::dds_::GearReport_"):
        stamp: Time_
        report: uint8

    @dataclass
    class Verdict_(IdlStruct, typename="rvc_msgs::msg::dds_::Verdict_"):
        time: float64
        property: str
        value: bool
        stamp: Time_
        robustness: float64
        explanation: sequence[str]

    return {"Time": Time_, "Deep": Deep_, "Inner": Inner_, "Nothing": Nothing_, "Mixed": Mixed_,
            "Gear": GearReport_, "Verdict": Verdict_}


def xcdr1_qos():
    """ROS 2 over CycloneDDS writes XCDR1 (rmw_cyclonedds); the Python binding needs telling."""
    from cyclonedds.qos import Policy, Qos
    return dds_qos() + Qos(Policy.DataRepresentation(use_cdrv0_representation=True))


def text(rng, n):
    return "".join(rng.choice("abcxyz _-") for _ in range(rng.randint(0, n)))


def random_mixed(rng, i):
    """One message as JSON-ready values (floats exact in float32 where the field is float32)."""
    def deep():
        return {"id": rng.randint(-2**63, 2**63 - 1), "code": text(rng, 5)}

    def inner():
        return {"x": rng.randint(-1000, 1000) / 8, "label": text(rng, 12), "raw": [rng.randint(0, 255) for _ in range(2)],
                "deep": deep()}
    return {
        "stamp": {"sec": 100 + i, "nanosec": rng.randint(0, 999_999_999)}, "ok": rng.random() < 0.5,
        "b": rng.randint(0, 255), "c": rng.randint(0, 255), "i8": rng.randint(-128, 127), "u8": rng.randint(0, 255),
        "i16": rng.randint(-2**15, 2**15 - 1), "u16": rng.randint(0, 2**16 - 1),
        "i32": rng.randint(-2**31, 2**31 - 1), "u32": rng.randint(0, 2**32 - 1),
        "i64": rng.randint(-2**63, 2**63 - 1), "big": rng.randint(0, 2**64 - 1),
        "f": rng.randint(-4096, 4096) / 16, "d": rng.uniform(-1e6, 1e6),
        "name": text(rng, 20), "tag": text(rng, 8), "pos": [rng.uniform(-10, 10) for _ in range(3)],
        "samples": [rng.randint(-2**15, 2**15 - 1) for _ in range(rng.randint(0, 5))],
        "inners": [inner() for _ in range(rng.randint(0, 2))],
        "flags": [rng.random() < 0.5 for _ in range(rng.randint(0, 4))],
        "words": [text(rng, 4) for _ in range(rng.randint(0, 3))],
        "codes": [text(rng, 3), text(rng, 3)], "pair": [inner(), inner()],
        "many": [inner() for _ in range(rng.randint(0, 3))], "names": [text(rng, 6), text(rng, 6)],
        "more": [text(rng, 6) for _ in range(rng.randint(0, 3))],
        "counts": [rng.randint(0, 2**32 - 1) for _ in range(rng.randint(0, 4))],
        "nothing": {}, "deep": deep(),
    }


def to_idl(T, v):
    """JSON values -> the IdlStruct sample (nested structs built from their dicts)."""
    def inner(d):
        return T["Inner"](x=d["x"], label=d["label"], raw=d["raw"], deep=T["Deep"](**d["deep"]))
    return T["Mixed"](**{**v, "stamp": T["Time"](**v["stamp"]), "inners": [inner(d) for d in v["inners"]],
                         "pair": [inner(d) for d in v["pair"]], "many": [inner(d) for d in v["many"]],
                         "nothing": T["Nothing"](structure_needs_at_least_one_member=0),
                         "deep": T["Deep"](**v["deep"])})


def from_idl(s):
    """An IdlStruct sample -> JSON values, as rvc writes them."""
    from dataclasses import fields, is_dataclass
    if is_dataclass(s):
        if type(s).__name__ == "Nothing_":
            return {}
        return {f.name: from_idl(getattr(s, f.name)) for f in fields(s)}
    if isinstance(s, (bytes, bytearray)):  # the binding gives uint8 arrays as bytes
        return list(s)
    if isinstance(s, (list, tuple)):
        return [from_idl(x) for x in s]
    return s


def test_python_typed_publisher_is_echoed_and_monitored(rvc, tmp_path, types):
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic
    domain = 120 + os.getpid() % 30
    rng = random.Random(11)
    values = [random_mixed(rng, i) for i in range(40)]
    spec = "{big > 9223372036854775807} or ({ok} and {i16 < 0})"
    common = ["--type", MIXED, "--msg-path", MSGS, "--domain", str(domain), "--idle-timeout", "3"]
    echo = subprocess.Popen([rvc, "echo", "dds:/rvc_typed/mixed", *common], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", spec, "--input", "dds:/rvc_typed/mixed", *common],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        dp = DomainParticipant(domain)
        writer = DataWriter(dp, Topic(dp, "rt/rvc_typed/mixed", types["Mixed"]), qos=xcdr1_qos())
        wait_for(lambda: dds_matched(writer) >= 2, "rvc echo and rvc monitor to match")
        for v in values:
            writer.write(to_idl(types, v))
        out, err = echo.communicate(timeout=HANG_GUARD)
        assert echo.returncode == 0, err
        got = [json.loads(l) for l in out.splitlines()]
        assert got == values  # every field, exactly (floats are exact in their wire type here)
        mout, merr = mon.communicate(timeout=HANG_GUARD)
        stats = json.loads(merr.strip().splitlines()[-1])
        assert stats["received"] == len(values) and stats["checked"] == len(values) and stats["rejected"] == 0
        oracle = tmp_path / "values.jsonl"
        oracle.write_text("".join(json.dumps(v) + "\n" for v in values))
        expected = subprocess.run([rvc, "check", "--all", "--spec", spec, str(oracle)], capture_output=True,
                                  text=True).stdout
        assert mout == expected and '"value":false' in expected and '"value":true' in expected
    finally:
        for p in (echo, mon):
            if p.poll() is None:
                p.kill()


def test_typed_replay_reaches_a_python_subscriber(rvc, tmp_path, types):
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    domain = 160 + os.getpid() % 30
    rng = random.Random(5)
    values = [random_mixed(rng, i) for i in range(30)]
    lines = [json.dumps(v) for v in values]
    lines.insert(7, '{"stamp": {"sec": 1}, "u8": 300}')  # out of range: named and skipped
    trace = tmp_path / "mixed.jsonl"
    trace.write_text("\n".join(lines) + "\n")
    dp = DomainParticipant(domain)
    reader = DataReader(dp, Topic(dp, "rt/rvc_typed/replayed", types["Mixed"]), qos=xcdr1_qos())
    rep = subprocess.run([rvc, "replay", str(trace), "--to", "dds:/rvc_typed/replayed", "--type", MIXED,
                          "--msg-path", MSGS, "--domain", str(domain), "--no-progress"],
                         capture_output=True, text=True, timeout=HANG_GUARD)
    assert rep.returncode == 3, rep.stderr  # one line rejected
    assert "line 8" in rep.stderr and "u8" in rep.stderr
    summary = json.loads(rep.stdout.strip().splitlines()[-1])
    assert summary["sent"] == len(values) and summary["rejected"] == 1
    got = []

    def collect():
        got.extend(reader.take(N=100))
        return len(got) >= len(values)
    wait_for(collect, "the typed samples")
    time.sleep(0.3)
    got.extend(reader.take(N=100))
    assert [from_idl(s) for s in got] == values


def test_typed_verdicts_reach_a_python_subscriber(rvc, tmp_path, types):
    """--verdict-type rvc_msgs/msg/Verdict: verdicts on a dds: output are typed samples a Python
    CycloneDDS reader of its own IDL type reads; a file output keeps JSON lines; the two agree."""
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    domain = 100 + os.getpid() % 30
    trace = tmp_path / "gear.jsonl"
    trace.write_text("".join(json.dumps({"stamp": {"sec": i, "nanosec": 0}, "report": r}) + "\n"
                             for i, r in enumerate([2, 22, 20, 2, 20, 22, 20])))
    dp = DomainParticipant(domain)
    reader = DataReader(dp, Topic(dp, "rt/rv/typed_verdicts", types["Verdict"]), qos=xcdr1_qos())
    out = tmp_path / "verdicts.jsonl"
    mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", "{report == REVERSE} -> pre {report == PARK}",
                            "--input", "dds:/vehicle/status/gear_status", "--type", GEAR, "--output",
                            "dds:/rv/typed_verdicts", "--output", f"file:{out}", "--verdict-type",
                            "rvc_msgs/msg/Verdict", "--wait-subscribers", "1", "--domain", str(domain),
                            "--idle-timeout", "3"], stderr=subprocess.PIPE, text=True)
    try:
        replay_gear(rvc, trace, domain)
        _, err = mon.communicate(timeout=HANG_GUARD)
        assert mon.returncode == 1, err  # the spec is violated at step 4
    finally:
        if mon.poll() is None:
            mon.kill()
    expected = [json.loads(line) for line in out.read_text().splitlines()]
    assert len(expected) == 7 and not all(v["value"] for v in expected)
    got = []

    def collect():
        got.extend(reader.take(N=100))
        return len(got) >= len(expected)
    wait_for(collect, "the typed verdicts")
    assert [{"time": v.time, "property": v.property, "value": v.value} for v in got] == expected
    # Boolean verdicts: robustness NaN; stamp: when the verdict was made (a live input: the wall clock)
    assert all(v.robustness != v.robustness and v.stamp.sec > 1_600_000_000 for v in got)


def replay_gear(rvc, trace, domain):
    """Publishes the JSON lines of `trace` as GearReport samples on /vehicle/status/gear_status."""
    rep = subprocess.run([rvc, "replay", str(trace), "--to", "dds:/vehicle/status/gear_status", "--type", GEAR,
                          "--domain", str(domain), "--no-progress"], capture_output=True, text=True,
                         timeout=HANG_GUARD)
    assert rep.returncode == 0, rep.stderr


def test_typed_replay_to_monitor_with_constants(rvc, tmp_path, types):
    """rvc to rvc over a typed topic of the paper's Table 3, with a message constant in the spec."""
    domain = 190 + os.getpid() % 30
    reports = [2, 2, 20, 22, 2, 20, 20, 1, 22, 2]
    lines = [json.dumps({"stamp": {"sec": i, "nanosec": 0}, "report": r}) for i, r in enumerate(reports)]
    trace = tmp_path / "gear.jsonl"
    trace.write_text("\n".join(lines) + "\n")
    spec = "{report == REVERSE} -> pre {report == PARK}"
    mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", spec, "--input", "dds:/vehicle/status/gear_status",
                            "--type", GEAR, "--domain", str(domain), "--idle-timeout", "2"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        replay_gear(rvc, trace, domain)
        out, err = mon.communicate(timeout=HANG_GUARD)
        numeric = tmp_path / "numeric.jsonl"
        numeric.write_text(trace.read_text())
        expected = subprocess.run([rvc, "check", "--all", "--spec", "{report == 20} -> pre {report == 22}",
                                   str(numeric)], capture_output=True, text=True).stdout
        assert out == expected and '"value":false' in expected, err
    finally:
        if mon.poll() is None:
            mon.kill()


def test_typed_bridge_dds_to_zenoh(rvc, tmp_path, types):
    """rvc bridge --type: a typed DDS topic forwarded to Zenoh as CDR payloads (what
    zenoh-bridge-ros2dds does), echoed from Zenoh with the values replayed into DDS."""
    if "zenoh" not in transports_built(rvc):
        pytest.skip("rvc built without Zenoh")
    from test_python_peers import free_port
    domain = 100 + os.getpid() % 20
    rng = random.Random(9)
    values = [random_mixed(rng, i) for i in range(25)]
    trace = tmp_path / "mixed.jsonl"
    trace.write_text("".join(json.dumps(v) + "\n" for v in values))
    typed = ["--type", MIXED, "--msg-path", MSGS]
    ep = f"tcp/127.0.0.1:{free_port()}"
    zenoh = ["--no-multicast-scouting"]
    echo = subprocess.Popen([rvc, "echo", "zenoh:rvc_typed/bridged", *typed, "--idle-timeout", "3", "--listen", ep,
                             *zenoh], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    bridge = subprocess.Popen([rvc, "bridge", "dds:/rvc_typed/bridged", "zenoh:rvc_typed/bridged", *typed,
                               "--domain", str(domain), "--connect", ep, *zenoh],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        rep = subprocess.run([rvc, "replay", str(trace), "--to", "dds:/rvc_typed/bridged", *typed, "--domain",
                              str(domain), "--no-progress", "--wait-timeout", "30"],
                             capture_output=True, text=True, timeout=HANG_GUARD)
        assert rep.returncode == 0, rep.stderr
        out, err = echo.communicate(timeout=HANG_GUARD)
        assert echo.returncode == 0, err
        assert [json.loads(l) for l in out.splitlines()] == values
    finally:
        for p in (echo, bridge):
            if p.poll() is None:
                p.kill()


def test_typed_dense_time_is_the_stamp(rvc, tmp_path, types):
    """--dense on a typed topic reads each sample's stamp (sec + nanosec) as its time, with no
    --time-field: verdicts equal `rvc check --dense` on the same values with the time written
    out as a number. `rvc echo --field` prints only the chosen field."""
    domain = 210 + os.getpid() % 15
    rng = random.Random(3)
    reports, t_ns = [], 5_000_000_000
    for _ in range(30):
        t_ns += rng.choice([40, 100, 250, 1000]) * 1_000_000
        reports.append((t_ns, rng.choice([1, 2, 20, 22])))
    lines = [json.dumps({"stamp": {"sec": t // 10**9, "nanosec": t % 10**9}, "report": r}) for t, r in reports]
    trace = tmp_path / "gear.jsonl"
    trace.write_text("\n".join(lines) + "\n")
    spec = "{report == REVERSE} -> once[0:0.5]{report == PARK}"
    topic = "dds:/vehicle/status/gear_dense"
    common = ["--type", GEAR, "--domain", str(domain), "--idle-timeout", "2"]
    mon = subprocess.Popen([rvc, "monitor", "--dense", "--spec", spec, "--input", topic, *common],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    echo = subprocess.Popen([rvc, "echo", topic, "--field", "stamp.sec", *common], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        rep = subprocess.run([rvc, "replay", str(trace), "--to", topic, "--type", GEAR, "--domain", str(domain),
                              "--no-progress", "--wait-subscribers", "2"], capture_output=True, text=True,
                             timeout=HANG_GUARD)
        assert rep.returncode == 0, rep.stderr
        out, err = mon.communicate(timeout=HANG_GUARD)
        numeric = tmp_path / "numeric.jsonl"
        numeric.write_text("".join(json.dumps({"t": t / 1e9, "report": r}) + "\n" for t, r in reports))
        expected = subprocess.run([rvc, "check", "--dense", "--time-field", "t", "--spec",
                                   "{report == 20} -> once[0:0.5]{report == 22}", str(numeric)],
                                  capture_output=True, text=True).stdout
        assert out == expected and '"value":false' in expected, err
        eout, eerr = echo.communicate(timeout=HANG_GUARD)
        assert [json.loads(l) for l in eout.splitlines()] == [{"stamp": {"sec": t // 10**9}} for t, _ in reports]
    finally:
        for p in (mon, echo):
            if p.poll() is None:
                p.kill()
    bad = subprocess.run([rvc, "echo", topic, "--field", "stamp.seconds", *common], capture_output=True, text=True)
    assert bad.returncode == 2 and "no field 'seconds' in builtin_interfaces/msg/Time; its fields: sec, nanosec" \
        in bad.stderr, bad.stderr


DDSPERF_IDL = """// ddsperf's KeyedSeq topic type (CycloneDDS's ddsperf_types.idl), a plain DDS type with a key
struct KeyedSeq { unsigned long seq; unsigned long keyval; sequence<octet> baggage; };
#pragma keylist KeyedSeq keyval
"""


def test_ddsperf_samples_of_an_idl_type_are_read(rvc, tmp_path):
    """ddsperf (CycloneDDS's own tool, Debian cyclonedds-tools) publishes its keyed KeyedSeq type on
    DDSPerfRDataKS; rvc reads it from the IDL above (DDS type name "KeyedSeq", key keyval, the topic
    name as is): every sample echoed in order, the sequence numbers ddsperf wrote consecutive, the
    baggage of the size asked for; a monitor's property over the fields holds."""
    if "dds" not in transports_built(rvc):
        pytest.fail("rvc built without DDS")
    import shutil
    ddsperf = shutil.which("ddsperf")
    assert ddsperf, "ddsperf missing (Debian cyclonedds-tools; scripts/install-deps.sh installs it)"
    idl = tmp_path / "ddsperf_types.idl"
    idl.write_text(DDSPERF_IDL)
    cfg = tmp_path / "lo.xml"
    subprocess.run([rvc, "dds-config", "-o", str(cfg)], check=True)
    common = ["--no-ros2-names", "--type", "KeyedSeq", "--msg-path", str(idl), "--domain", "17"]
    echo = subprocess.Popen([rvc, "echo", "dds:DDSPerfRDataKS", *common, "-n", "400", "--idle-timeout", "20"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    mon = subprocess.Popen([rvc, "monitor", "--input", "dds:DDSPerfRDataKS", *common, "--idle-timeout", "3",
                            "--spec", "historically({keyval == 0} && {baggage[51] >= 0})", "--output", "-"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(1.0)
    env = dict(os.environ, CYCLONEDDS_URI=f"file://{cfg}")  # ddsperf pinned to lo like rvc
    pub = subprocess.run([ddsperf, "-i", "17", "-D", "3", "pub", "500Hz", "size", "64"], env=env,
                         capture_output=True, text=True, timeout=30)
    assert pub.returncode == 0, pub.stderr
    out, err = echo.communicate(timeout=HANG_GUARD)
    assert echo.returncode == 0, err
    rows = [json.loads(line) for line in out.splitlines()]
    assert len(rows) == 400
    seqs = [r["seq"] for r in rows]
    assert seqs == list(range(seqs[0], seqs[0] + 400)), seqs[:10]
    assert all(r["keyval"] == 0 and len(r["baggage"]) == 52 for r in rows)  # 64 B = 12 B fixed part + 52
    mout, merr = mon.communicate(timeout=HANG_GUARD)
    assert mon.returncode == 0, merr
    assert json.loads(mout.splitlines()[0])["value"] is True


def test_bridge_takes_one_type_for_all_routes_or_one_per_route(rvc, tmp_path):
    """Several --type on `rvc bridge` give each route its type in order (the Autoware setup 2 bridges
    nine topics of nine types); a count that fits neither is refused before anything is opened, and an
    unknown type of any route is named."""
    routes = ["dds:/a", f"file:{tmp_path}/a.cdr", "dds:/b", f"file:{tmp_path}/b.cdr"]  # no Zenoh needed
    r = subprocess.run([rvc, "bridge", *routes, "--type", GEAR, "--type", GEAR, "--type", GEAR],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and "3 --type for 2 routes" in r.stderr, r.stderr
    r = subprocess.run([rvc, "bridge", *routes, "--type", "nope_msgs/msg/Missing", "--type", GEAR],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and "unknown message type nope_msgs/msg/Missing" in r.stderr, r.stderr
