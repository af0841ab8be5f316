"""Arithmetic in atoms and rise/fall (issue 29, docs/semantics.md "Arithmetic in atoms"), against
RTAMT (PyPI `rtamt`, its discrete-time online STL monitor) on random formulas and traces: the
robustness at every step is RTAMT's value, and the Boolean verdict is `robustness > 0` wherever that
value is not 0 (at 0 RTAMT has no Boolean; rvc's `a <= b` holds at a == b). The same formulas over
typed CDR samples (serialized by rosbags into an MCAP bag) give the JSON trace's verdicts. Spec errors
name their column (exit 2); cross-input expressions over two files (hand-computed).

RTAMT lacks unary minus, min/max of two values and division by a field that may be 0 (it raises);
those are checked by hand in tests/unit/expr_atoms_test.cpp."""
import json
import math
import random
import subprocess

import numpy as np
import pytest

from conftest import transports_built

rtamt = pytest.importorskip("rtamt")  # under CI=true a skip fails (tests/rvc_testlib.py)

FIELDS = "abc"
VALUES = [-2.5, -1, -0.5, 0, 0.25, 0.5, 1, 1.5, 2, 3]
CONSTS = ["0.5", "1", "2", "3", "1.5"]
COMPARISONS = ["<", "<=", ">", ">=", "=="]
FORMULAS = 30


def expression(rng, depth):
    """(rvc text, RTAMT text) of a numeric expression."""
    if depth == 0 or rng.random() < 0.3:
        leaf = rng.choice(list(FIELDS) + CONSTS)
        return leaf, leaf
    kind = rng.choice(["+", "-", "*", "/", "abs"])
    if kind == "abs":
        r, t = expression(rng, depth - 1)
        return f"abs({r})", f"abs({t})"
    (lr, lt), (rr, rt) = expression(rng, depth - 1), expression(rng, depth - 1)
    if kind == "/":  # never by a field that may be 0: RTAMT raises there
        rr = rt = rng.choice(["2", "4", "0.5"])
    return f"({lr} {kind} {rr})", f"({lt} {kind} {rt})"


def atom(rng):
    (lr, lt), (rr, rt) = expression(rng, rng.randint(0, 2)), expression(rng, rng.randint(0, 2))
    if lr in CONSTS and rr in CONSTS:
        lr, lt = "a", "a"
    op = rng.choice(COMPARISONS)
    if op == "==" and rr in FIELDS:  # a bare word after == is a string: a field is written (c)
        rr = f"({rr})"
    return f"{{{lr} {op} {rr}}}", f"({lt} {op} {rt})"


def formula(rng, depth):
    if depth == 0 or rng.random() < 0.25:
        return atom(rng)
    kind = rng.choice(["not", "and", "or", "rise", "fall", "once", "historically"])
    r, t = formula(rng, depth - 1)
    if kind == "not":
        return f"not ({r})", f"not ({t})"
    if kind in ("rise", "fall"):
        return f"{kind}({r})", f"{kind}({t})"
    if kind in ("once", "historically"):
        k = rng.randint(0, 3)
        return f"{kind}[0:{k}]({r})", f"{kind}[0:{k}]({t})"
    r2, t2 = formula(rng, depth - 1)
    return f"({r}) {kind} ({r2})", f"({t}) {kind} ({t2})"


def rtamt_values(text, rows):
    spec = rtamt.StlDiscreteTimeSpecification()
    for f in FIELDS:
        spec.declare_var(f, "float")
    spec.declare_var("out", "float")
    spec.spec = "out = " + text
    spec.parse()
    return [spec.update(i, [(f, float(row[f])) for f in FIELDS]) for i, row in enumerate(rows)]


def value(v):
    return {"inf": math.inf, "-inf": -math.inf}.get(v, v) if isinstance(v, str) else v


def run_rvc(rvc, tmp_path, formulas, source, robustness, extra=()):
    props = tmp_path / "props.json"
    props.write_text(json.dumps({"properties": [{"name": f"f{i}", "spec": f} for i, f in enumerate(formulas)]}))
    args = [rvc, "check", "--all", "--properties", str(props), *extra, str(source)]
    if robustness:
        args.insert(2, "--robustness")
    r = subprocess.run(args, capture_output=True, text=True, timeout=120)
    assert r.returncode in (0, 1) and r.stderr == "", r.stderr
    out = {f"f{i}": [] for i in range(len(formulas))}
    for line in r.stdout.splitlines():
        v = json.loads(line)
        out[v["property"]].append(value(v["value"]))
    return out


def random_case(seed, steps=40, c_integral=False):
    rng = random.Random(seed)
    pairs = [formula(rng, rng.randint(0, 3)) for _ in range(FORMULAS)]
    rows = [{f: rng.choice(VALUES) for f in FIELDS} for _ in range(steps)]
    if c_integral:
        for row in rows:
            row["c"] = int(rng.choice([-3, -1, 0, 1, 2, 5]))
    return pairs, rows


def compare(pairs, rows, robust, boolean):
    for i, (r_text, t_text) in enumerate(pairs):
        want = rtamt_values(t_text, rows)
        got_r, got_b = robust[f"f{i}"], boolean[f"f{i}"]
        assert len(got_r) == len(want) == len(got_b), r_text
        for step, (g, w, b) in enumerate(zip(got_r, want, got_b)):
            assert g == pytest.approx(w, rel=1e-12, abs=1e-12), (r_text, t_text, step, rows[: step + 1])
            if w != 0:
                assert b == (w > 0), (r_text, step, w, b)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_arithmetic_and_edges_match_rtamt(rvc, tmp_path, seed):
    pairs, rows = random_case(seed)
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(json.dumps(r) + "\n" for r in rows))
    formulas = [p[0] for p in pairs]
    compare(pairs, rows, run_rvc(rvc, tmp_path, formulas, trace, True), run_rvc(rvc, tmp_path, formulas, trace, False))


TYPE = "expr_msgs/msg/Abc"
DEFINITION = "float64 a\nfloat32 b\nint32 c\n"


@pytest.mark.needs_rust
def test_typed_samples_give_the_json_verdicts(rvc, tmp_path):
    """float64, float32 and int32 fields in CDR (rosbags) read as their JSON numbers: same values, same
    robustness, and both equal RTAMT's."""
    from mcap.writer import Writer
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg
    if "zenoh" not in transports_built(rvc):  # the MCAP reader lives in the Rust library
        pytest.fail("this rvc was built without its Rust library (RVC_WITH_ZENOH=OFF): no MCAP")
    pairs, rows = random_case(7, c_integral=True)  # b's values are exact in float32
    ts = get_typestore(Stores.EMPTY)
    ts.register(get_types_from_msg(DEFINITION, TYPE))
    Abc = ts.types[TYPE]
    bag = tmp_path / "abc.mcap"
    with open(bag, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2", library="rvc tests")
        sid = w.register_schema(name=TYPE, encoding="ros2msg", data=DEFINITION.encode())
        cid = w.register_channel(topic="/abc", message_encoding="cdr", schema_id=sid)
        for k, row in enumerate(rows):
            m = Abc(a=np.float64(row["a"]), b=np.float32(row["b"]), c=np.int32(row["c"]))
            w.add_message(channel_id=cid, log_time=k, publish_time=k, sequence=k, data=bytes(ts.serialize_cdr(m, TYPE)))
        w.finish()
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(json.dumps(r) + "\n" for r in rows))
    formulas = [p[0] for p in pairs]
    typed_r, typed_b = run_rvc(rvc, tmp_path, formulas, bag, True), run_rvc(rvc, tmp_path, formulas, bag, False)
    assert typed_r == run_rvc(rvc, tmp_path, formulas, trace, True)
    assert typed_b == run_rvc(rvc, tmp_path, formulas, trace, False)
    compare(pairs, rows, typed_r, typed_b)


def caret_column(stderr):
    caret = next(line for line in stderr.splitlines() if line.strip() == "^")
    return len(caret) - len("  ^") + 1


def test_bad_expressions_point_at_the_column(rvc):
    for args, spec, column, words in [
        ([], "{abs(a - b) < }", 15, "expected a number, a field"),
        ([], "{a * (b + 1 > 2}", 13, "expected ')'"),
        ([], "{a + b}", 7, "compare it"),
        ([], "{min(a, b, c) > 1}", 10, "min takes two arguments"),
        (["--dense"], "rise({p})", 1, "instant"),
    ]:
        r = subprocess.run([rvc, "check", *args, "--spec", spec, "-"], input="", capture_output=True, text=True,
                           timeout=60)
        assert r.returncode == 2, (spec, r.stderr)
        assert words in r.stderr and caret_column(r.stderr) == column, (spec, r.stderr)


@pytest.mark.needs_rust
def test_a_typed_field_that_is_no_number_is_refused_at_its_column(rvc, tmp_path):
    from mcap.writer import Writer
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg
    name, definition = "expr_msgs/msg/Named", "string name\nfloat64 x\n"
    ts = get_typestore(Stores.EMPTY)
    ts.register(get_types_from_msg(definition, name))
    bag = tmp_path / "named.mcap"
    with open(bag, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2", library="rvc tests")
        sid = w.register_schema(name=name, encoding="ros2msg", data=definition.encode())
        cid = w.register_channel(topic="/named", message_encoding="cdr", schema_id=sid)
        m = ts.types[name](name="n", x=np.float64(1))
        w.add_message(channel_id=cid, log_time=0, publish_time=0, sequence=0, data=bytes(ts.serialize_cdr(m, name)))
        w.finish()
    r = subprocess.run([rvc, "check", "--spec", "{x + name > 1}", str(bag)], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 2, r.stderr
    assert "expression computes with numbers" in r.stderr and caret_column(r.stderr) == 6, r.stderr


def test_two_files_compared_field_against_field(rvc, tmp_path):
    """--input steer=file:... --input cmd=file:...: merge by stamp; each side holds its last value;
    false until both have one (hand-computed)."""
    steer, cmd = tmp_path / "steer.jsonl", tmp_path / "cmd.jsonl"
    steer.write_text('{"time": 1, "angle": 0.45}\n{"time": 3, "angle": 0.85}\n')
    cmd.write_text('{"time": 0, "angle": 0.5}\n{"time": 2, "angle": 0.9}\n')
    r = subprocess.run([rvc, "monitor", "--all", "--spec", "{abs(steer.angle - cmd.angle) < 0.1}",
                        "--input", f"steer=file:{steer}", "--input", f"cmd=file:{cmd}"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 1, r.stderr
    assert [json.loads(line)["value"] for line in r.stdout.splitlines()] == [False, True, False, True], r.stdout
