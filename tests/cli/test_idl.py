"""IDL definitions (`--msg-path X.idl`, src/msg/idl_parser.cpp) against rosbags' own IDL reader and CDR,
an implementation no one here wrote: random IDL types (random nesting, typedefs, sequences bounded and
not, fixed arrays, bounded strings, every primitive, constants), ROS 2 style (module pkg::msg) and plain
DDS style (any module), byte-exact round trips in both endiannesses; a ROS 2 bag whose schemas are IDL
(`ros2idl`, as rosbag2 records types defined only in .idl) checks like its JSON.
The descriptors built from IDL are compared with idlc's in tests/integration/dds; real samples of an
IDL type published by ddsperf are read in tests/integration/participants/test_typed_dds.py.
"""
import json
import random

import pytest

from test_msg_cdr import msg, rand_message, same

rosbags_typesys = pytest.importorskip("rosbags.typesys")
get_typestore, Stores, get_types_from_idl = (rosbags_typesys.get_typestore, rosbags_typesys.Stores,
                                             rosbags_typesys.get_types_from_idl)

# IDL spelling -> the .msg name rosbags reports; octet 0..127 (see test_msg_cdr.INTS)
IDL_PRIMS = ["boolean", "octet", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
             "float", "double", "string", "short", "unsigned short", "long", "unsigned long", "long long",
             "unsigned long long"]


def random_idl(rng, count, module, ros):
    """One IDL file: Name0 uses only primitives, NameK may nest Name0..NameK-1 (also through typedefs)."""
    body = []
    for k in range(count):
        members, typedefs = [], []
        for i in range(rng.randint(1, 7)):
            if k and rng.random() < 0.35:
                base = "Name%d" % rng.randrange(k)
            else:
                base = rng.choice(IDL_PRIMS)
                if base == "string" and rng.random() < 0.3:
                    base = "string<%d>" % rng.randint(1, 8)
            shape = rng.choice(["", "", "", "seq", "bseq", "arr", "tarr"])
            if shape == "seq":
                members.append("sequence<%s> f%d;" % (base, i))
            elif shape == "bseq":
                members.append("sequence<%s, %d> f%d;" % (base, rng.randint(1, 4), i))
            elif shape == "arr":
                members.append("%s f%d[%d];" % (base, i, rng.randint(1, 4)))
            elif shape == "tarr":  # an array typedef, as rosidl writes for T[N] in sequences
                typedefs.append("typedef %s Name%d__f%d[%d];" % (base, k, i, rng.randint(1, 4)))
                members.append("Name%d__f%d f%d;" % (k, i, i))
            else:
                members.append("%s f%d;" % (base, i))
        if rng.random() < 0.4:
            body.append("module Name%d_Constants { const uint8 KIND = %d; const double SCALE = %r; };"
                        % (k, rng.randint(0, 255), rng.uniform(-5, 5)))
        body += typedefs
        body.append("struct Name%d {\n  %s\n};" % (k, "\n  ".join(members)))
    inner = "\n".join(body)
    if ros:
        return "module %s { module msg {\n%s\n}; };\n" % (module, inner)
    return "module %s {\n%s\n};\n" % (module, inner)


def round_trip_idl(rvc, ts, theirs, mine, rng, count, idl_file):
    for little in (True, False):
        objs = [rand_message(ts, rng, theirs) for _ in range(count)]
        raws = [bytes(ts.serialize_cdr(o, theirs, little_endian=little)) for o, _ in objs]
        out = msg(rvc, "decode", "--type", mine, "--msg-path", str(idl_file),
                  stdin="".join(r.hex() + "\n" for r in raws)).stdout
        got = [json.loads(line) for line in out.splitlines()]
        assert len(got) == count
        for (_, exp), g, raw in zip(objs, got, raws):
            assert same(exp, g), (mine, little, raw.hex(), exp, g)
        enc = ["encode", "--type", mine, "--msg-path", str(idl_file)] + ([] if little else ["--big-endian"])
        hexes = msg(rvc, *enc, stdin=out).stdout.split()
        assert [bytes.fromhex(h) for h in hexes] == raws, mine


@pytest.mark.parametrize("ros", [True, False], ids=["rosidl", "plain"])
def test_random_idl_types_round_trip_byte_exact(rvc, tmp_path, ros):
    rng = random.Random(17 if ros else 23)
    for trial in range(4):
        module = "idlfuzz%d%s" % (trial, "_msgs" if ros else "")
        text = random_idl(rng, 8, module, ros)
        path = tmp_path / ("%s.idl" % module)
        path.write_text(text)
        ts = get_typestore(Stores.EMPTY)
        ts.register(get_types_from_idl(text))
        for k in range(8):
            theirs = "%s/msg/Name%d" % (module, k) if ros else "%s/Name%d" % (module, k)
            mine = theirs if ros else "%s::Name%d" % (module, k)
            round_trip_idl(rvc, ts, theirs, mine, rng, 4, path)
        if ros:  # the constants module gives the struct its constants, as for a .msg
            shown = msg(rvc, "show", "%s/msg/Name7" % module, "--msg-path", str(path)).stdout
            for name, (consts, _) in ts.fielddefs.items():
                if name.endswith("/Name7"):
                    for cname, _, value in consts:
                        assert "%s=" % cname in shown.replace(" ", ""), (cname, shown)


GEAR_IDL = """#include "builtin_interfaces/msg/Time.idl"
module idlbag_msgs { module msg {
  module Gear_Constants { const uint8 DRIVE = 2; const uint8 REVERSE = 20; };
  struct Gear { builtin_interfaces::msg::Time stamp; uint8 report; float speed; };
}; };
"""
TIME_IDL = """module builtin_interfaces { module msg {
  struct Time { int32 sec; uint32 nanosec; };
}; };
"""


def test_bag_with_idl_schemas_checks_like_its_json(rvc, tmp_path):
    """A bag whose schema is `ros2idl` (written with the mcap package, samples by rosbags from the same
    IDL): the type comes from the bag; verdicts equal `rvc check` on the values as JSON (with numbers
    for the constants, which JSON has no type to take from)."""
    from mcap.writer import Writer
    ts = get_typestore(Stores.EMPTY)
    ts.register(get_types_from_idl(TIME_IDL))
    ts.register(get_types_from_idl(GEAR_IDL.split("\n", 1)[1]))  # rosbags' reader takes no #include
    Gear, Time = ts.types["idlbag_msgs/msg/Gear"], ts.types["builtin_interfaces/msg/Time"]
    rng = random.Random(3)
    rows, bag = [], tmp_path / "gear.mcap"
    schema = GEAR_IDL + "=" * 80 + "\nIDL: builtin_interfaces/msg/Time\n" + TIME_IDL
    with open(bag, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2")
        sid = w.register_schema(name="idlbag_msgs/msg/Gear", encoding="ros2idl", data=schema.encode())
        cid = w.register_channel(topic="/gear", message_encoding="cdr", schema_id=sid)
        t = 1_700_000_000 * 10**9
        for _ in range(200):
            t += rng.choice([20, 40]) * 10**6
            report, speed = rng.choice([2, 2, 20]), float(rng.choice([0.0, 0.0, 1.5, -0.5]))
            m = Gear(stamp=Time(sec=t // 10**9, nanosec=t % 10**9), report=report, speed=speed)
            w.add_message(channel_id=cid, log_time=t, publish_time=t, data=bytes(ts.serialize_cdr(m, "idlbag_msgs/msg/Gear")))
            rows.append({"stamp": {"sec": t // 10**9, "nanosec": t % 10**9}, "report": report, "speed": speed})
        w.finish()
    trace = tmp_path / "gear.jsonl"
    trace.write_text("".join(json.dumps(r) + "\n" for r in rows))
    typed = subprocess_run([rvc, "check", str(bag), "--all", "--spec", "{report == REVERSE} -> {speed <= 0}"])
    plain = subprocess_run([rvc, "check", str(trace), "--all", "--spec", "{report == 20} -> {speed <= 0}"])
    assert typed.returncode == plain.returncode == 1, (typed.stderr, plain.stderr)
    assert typed.stdout == plain.stdout and len(typed.stdout.splitlines()) == 200


def subprocess_run(args):
    import subprocess
    return subprocess.run(args, capture_output=True, text=True, timeout=120)


def test_bad_idl_is_named_at_its_line_and_column(rvc, tmp_path):
    bad = tmp_path / "bad.idl"
    bad.write_text("module m {\n  struct S { long a[2][2]; };\n};\n")
    r = msg(rvc, "show", "m::S", "--msg-path", str(bad), check=False)
    assert r.returncode != 0
    assert "bad.idl:2:23: 'a': multi-dimensional arrays are not supported" in r.stderr, r.stderr
