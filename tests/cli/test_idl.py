"""IDL definitions (`--msg-path X.idl`, src/msg/idl_parser.cpp) against rosbags' own IDL reader and CDR,
an implementation no one here wrote: random IDL types (random nesting, typedefs, sequences bounded and
not, fixed arrays, bounded strings, every primitive, constants), ROS 2 style (module pkg::msg) and plain
DDS style (any module), byte-exact round trips in both endiannesses. (A ROS 2 bag whose schemas are
IDL is in test_mcap.py, with the other bags: sanitizer builds have no MCAP reader.)
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


def test_bad_idl_is_named_at_its_line_and_column(rvc, tmp_path):
    bad = tmp_path / "bad.idl"
    bad.write_text("module m {\n  struct S { long a[2][2]; };\n};\n")
    r = msg(rvc, "show", "m::S", "--msg-path", str(bad), check=False)
    assert r.returncode != 0
    assert "bad.idl:2:23: 'a': multi-dimensional arrays are not supported" in r.stderr, r.stderr
