"""`rvc check BAG --msg-path DIR` (issue 25): definitions a bag's schemas leave out.

Bags written with Foxglove's `mcap` package (PyPI) whose schema records name a type but define it only
partly or not at all: a schema that holds only the top-level definition (the nested type is only in
DIR), and a schema record with a name and no text. Samples are serialized by rosbags from the same
definitions; the verdicts are written down by hand.
"""
import json
import os
import subprocess

import pytest

from conftest import transports_built

pytestmark = pytest.mark.needs_rust  # every test here reads a bag

PAIR = "int32 a\nfloat64 b\n"
OUTER = "rvc_test_pkg/Pair inner\nbool ok\n"
A_VALUES = [1, 5, 9, 2]
# {inner.a < 6} (or {a < 6}) over a = 1, 5, 9, 2: true at 0, false at 2, true again at 3.
WANT = [{"time": 0, "property": "p1", "value": True}, {"time": 2, "property": "p1", "value": False},
        {"time": 3, "property": "p1", "value": True}]


def run(args):
    return subprocess.run(args, capture_output=True, text=True, timeout=60)


@pytest.fixture
def defs(rvc, tmp_path):
    if "zenoh" not in transports_built(rvc):  # the MCAP reader lives in the Rust library
        pytest.fail("this rvc was built without its Rust library (RVC_WITH_ZENOH=OFF): no MCAP")
    d = tmp_path / "defs" / "rvc_test_pkg" / "msg"
    d.mkdir(parents=True)
    (d / "Pair.msg").write_text(PAIR)
    (d / "Outer.msg").write_text(OUTER)
    return str(tmp_path / "defs")


def typestore():
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg
    ts = get_typestore(Stores.EMPTY)
    ts.register(get_types_from_msg(PAIR, "rvc_test_pkg/msg/Pair"))
    ts.register(get_types_from_msg(OUTER, "rvc_test_pkg/msg/Outer"))
    return ts


def write_bag(path, type_name, schema_text, samples, schema=True):
    from mcap.writer import Writer
    with open(path, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2", library="rvc tests")
        sid = w.register_schema(name=type_name, encoding="ros2msg", data=schema_text.encode()) if schema else 0
        cid = w.register_channel(topic="/t", message_encoding="cdr", schema_id=sid)
        for i, data in enumerate(samples):
            w.add_message(channel_id=cid, log_time=i + 1, publish_time=i + 1, sequence=i, data=bytes(data))
        w.finish()
    return str(path)


def outer_samples():
    ts = typestore()
    Pair, Outer = ts.types["rvc_test_pkg/msg/Pair"], ts.types["rvc_test_pkg/msg/Outer"]
    return [ts.serialize_cdr(Outer(inner=Pair(a=a, b=0.5), ok=True), "rvc_test_pkg/msg/Outer") for a in A_VALUES]


def verdicts(out):
    return [json.loads(line) for line in out.stdout.splitlines()]


def test_nested_type_only_in_msg_path(rvc, tmp_path, defs):
    # The schema defines Outer but not the Pair it uses.
    bag = write_bag(tmp_path / "outer.mcap", "rvc_test_pkg/msg/Outer", OUTER, outer_samples())
    without = run([rvc, "check", "--spec", "{inner.a < 6}", bag])
    assert without.returncode == 2 and "rvc_test_pkg" in without.stderr and "Pair" in without.stderr, without.stderr
    # --topic and --msg-path before the bag: each takes one value, the bag stays the trace.
    out = run([rvc, "check", "--topic", "/t", "--msg-path", defs, bag, "--spec", "{inner.a < 6}"])
    assert out.returncode == 1, out.stderr
    assert verdicts(out) == WANT


def test_schema_that_only_names_its_type(rvc, tmp_path, defs):
    ts = typestore()
    Pair = ts.types["rvc_test_pkg/msg/Pair"]
    samples = [ts.serialize_cdr(Pair(a=a, b=0.5), "rvc_test_pkg/msg/Pair") for a in A_VALUES]
    bag = write_bag(tmp_path / "pair.mcap", "rvc_test_pkg/msg/Pair", "", samples)
    out = run([rvc, "check", bag, "--msg-path", defs, "--spec", "{a < 6}"])
    assert out.returncode == 1, out.stderr
    assert verdicts(out) == WANT
    # Without the folder the type is unknown: said, not read as a type without fields.
    without = run([rvc, "check", bag, "--spec", "{a < 6}"])
    assert without.returncode == 2 and "rvc_test_pkg/msg/Pair" in without.stderr, without.stderr
    # rvc monitor --input mcap:BAG takes the same --msg-path.
    mon = run([rvc, "monitor", "--input", "mcap:" + bag, "--msg-path", defs, "--spec", "{a < 6}"])
    assert mon.returncode == 1, mon.stderr
    assert verdicts(mon) == WANT


def test_channel_without_schema_is_named(rvc, tmp_path, defs):
    bag = write_bag(tmp_path / "bare.mcap", "", "", outer_samples(), schema=False)
    out = run([rvc, "check", bag, "--msg-path", defs, "--spec", "{inner.a < 6}"])
    assert out.returncode == 2, out.stderr
    assert "topic '/t'" in out.stderr and "has no schema" in out.stderr, out.stderr
    assert len(out.stderr.strip().splitlines()) == 1, out.stderr


def test_msg_path_on_a_json_trace_is_refused(rvc, tmp_path, defs):
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"a": 1}\n')
    out = run([rvc, "check", str(trace), "--msg-path", defs, "--spec", "{a < 6}"])
    assert out.returncode == 2 and "--msg-path" in out.stderr and "t.jsonl" in out.stderr, out.stderr
