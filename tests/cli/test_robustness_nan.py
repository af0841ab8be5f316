"""NaN in --robustness (issue 36, docs/semantics.md "Robustness"): a comparison with a NaN side has
the margin of its Boolean value (-inf when false, +inf for != and {x}), so and/or never see a NaN,
the conjuncts' order does not matter, and the robustness verdict's exit status is the Boolean one, on
JSON lines and on typed CDR samples (serialized by rosbags), also inside an array quantifier. Before:
`{y > 0} and {x > 0.2}` with x NaN was +5 (exit 0) against a false Boolean verdict, the other order
null."""
import json
import math
import subprocess

import numpy as np
import pytest

from conftest import transports_built

from rvc_testlib import write_mcap_bag as write_bag  # noqa: E402

INF = math.inf


def value(v):
    return {"inf": INF, "-inf": -INF}.get(v, v) if isinstance(v, str) else v


def check(rvc, trace, spec, *extra):
    r = subprocess.run([rvc, "check", *extra, str(trace), "--spec", spec], capture_output=True, text=True, timeout=60)
    assert r.returncode in (0, 1), r.stderr
    return r.returncode, [value(json.loads(line)["value"]) for line in r.stdout.splitlines()]


# spec, Boolean verdict, margin (by hand: NaN fails every comparison but !=; {x} NaN is non-zero)
CASES = [
    ("{y > 0} and {x > 0.2}", False, -INF),
    ("{x > 0.2} and {y > 0}", False, -INF),
    ("{y > 0} or {x > 0.2}", True, 5.0),
    ("{x > 0.2} or {y > 0}", True, 5.0),
    ("not ({x < 0.2} or {x >= 0.2})", True, INF),
    ("{x != 0.2} and {y > 0}", True, 5.0),
    ("{x == 0.2} or {y < 0}", False, -5.0),
    ("{x} and {y > 0}", True, 5.0),
    ("historically({y > 0} and {x <= 1})", False, -INF),
]


@pytest.mark.parametrize("dense", [False, True], ids=["discrete", "dense"])
@pytest.mark.parametrize("spec,holds,margin", CASES)
def test_json_nan_margins_agree_with_the_boolean_verdict(rvc, tmp_path, spec, holds, margin, dense):
    trace = tmp_path / "nan.jsonl"
    trace.write_text('{"time": 0, "x": NaN, "y": 5}\n')
    extra = ["--dense"] if dense else []
    b_status, b_values = check(rvc, trace, spec, *extra)
    r_status, r_values = check(rvc, trace, spec, "--robustness", *extra)
    assert b_values == [holds]
    assert r_values == [margin]
    assert b_status == r_status == (0 if holds else 1)


def test_json_array_quantifier_with_a_nan_element(rvc, tmp_path):
    trace = tmp_path / "scan.jsonl"
    trace.write_text('{"ranges": [0.5, NaN, 0.25]}\n{"ranges": [NaN]}\n{"ranges": [0.5]}\n')
    for spec, bools, margins in [("{all(ranges[*] > 0.2)}", [False, False, True], [-INF, -INF, 0.3]),
                                 ("{any(ranges[*] < 0.3)}", [True, False, False], [0.05, -INF, -0.2])]:
        status, got = check(rvc, trace, spec, "--all")
        assert got == bools, spec
        r_status, r_got = check(rvc, trace, spec, "--all", "--robustness")
        assert r_got == pytest.approx(margins, abs=1e-12), spec
        assert r_status == status == 1, spec


@pytest.mark.needs_rust
def test_typed_samples_with_nan(rvc, tmp_path):
    """A geometry_msgs/Point with x NaN and a LaserScan with a NaN range, serialized by rosbags: the
    JSON trace's margins, both conjunct orders, Boolean and robustness exit status alike."""
    from rosbags.typesys import Stores, get_typestore
    if "zenoh" not in transports_built(rvc):  # the MCAP reader lives in the Rust library
        pytest.fail("this rvc was built without its Rust library (RVC_WITH_ZENOH=OFF): no MCAP")
    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    point = "geometry_msgs/msg/Point"
    bag = write_bag(tmp_path / "point.mcap", "/p", point, ts.generate_msgdef(point, ros_version=2)[0],
                    [ts.serialize_cdr(T[point](x=math.nan, y=5.0, z=0.0), point)])
    for spec, holds, margin in CASES:
        if "historically" in spec:
            continue
        b_status, b_values = check(rvc, bag, spec)
        r_status, r_values = check(rvc, bag, spec, "--robustness")
        assert (b_values, r_values) == ([holds], [margin]), spec
        assert b_status == r_status == (0 if holds else 1), spec

    scan = "sensor_msgs/msg/LaserScan"
    samples = []
    for k, ranges in enumerate([[0.5, math.nan, 0.25], [math.nan], [0.5]]):
        header = T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=k, nanosec=0), frame_id="l")
        m = T[scan](header=header, angle_min=0.0, angle_max=1.0, angle_increment=0.5, time_increment=0.0,
                    scan_time=0.1, range_min=0.0, range_max=10.0, ranges=np.array(ranges, dtype=np.float32),
                    intensities=np.array([], dtype=np.float32))
        samples.append(ts.serialize_cdr(m, scan))
    bag = write_bag(tmp_path / "scan.mcap", "/scan", scan, ts.generate_msgdef(scan, ros_version=2)[0], samples)
    status, got = check(rvc, bag, "{all(ranges[*] > 0.2)}", "--all")
    r_status, r_got = check(rvc, bag, "{all(ranges[*] > 0.2)}", "--all", "--robustness")
    assert got == [False, False, True]
    assert r_got == pytest.approx([-INF, -INF, 0.3], abs=1e-7)  # 0.5 is exact in float32
    assert status == r_status == 1
