"""ROS 2 CDR <-> JSON (`rvc msg decode/encode`, src/io/cdr_codec.cpp) against rosbags, a CDR
implementation no one here wrote: byte-exact round trips for every bundled type and for random
generated types (random nesting, sequences, bounded and fixed arrays, strings, every primitive),
in both endiannesses; the bundled definitions compared field by field with rosbags' own ROS 2
Jazzy definitions (common_interfaces: all of them bundled); the types of every bundled service
(.srv: Name_Request, Name_Response, Name_Event); truncated and corrupted samples rejected with a byte offset, never a crash.
"""
import json
import math
import pathlib
import random
import struct
import subprocess

import numpy as np
import pytest

rosbags_typesys = pytest.importorskip("rosbags.typesys")
Stores, get_typestore, get_types_from_msg = (rosbags_typesys.Stores, rosbags_typesys.get_typestore,
                                              rosbags_typesys.get_types_from_msg)

# byte and char: 0..127, where rosbags (int8) and rosidl (octet, uint8) agree on the value
INTS = {"int8": (-128, 127), "uint8": (0, 255), "byte": (0, 127), "char": (0, 127), "int16": (-2**15, 2**15 - 1),
        "uint16": (0, 2**16 - 1), "int32": (-2**31, 2**31 - 1), "uint32": (0, 2**32 - 1),
        "int64": (-2**63, 2**63 - 1), "uint64": (0, 2**64 - 1)}
NP = {"int8": np.int8, "uint8": np.uint8, "byte": np.uint8, "char": np.uint8, "int16": np.int16, "uint16": np.uint16,
      "int32": np.int32, "uint32": np.uint32, "int64": np.int64, "uint64": np.uint64, "float32": np.float32,
      "float64": np.float64, "bool": np.bool_}
EMPTY = "structure_needs_at_least_one_member"
DEFINITIONS = pathlib.Path(__file__).resolve().parent.parent.parent / "src" / "msg" / "definitions"
# The ROS 2 packages bundled whole (docs/ros2-types.md): every message rosbags' Jazzy store has of them.
COMMON = ["builtin_interfaces", "std_msgs", "geometry_msgs", "sensor_msgs", "nav_msgs", "diagnostic_msgs",
          "rosgraph_msgs", "rcl_interfaces", "tf2_msgs", "trajectory_msgs", "visualization_msgs", "action_msgs",
          "unique_identifier_msgs", "shape_msgs", "service_msgs"]


def msg(rvc, *args, stdin="", check=True):
    r = subprocess.run([rvc, "msg", *args], input=stdin, capture_output=True, text=True, timeout=120)
    if check:
        assert r.returncode == 0, r.stderr
    return r


def bundled(rvc):
    return msg(rvc, "list").stdout.split()


# ------------------------------------------------------------ random values and the oracle

def rand_string(rng, bound=0):
    alphabet = "abcXYZ 019_-\"\\/\u00e9\u4e2d\U0001f600\t\n"
    n = rng.randint(0, bound if bound else 12)
    s = "".join(rng.choice(alphabet) for _ in range(n))
    while bound and len(s.encode()) > bound:
        s = s[:-1]
    return s


def rand_base(rng, base, bound):
    if base == "bool":
        return rng.random() < 0.5
    if base in INTS:
        lo, hi = INTS[base]
        return rng.choice([lo, hi, 0, rng.randint(lo, hi)])
    if base == "float32":
        return float(np.float32(rng.choice([0.0, -1.5, 0.1, 3.4e38, rng.uniform(-1e6, 1e6)])))
    if base == "float64":
        return rng.choice([0.0, -0.0, 0.1, 1e308, 5e-324, rng.uniform(-1e12, 1e12)])
    if base == "string":
        return rand_string(rng, bound)
    raise AssertionError(base)


def rand_value(ts, rng, spec, depth=0):
    """(rosbags object, expected JSON value) for one field spec of rosbags' fielddefs."""
    kind, detail = spec
    kind = int(kind)
    if kind == 1:  # base
        base, bound = detail
        v = rand_base(rng, base, bound)
        return v, v
    if kind == 2:  # nested message
        return rand_message(ts, rng, detail, depth + 1)
    (inner, size) = detail
    n = size if kind == 3 else rng.randint(0, size if size else 4)
    pairs = [rand_value(ts, rng, inner, depth) for _ in range(n)]
    objs, exp = [p[0] for p in pairs], [p[1] for p in pairs]
    if int(inner[0]) == 1 and inner[1][0] != "string":
        objs = np.array(objs, dtype=NP[inner[1][0]])
    return objs, exp


def rand_message(ts, rng, name, depth=0):
    consts, fields = ts.fielddefs[name]
    kwargs, expected = {}, {}
    for fname, spec in fields:
        if fname == EMPTY:  # the placeholder of an empty message: writers send 0
            kwargs[fname] = 0
            continue
        obj, exp = rand_value(ts, rng, spec, depth)
        kwargs[fname] = obj
        if fname != EMPTY:
            expected[fname] = exp
    return ts.types[name](**kwargs), expected


def same(a, b):
    """JSON equality, floats exact (NaN never produced)."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, bool) or isinstance(b, bool):
        return a is b
    if isinstance(a, float) or isinstance(b, float):
        return float(a) == float(b) and math.copysign(1, a) == math.copysign(1, b)
    return a == b


def round_trip(rvc, ts, name, rng, count, msg_path=(), ts_name=None):
    paths = [a for p in msg_path for a in ("--msg-path", str(p))]
    ts_name = ts_name or name
    for little in (True, False):
        objs = [rand_message(ts, rng, ts_name) for _ in range(count)]
        raws = [bytes(ts.serialize_cdr(o, ts_name, little_endian=little)) for o, _ in objs]
        out = msg(rvc, "decode", "--type", name, *paths, stdin="".join(r.hex() + "\n" for r in raws)).stdout
        got = [json.loads(line) for line in out.splitlines()]
        assert len(got) == count
        for (o, exp), g, raw in zip(objs, got, raws):
            assert same(exp, g), (name, little, raw.hex(), exp, g)
        enc_args = ["encode", "--type", name, *paths] + ([] if little else ["--big-endian"])
        hexes = msg(rvc, *enc_args, stdin=out).stdout.split()
        assert [bytes.fromhex(h) for h in hexes] == raws, name


# ------------------------------------------------------------ tests

def test_bundled_definitions_match_rosbags_jazzy(rvc):
    ts = get_typestore(Stores.ROS2_JAZZY)
    names = bundled(rvc)
    missing = [n for n in ts.fielddefs if n.split("/")[0] in COMMON and n not in names]
    assert not missing, missing
    compared = 0
    for name in names:
        if name not in ts.fielddefs:
            continue  # Autoware types and services: not in rosbags' store
        text = msg(rvc, "show", name).stdout
        mine = get_types_from_msg("\n".join(l for l in text.splitlines()
                                            if not l.startswith(("#", "\t"))), name)[name]
        theirs = ts.fielddefs[name]
        their_fields = [(f, s) for f, s in theirs[1] if f != EMPTY]
        assert [(f, repr(s)) for f, s in mine[1]] == [(f, repr(s)) for f, s in their_fields], name
        compared += 1
    assert compared >= 140, compared


def service_alias(name):
    """rosbags renames types named pkg/srv/X, so a service's types are registered as pkg/msg/X (the wire
    format does not depend on the name)."""
    return name.replace("/srv/", "/msg/")


def register_service(ts, name):
    """The three types of a bundled service, from its .srv file (request, '---', response) and rosidl's
    event layout (info, request[<=1], response[<=1])."""
    pkg, _, base = name.split("/")
    request, response = (DEFINITIONS / pkg / "srv" / (base + ".srv")).read_text().split("---\n")
    for part, text in (("Request", request), ("Response", response)):
        if f"{pkg}/msg/{base}_{part}" not in ts.fielddefs:
            ts.register(get_types_from_msg(text, f"{pkg}/msg/{base}_{part}"))
    event = f"{pkg}/msg/{base}_Event"
    if event not in ts.fielddefs:
        ts.register(get_types_from_msg(f"service_msgs/msg/ServiceEventInfo info\n{pkg}/msg/{base}_Request[<=1] request\n"
                                       f"{pkg}/msg/{base}_Response[<=1] response\n", event))


def register_bundled(rvc, ts):
    for name in bundled(rvc):
        if "/srv/" in name:
            register_service(ts, name.rsplit("_", 1)[0])
            continue
        if name in ts.fielddefs:
            continue
        text = msg(rvc, "show", name).stdout
        top = "\n".join(l for l in text.splitlines() if not l.startswith(("#", "\t")))
        ts.register(get_types_from_msg(top, name))


def test_every_bundled_type_round_trips_byte_exact(rvc):
    ts = get_typestore(Stores.ROS2_JAZZY)
    register_bundled(rvc, ts)
    rng = random.Random(11)
    names = bundled(rvc)
    services = [n for n in names if "/srv/" in n]
    assert len(services) >= 3 * 20 and "std_srvs/srv/SetBool_Event" in services, services
    for name in names:
        round_trip(rvc, ts, name, rng, 6, ts_name=service_alias(name))


def test_bundled_defaults(rvc):
    """Fields a message leaves out take the published definitions' defaults when encoded: a Pose with no
    orientation is the identity rotation (geometry_msgs/Quaternion's w defaults to 1). Oracle: rosbags
    decodes the bytes rvc writes."""
    ts = get_typestore(Stores.ROS2_JAZZY)
    for typ, given, expect in [
        ("geometry_msgs/msg/Quaternion", {}, {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}),
        ("geometry_msgs/msg/Pose", {"position": {"x": 2.0}}, {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}),
    ]:
        r = subprocess.run([rvc, "msg", "encode", "--type", typ], input=json.dumps(given) + "\n",
                           capture_output=True, text=True, timeout=30)
        assert r.returncode == 0, r.stderr
        msg = ts.deserialize_cdr(bytes.fromhex(r.stdout.split()[0]), typ)
        q = msg if typ.endswith("Quaternion") else msg.orientation
        assert {k: getattr(q, k) for k in "xyzw"} == expect, (typ, r.stdout)


PRIMS = ["bool", "byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
         "float32", "float64", "string"]


def random_types(rng, count, pkg="rvcfuzz_msgs"):
    """Random .msg definitions: Name0 uses only primitives, NameK may nest Name0..NameK-1."""
    defs = {}
    for k in range(count):
        lines = []
        if rng.random() < 0.3:
            lines.append("uint8 KIND_%d = %d  # a constant" % (k, rng.randint(0, 255)))
        for i in range(rng.randint(1 if k == 0 else 0, 7)):
            if k and rng.random() < 0.35:
                base = "Name%d" % rng.randrange(k)
            else:
                base = rng.choice(PRIMS)
                if base == "string" and rng.random() < 0.3:
                    base = "string<=%d" % rng.randint(1, 8)
            arr = rng.choice(["", "", "", "[]", "[%d]" % rng.randint(1, 4), "[<=%d]" % rng.randint(1, 4)])
            lines.append("%s%s f%d" % (base, arr, i))
        defs["%s/msg/Name%d" % (pkg, k)] = "\n".join(lines) + "\n"
    return defs


def test_random_types_round_trip_byte_exact(rvc, tmp_path):
    rng = random.Random(5)
    for trial in range(4):
        pkg = "rvcfuzz%d_msgs" % trial
        defs = random_types(rng, 8, pkg)
        ts = get_typestore(Stores.ROS2_HUMBLE)
        for name, text in defs.items():
            ts.register(get_types_from_msg(text, name))
            folder = tmp_path / pkg / "msg"
            folder.mkdir(parents=True, exist_ok=True)
            (folder / (name.split("/")[-1] + ".msg")).write_text(text)
        for name in defs:
            round_trip(rvc, ts, name, rng, 5, msg_path=[tmp_path])


def test_truncated_and_corrupted_samples_are_rejected_with_an_offset(rvc):
    ts = get_typestore(Stores.ROS2_JAZZY)
    register_bundled(rvc, ts)
    name = "tier4_external_api_msgs/msg/VehicleStatusStamped"
    obj, _ = rand_message(ts, random.Random(2), name)
    raw = bytes(ts.serialize_cdr(obj, name))
    lines = [raw[:n].hex() for n in range(1, len(raw))]  # every cut (the last field is a uint8)
    r = msg(rvc, "decode", "--type", name, stdin="\n".join(lines) + "\n" + raw.hex() + "\n", check=False)
    assert r.returncode == 3, r.stderr
    assert len(r.stdout.splitlines()) == 1  # only the whole sample
    errors = [l for l in r.stderr.splitlines() if "(message skipped)" in l]
    assert len(errors) == len(lines)
    assert "line 1: sample of 1 bytes has no 4-byte CDR header" in errors[0]
    assert all("truncated sample in field " in e for e in errors[3:]), errors
    assert "line 4: truncated sample in field stamp.sec at byte 4" in errors[3]
    # a string whose length runs past the end, a bool that is neither 0 nor 1, trailing junk
    tname = "std_msgs/msg/String"
    good = bytes(ts.serialize_cdr(ts.types[tname](data="hello"), tname))
    long_len = good[:4] + struct.pack("<I", 1000) + good[8:]
    no_nul = good[:-1] + b"x"
    junk = good + b"\0" * 8
    r = msg(rvc, "decode", "--type", tname, stdin="\n".join(x.hex() for x in (long_len, no_nul, junk, good)) + "\n",
            check=False)
    assert r.returncode == 3
    assert r.stdout == '{"data":"hello"}\n'
    err = r.stderr
    assert "line 1: string field 'data' claims 1000 bytes, the sample has 6 left at byte 4" in err, err
    assert "line 2: string without its terminating NUL in field data" in err, err
    assert "line 3: 8 bytes left over after the last field" in err, err
    bname = "std_msgs/msg/Bool"
    r = msg(rvc, "decode", "--type", bname, stdin=(b"\x00\x01\x00\x00\x07").hex() + "\n", check=False)
    assert "bool holding 7 in field data at byte 4" in r.stderr
    r = msg(rvc, "decode", "--type", bname, stdin="00070000 01\n", check=False)
    assert "column 9: not a hex byte" in r.stderr or "unsupported CDR representation 0x0007" in r.stderr


def test_encode_names_the_field_of_a_bad_value(rvc):
    cases = {
        '{"status":{"twist":{"linear":{"x":"fast"}}}}': "field status.twist.linear.x: expected a number",
        '{"status":{"gear_shift":{"data":300}}}': "field status.gear_shift.data: 300 is out of range",
        '{"stamp":{"sec":1},"speed":3}': "unknown field 'speed'",
        '{"stamp": ': "not JSON",
    }
    r = msg(rvc, "encode", "--type", "tier4_external_api_msgs/msg/VehicleStatusStamped",
            stdin="\n".join(cases) + "\n{}\n", check=False)
    assert r.returncode == 3
    assert len(r.stdout.split()) == 1  # {} encodes: every field takes its default
    for i, (_, want) in enumerate(cases.items(), start=1):
        assert ("line %d: " % i) in r.stderr and want in r.stderr, (want, r.stderr)


def test_unknown_type_and_bad_definitions_are_named(rvc, tmp_path):
    r = msg(rvc, "show", "nope_msgs/msg/Missing", check=False)
    assert r.returncode == 2 and "unknown message type nope_msgs/msg/Missing" in r.stderr
    (tmp_path / "bad_msgs" / "msg").mkdir(parents=True)
    (tmp_path / "bad_msgs" / "msg" / "Bad.msg").write_text("int32 ok\nfloat64[<=x] broken\n")
    r = msg(rvc, "show", "bad_msgs/msg/Bad", "--msg-path", str(tmp_path), check=False)
    assert r.returncode == 2
    assert "Bad.msg:2:11: expected a positive array bound, got 'x'" in r.stderr, r.stderr
    (tmp_path / "bad_msgs" / "msg" / "Loop.msg").write_text("Loop next\n")
    r = msg(rvc, "show", "bad_msgs/msg/Loop", "--msg-path", str(tmp_path), check=False)
    assert r.returncode == 2 and "contains itself" in r.stderr, r.stderr


def test_constants_are_listed(rvc):
    out = msg(rvc, "show", "autoware_auto_vehicle_msgs/msg/GearReport").stdout
    assert "uint8 REVERSE=20" in out and "uint8 report" in out and "\tint32 sec" in out


def test_bundled_definitions_match_the_schemas_of_a_ros2_recorded_bag(rvc, tmp_path):
    """ROS 2's own test bag (tests/data/ros2-bags/talker_mcap, recorded by rosbag2) carries the full
    definitions of what it recorded: rcl_interfaces/Log, ParameterEvent and the types they use,
    std_msgs/String. Each read from the bag (--msg-path) must give the bundled fields; constants may
    differ in their declared type only (Log's are `byte` in that recording, `uint8` in Jazzy)."""
    import re
    reader = pytest.importorskip("mcap.reader")
    bag = pathlib.Path(__file__).resolve().parent.parent / "data" / "ros2-bags" / "talker_mcap" / "talker.mcap"
    names = set()
    with open(bag, "rb") as f:
        for schema in reader.make_reader(f).get_summary().schemas.values():
            sections = re.split(r"\n=+\n", schema.data.decode())
            name = schema.name
            for i, text in enumerate(sections):
                if i:
                    head, _, text = text.partition("\n")
                    name = head.split("MSG:")[1].strip()
                pkg, short = name.split("/")[0], name.split("/")[-1]
                (tmp_path / pkg / "msg").mkdir(parents=True, exist_ok=True)
                (tmp_path / pkg / "msg" / (short + ".msg")).write_text(text)
                names.add(f"{pkg}/msg/{short}")
    assert len(names) >= 6, names

    def shown(*args):
        lines = msg(rvc, "show", *args).stdout.splitlines()[1:]
        return [re.sub(r"^(\t*)(byte|uint8) ([A-Z_]+=)", r"\1CONST \3", l) for l in lines]
    for name in sorted(names):
        assert shown(name) == shown(name, "--msg-path", str(tmp_path)), name
