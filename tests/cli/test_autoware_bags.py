"""Real Autoware recordings (../shared/data/autoware-bags: nav_msgs/Odometry at ~50 Hz, epoch
nanosecond stamps): dense properties that hold are reported as holding, from the first message, and a
window edge falls at the exact nanosecond (issue 36).

Oracle: the `rosbags` package reads every header stamp as integers (sec, nanosec); the largest gap
between two stamps, G ns, is worked out here. `historically({@age <= G})` must hold (a gap of exactly
the bound is no violation), and with G - 1 ns it must fall exactly 1 ns before the message that ends the
first largest gap."""
import json
import os
import subprocess

import pytest

BAGS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "shared", "data", "autoware-bags")
NAMES = ["bag_ego_trajectory_turn-right.db3", "bag_ego_trajectory_turn-left-right.db3"]
TOPIC = "/localization/kinematic_state"
pytestmark = pytest.mark.needs_rust  # bags are read through rvc's Rust library in the sanitizer-free build


def run(args):
    return subprocess.run(args, capture_output=True, text=True, timeout=120)


def sec_text(ns):
    whole, frac = divmod(ns, 10**9)
    return str(whole) if frac == 0 else f"{whole}.{frac:09d}".rstrip("0")


def stamps(path):
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore
    from pathlib import Path
    out = []
    with AnyReader([Path(path)], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as r:
        conns = [c for c in r.connections if c.topic == TOPIC]
        for conn, _, raw in r.messages(connections=conns):
            m = r.deserialize(raw, conn.msgtype)
            out.append(m.header.stamp.sec * 10**9 + m.header.stamp.nanosec)
    return out


def verdicts(stdout):
    return [(line[len('{"time":'):line.index(",")], json.loads(line)["value"]) for line in stdout.splitlines()]


@pytest.fixture(scope="module", params=NAMES)
def bag(request):
    path = os.path.join(BAGS, request.param)
    assert os.path.exists(path), f"{path}: the shared Autoware recordings are this test's data (never skipped)"
    ts = stamps(path)
    assert len(ts) > 2000 and ts == sorted(ts)
    return path, ts


def test_a_property_that_holds_is_reported_as_holding_from_the_first_message(rvc, bag):
    path, ts = bag
    spec = "historically({twist.twist.linear.x < 1000})"
    for args in ([rvc, "check", path, "--dense", "--spec", spec],
                 [rvc, "monitor", "--dense", "--input", f"bag:{path}", "--spec", spec]):
        r = run(args)
        assert r.returncode == 0, (args, r.stdout, r.stderr)
        assert verdicts(r.stdout) == [(sec_text(ts[0]), True)], r.stdout


def test_a_silence_bound_falls_at_the_exact_nanosecond(rvc, bag):
    path, ts = bag
    gaps = [b - a for a, b in zip(ts, ts[1:])]
    g = max(gaps)
    k = gaps.index(g)  # the first largest gap: from ts[k] to ts[k + 1]
    held = run([rvc, "check", path, "--dense", "--spec", f"historically({{@age <= {sec_text(g)}}})"])
    assert held.returncode == 0, held.stderr
    assert verdicts(held.stdout) == [(sec_text(ts[0]), True)]
    fell = run([rvc, "check", path, "--dense", "--spec", f"historically({{@age <= {sec_text(g - 1)}}})"])
    assert fell.returncode == 1, fell.stderr
    assert verdicts(fell.stdout) == [(sec_text(ts[0]), True), (sec_text(ts[k] + g - 1), False)]
