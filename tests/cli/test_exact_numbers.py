"""Numbers compare exactly (docs/semantics.md, "Numbers"): random int64, uint64, float64 and float32
values near 2^53, 2^63 and 2^64 - 1, negative, -0.0, huge exponents, NaN and the infinities, against
random literals of the same kinds, in JSON traces (layouts on and off) and in typed CDR samples made by
rosbags (an MCAP bag), each verdict checked against Python's own comparison (exact between int and
float). The JSON traces are written by Python's json module, which writes NaN and the infinities as
NaN, Infinity and -Infinity: rvc reads them as those numbers, as its typed path does.

Non-finite floats round-trip (issue 25): `rvc msg decode` writes them so that json.loads reads them
back and `rvc check` on that output gives the typed input's verdicts.
"""
import json
import math
import operator
import random
import subprocess

import numpy as np
import pytest

from conftest import transports_built

TYPE = "exact_msgs/msg/Nums"
DEFINITION = "int64 i\nuint64 u\nfloat64 f\nfloat32 g\n"
OPS = {"==": operator.eq, "!=": operator.ne, "<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge}

I53, I63, I64 = 2**53, 2**63, 2**64
INT64 = [I53 - 1, I53, I53 + 1, I53 + 2, -I53 - 1, -I53, I63 - 1, I63 - 2, -I63, -I63 + 1, 0, -1,
         1_700_000_000_000_000_000, 1_700_000_000_000_000_001, 1_699_999_999_999_999_999]
UINT64 = [I64 - 1, I64 - 2, I64 - 2048, I63, I63 + 1, I63 - 1, I53, I53 + 1, 0, 1, 1_700_000_000_000_000_001]
FLOATS = [0.0, -0.0, 2.0**53, 2.0**53 + 2, 2.0**63, 2.0**64, -2.0**63, 1e300, -1e300, 5e-324, 0.5, -1.5,
          1.7e18, 18446744073709549568.0, 9223372036854774784.0, float("nan"), float("inf"), float("-inf")]


def run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, timeout=120, **kw)


def rand_int(rng, pool, lo, hi):
    return rng.choice(pool) if rng.random() < 0.8 else rng.randint(lo, hi)


def rand_messages(rng, n):
    rows = []
    for _ in range(n):
        g = float(np.float32(rng.choice(FLOATS + [rng.uniform(-1e6, 1e6)])))  # float32 values, as doubles
        f = rng.choice(FLOATS) if rng.random() < 0.8 else rng.uniform(-1e19, 1e19)
        rows.append({"i": rand_int(rng, INT64, -I63, I63 - 1), "u": rand_int(rng, UINT64, 0, I64 - 1), "f": f, "g": g})
    return rows


def rand_specs(rng, n):
    """(spec text, field, op, literal): integer literals exact, floats by repr (which reads back exactly)."""
    literals = INT64 + UINT64 + [x for x in FLOATS if math.isfinite(x)]
    out = []
    for _ in range(n):
        field, op, lit = rng.choice("iufg"), rng.choice(list(OPS)), rng.choice(literals)
        text = str(lit) if isinstance(lit, int) else repr(lit)
        out.append((f"{{{field} {op} {text}}}", field, op, lit))
    return out


def verdicts(stdout):
    """(property, step) -> value, from `rvc check --all`."""
    out = {}
    for line in stdout.splitlines():
        v = json.loads(line)
        out[(v["property"], int(v["time"]))] = v["value"]
    return out


def expected(rows, specs):
    return {(f"p{k + 1}", step): OPS[op](row[field], lit)  # Python: exact for int against float, NaN false but !=
            for k, (_, field, op, lit) in enumerate(specs) for step, row in enumerate(rows)}


def check_args(specs):
    args = ["--all"]
    for s in specs:
        args += ["--spec", s[0]]
    return args


def first_difference(got, want, rows, specs):
    for key in sorted(want):
        if got.get(key) != want[key]:
            k, step = int(key[0][1:]) - 1, key[1]
            return f"{specs[k][0]} at step {step} on {rows[step]}: rvc {got.get(key)}, Python {want[key]}"
    return None


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_json_numbers_compare_as_python_compares_them(rvc, tmp_path, seed):
    rng = random.Random(seed)
    rows, specs = rand_messages(rng, 150), rand_specs(rng, 40)
    trace = tmp_path / "nums.jsonl"
    trace.write_text("".join(json.dumps(r) + "\n" for r in rows))  # NaN, Infinity, -Infinity as Python writes them
    want = expected(rows, specs)
    for layouts in ([], ["--no-layouts"]):
        r = run([rvc, "check", *check_args(specs), *layouts, str(trace)])
        assert r.returncode in (0, 1) and r.stderr == "", r.stderr
        got = verdicts(r.stdout)
        assert len(got) == len(want)
        assert first_difference(got, want, rows, specs) is None, first_difference(got, want, rows, specs)


def rosbags_store():
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg
    ts = get_typestore(Stores.EMPTY)
    ts.register(get_types_from_msg(DEFINITION, TYPE))
    return ts


def sample(ts, row):
    Nums = ts.types[TYPE]
    m = Nums(i=np.int64(row["i"]), u=np.uint64(row["u"]), f=np.float64(row["f"]), g=np.float32(row["g"]))
    return bytes(ts.serialize_cdr(m, TYPE))


@pytest.mark.needs_rust
@pytest.mark.parametrize("seed", [4, 5])
def test_typed_numbers_compare_as_python_compares_them(rvc, tmp_path, seed):
    """The same in CDR samples serialized by rosbags, in a bag rvc reads with its typed decoder."""
    from mcap.writer import Writer
    if "zenoh" not in transports_built(rvc):  # the MCAP reader lives in the Rust library
        pytest.fail("this rvc was built without its Rust library (RVC_WITH_ZENOH=OFF): no MCAP")
    ts = rosbags_store()
    rng = random.Random(seed)
    rows, specs = rand_messages(rng, 150), rand_specs(rng, 40)
    bag = tmp_path / "nums.mcap"
    with open(bag, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2", library="rvc tests")
        sid = w.register_schema(name=TYPE, encoding="ros2msg", data=DEFINITION.encode())
        cid = w.register_channel(topic="/nums", message_encoding="cdr", schema_id=sid)
        for k, row in enumerate(rows):
            w.add_message(channel_id=cid, log_time=k, publish_time=k, sequence=k, data=sample(ts, row))
        w.finish()
    r = run([rvc, "check", *check_args(specs), str(bag)])
    assert r.returncode in (0, 1) and r.stderr == "", r.stderr
    got, want = verdicts(r.stdout), expected(rows, specs)
    assert len(got) == len(want)
    assert first_difference(got, want, rows, specs) is None, first_difference(got, want, rows, specs)


@pytest.mark.needs_rust  # its last part reads the values from a bag
def test_non_finite_floats_round_trip_through_json(rvc, tmp_path):
    """Typed samples with NaN and infinities: `rvc msg decode` writes JSON that Python's json.loads reads
    back to the same values, `rvc msg encode` turns back into the same bytes, and `rvc check` on it gives
    the verdicts of the typed samples (IEEE 754 comparisons on both)."""
    ts = rosbags_store()
    (tmp_path / "exact_msgs" / "msg").mkdir(parents=True)
    (tmp_path / "exact_msgs" / "msg" / "Nums.msg").write_text(DEFINITION)
    rng = random.Random(6)
    rows = rand_messages(rng, 60)
    for k, x in enumerate([float("nan"), float("inf"), float("-inf")]):  # surely present, in both floats
        rows[k]["f"] = rows[k + 3]["g"] = x
    hexes = [sample(ts, row).hex() for row in rows]
    msg_path = ["--type", TYPE, "--msg-path", str(tmp_path)]
    decoded = run([rvc, "msg", "decode", *msg_path], input="".join(h + "\n" for h in hexes))
    assert decoded.returncode == 0, decoded.stderr
    lines = decoded.stdout.splitlines()
    assert len(lines) == len(rows)
    for line, row in zip(lines, rows):
        back = json.loads(line)  # Python reads NaN, Infinity, -Infinity
        for k in "iufg":
            assert back[k] == row[k] or (math.isnan(back[k]) and math.isnan(row[k])), (line, row)
    assert "NaN" in decoded.stdout and "-Infinity" in decoded.stdout and "null" not in decoded.stdout
    encoded = run([rvc, "msg", "encode", *msg_path], input=decoded.stdout)
    assert encoded.returncode == 0, encoded.stderr
    assert encoded.stdout.split() == hexes  # rosbags' NaN is the quiet NaN rvc writes back
    specs = [("{f > 0}",), ("{f != 1.5}",), ("{g <= 0}",), ("{i == 0}",), ("{g}",), ("{f < 1e308} || {g >= -1}",)]
    bag = tmp_path / "nf.mcap"
    from mcap.writer import Writer
    if "zenoh" not in transports_built(rvc):
        pytest.fail("this rvc was built without its Rust library (RVC_WITH_ZENOH=OFF): no MCAP")
    with open(bag, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2", library="rvc tests")
        sid = w.register_schema(name=TYPE, encoding="ros2msg", data=DEFINITION.encode())
        cid = w.register_channel(topic="/nums", message_encoding="cdr", schema_id=sid)
        for k, h in enumerate(hexes):
            w.add_message(channel_id=cid, log_time=k, publish_time=k, sequence=k, data=bytes.fromhex(h))
        w.finish()
    trace = tmp_path / "decoded.jsonl"
    trace.write_text(decoded.stdout)
    typed = run([rvc, "check", *check_args(specs), str(bag)])
    plain = run([rvc, "check", *check_args(specs), str(trace)])
    assert typed.stderr == plain.stderr == "", (typed.stderr, plain.stderr)
    assert typed.stdout == plain.stdout and typed.returncode == plain.returncode
    # And against Python (NaN: every comparison false but !=).
    got = verdicts(plain.stdout)
    for step, row in enumerate(rows):
        assert got[("p1", step)] == (row["f"] > 0)
        assert got[("p2", step)] == (row["f"] != 1.5)
        assert got[("p3", step)] == (row["g"] <= 0)
        assert got[("p5", step)] == (row["g"] != 0)
