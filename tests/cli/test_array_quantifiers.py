"""Array quantifiers in atoms (issue 29, docs/semantics.md "Array quantifiers"): all(..), any(..) and
count(..) over the elements of a JSON array, Boolean and robustness, discrete and dense, on
hand-computed traces; elements without a usable value (lenient warning, strict rejection); spec errors at
their column; typed (CDR) input: a LaserScan bag and a custom array of structs (--msg-path), samples
serialized by rosbags."""
import json
import math
import subprocess

import numpy as np
import pytest

from conftest import transports_built

from rvc_testlib import write_mcap_bag as write_bag  # noqa: E402

ROWS = [
    {"time": 0.0, "ranges": [0.5, 0.3], "objects": [{"distance": 1}, {"distance": 3}]},
    {"time": 0.5, "ranges": [0.1, 0.3], "objects": []},
    {"time": 1.5, "ranges": [], "objects": [{"distance": 1}, {"distance": 1.5}, {"distance": 0.5}]},
    {"time": 2.0, "ranges": [0.25, 0.9, 0.4], "objects": [{"distance": 2.5}, {"distance": 1.75}]},
]
SPECS = {
    "all": "{all(ranges[*] > 0.2)}",
    "any": "{any(objects[*].distance < 2.0)}",
    "count": "{count(objects[*].distance < 2.0) >= 2}",
    "hist": "historically{all(ranges[*] >= 0.1)}",
}
# By hand: all = min(r - 0.2) (empty: +inf), any = max(2 - d) (empty: -inf), count = #(d < 2) - 2.
WANT_MARGINS = {
    "all": [0.1, -0.1, math.inf, 0.05],
    "any": [1, -math.inf, 1.5, 0.25],
    "count": [-1, -2, 1, -1],
    "hist": [0.2, 0.0, 0.0, 0.0],
}
WANT_BOOL = {
    "all": [True, False, True, True],
    "any": [True, False, True, True],
    "count": [False, False, True, False],
    "hist": [True, True, True, True],
}


def value(v):
    return {"inf": math.inf, "-inf": -math.inf}.get(v, v) if isinstance(v, str) else v


def run(rvc, tmp_path, rows, *extra, specs=SPECS):
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(json.dumps(r) + "\n" for r in rows))
    props = tmp_path / "props.json"
    props.write_text(json.dumps({"properties": [{"name": n, "spec": s} for n, s in specs.items()]}))
    r = subprocess.run([rvc, "check", "--all", *extra, "--properties", str(props), str(trace)],
                       capture_output=True, text=True, timeout=60)
    out = {n: [] for n in specs}
    for line in r.stdout.splitlines():
        v = json.loads(line)
        out[v["property"]].append(value(v["value"]))
    return r, out


def test_discrete_boolean_and_robustness_by_hand(rvc, tmp_path):
    r, got = run(rvc, tmp_path, ROWS)
    assert r.returncode in (0, 1) and r.stderr == "", r.stderr
    assert got == WANT_BOOL
    r, got = run(rvc, tmp_path, ROWS, "--robustness")
    assert r.returncode in (0, 1) and r.stderr == "", r.stderr
    for name, want in WANT_MARGINS.items():
        assert got[name] == pytest.approx(want, abs=1e-12), name


def test_dense_time_by_hand(rvc, tmp_path):
    # Instants 0, 0.5, 1.5, 2: count(..) == 0 holds on [0.5, 1.5) only, so once[0:0.4] of it holds at
    # 0.5 and at 1.5 (the window [1.1, 1.5] meets it), and stops at 1.9 (--all also prints that instant).
    specs = {"recent_empty": "once[0:0.4]{count(objects[*].distance < 2) == 0}"}
    r, got = run(rvc, tmp_path, ROWS, "--dense", specs=specs)
    assert r.returncode in (0, 1) and r.stderr == "", r.stderr
    assert got["recent_empty"] == [False, True, True, False, False]
    assert [json.loads(line)["time"] for line in r.stdout.splitlines()] == [0, 0.5, 1.5, 1.9, 2]


def test_elements_without_a_value(rvc, tmp_path):
    rows = [{"objects": [{"distance": 1}]}, {"objects": [{"distance": 3}, {"x": 1}]},
            {"objects": "none"}, {"objects": [{"distance": 3}]}]
    specs = {"near": "{any(objects[*].distance < 2)}"}
    r, got = run(rvc, tmp_path, rows, specs=specs)
    assert got["near"] == [True, True, True, False]  # the bad messages keep the previous value
    assert 'field "distance" of element 1 of "objects" is missing' in r.stderr, r.stderr
    assert 'field "objects" is a string, but {any(objects[*].distance < 2)} needs an array' in r.stderr, r.stderr
    r, got = run(rvc, tmp_path, rows, "--strict", specs=specs)
    assert r.returncode != 0 and got["near"] == [True, False]
    assert "element 1" in r.stderr and "needs an array" in r.stderr, r.stderr


def test_every_element_and_one_element_of_an_array_are_refused_together(rvc, tmp_path):
    """Each element is read once: ranges[*] and ranges[0] in one run are refused (exit 2), never mis-evaluated."""
    trace = tmp_path / "t.jsonl"
    trace.write_text(json.dumps(ROWS[0]) + "\n")
    r = subprocess.run([rvc, "check", "--spec", "{all(ranges[*] > 0.2)} && {ranges[0] > 1}", str(trace)],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and r.stdout == "", r.stderr
    assert '"ranges[*]" and a test of its element "ranges[0]"' in r.stderr, r.stderr


def caret_column(stderr):
    caret = next(line for line in stderr.splitlines() if line.strip() == "^")
    return len(caret) - len("  ^") + 1


def test_spec_errors_point_at_the_column(rvc):
    for spec, column, words in [
        ("{ranges[*] > 0.2}", 8, "inside all(..)"),
        ("{all(ranges > 0.2)}", 6, "needs an array path with '[*]'"),
        ("{count(a[*] > 1)}", 17, "count(..) is a number"),
        ("{any(a[*].b[*] > 1)}", 12, "one '[*]' per quantifier"),
    ]:
        r = subprocess.run([rvc, "check", "--spec", spec, "-"], input="", capture_output=True, text=True, timeout=60)
        assert r.returncode == 2, (spec, r.stderr)
        assert words in r.stderr and caret_column(r.stderr) == column, (spec, r.stderr)


def bag_values(rvc, bag, spec, *extra):
    r = subprocess.run([rvc, "check", "--all", *extra, str(bag), "--spec", spec], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode in (0, 1) and r.stderr == "", r.stderr
    return [value(json.loads(line)["value"]) for line in r.stdout.splitlines()]


@pytest.mark.needs_rust
def test_typed_laserscan_ranges(rvc, tmp_path):
    """sensor_msgs/msg/LaserScan samples (rosbags, float32 ranges exact in float32) give the JSON
    trace's hand-computed verdicts and margins."""
    from rosbags.typesys import Stores, get_typestore
    if "zenoh" not in transports_built(rvc):  # the MCAP reader lives in the Rust library
        pytest.fail("this rvc was built without its Rust library (RVC_WITH_ZENOH=OFF): no MCAP")
    ts = get_typestore(Stores.ROS2_HUMBLE)
    name, T = "sensor_msgs/msg/LaserScan", get_typestore(Stores.ROS2_HUMBLE).types
    scans = [[0.5, 0.25], [0.125, 0.25], [], [0.25, 0.875, 0.375]]
    samples = []
    for k, ranges in enumerate(scans):
        header = T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=k, nanosec=0), frame_id="l")
        m = T[name](header=header, angle_min=0.0, angle_max=1.0, angle_increment=0.5, time_increment=0.0,
                    scan_time=0.1, range_min=0.0, range_max=10.0, ranges=np.array(ranges, dtype=np.float32),
                    intensities=np.array([], dtype=np.float32))
        samples.append(ts.serialize_cdr(m, name))
    bag = write_bag(tmp_path / "scan.mcap", "/scan", name, ts.generate_msgdef(name, ros_version=2)[0], samples)
    spec = "{all(ranges[*] > 0.2)}"
    assert bag_values(rvc, bag, spec) == [True, False, True, True]
    assert bag_values(rvc, bag, spec, "--robustness") == pytest.approx([0.05, -0.075, math.inf, 0.05], abs=1e-12)
    assert bag_values(rvc, bag, "{count(ranges[*] < 0.3) == 2}") == [False, True, False, False]


@pytest.mark.needs_rust
def test_typed_array_of_structs_via_msg_path(rvc, tmp_path):
    """A custom message with an array of structs whose element type is only in --msg-path DIR."""
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg
    if "zenoh" not in transports_built(rvc):
        pytest.fail("this rvc was built without its Rust library (RVC_WITH_ZENOH=OFF): no MCAP")
    obj, objects = "float64 distance\nstring label\n", "rvc_aq_pkg/Obj[] objects\n"
    d = tmp_path / "defs" / "rvc_aq_pkg" / "msg"
    d.mkdir(parents=True)
    (d / "Obj.msg").write_text(obj)
    ts = get_typestore(Stores.EMPTY)
    ts.register(get_types_from_msg(obj, "rvc_aq_pkg/msg/Obj"))
    ts.register(get_types_from_msg(objects, "rvc_aq_pkg/msg/Objects"))
    Obj, Objects = ts.types["rvc_aq_pkg/msg/Obj"], ts.types["rvc_aq_pkg/msg/Objects"]
    samples = [ts.serialize_cdr(Objects(objects=[Obj(distance=float(x), label=lab) for x, lab in row]),
                                "rvc_aq_pkg/msg/Objects")
               for row in [[(1, "car"), (3, "ped")], [], [(1, "ped"), (1.5, "car"), (0.5, "ped")], [(2.5, "car")]]]
    bag = write_bag(tmp_path / "objs.mcap", "/objs", "rvc_aq_pkg/msg/Objects", objects, samples)
    defs = str(tmp_path / "defs")
    assert bag_values(rvc, bag, "{count(objects[*].distance < 2.0) >= 2}", "--msg-path", defs) == \
        [False, False, True, False]
    assert bag_values(rvc, bag, "{any(objects[*].distance < 2.0)}", "--robustness", "--msg-path", defs) == \
        [1, -math.inf, 1.5, -0.5]
    assert bag_values(rvc, bag, '{all(objects[*].label == "car")}', "--msg-path", defs) == [False, True, False, True]
