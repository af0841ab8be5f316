"""The Autoware case study (examples/autoware): the simulated vehicle's scenarios against the safety
properties, with the hand-written oracle examples/autoware/expected.yaml.

- Every scenario, as a rosbag2 MCAP bag written by `rosbags` (vehicle.py), is checked by `rvc check
  BAG --topic NAME=TOPIC ... --sync merge` with properties.yaml (discrete time) and
  properties-dense.yaml (dense time): each property's final verdict equals expected.yaml, and the
  exit status is 1 exactly when the oracle expects a violation.
- The oracle itself keeps its coverage: it names every scenario file and every property, nominal
  scenarios hold everything, each fault violates exactly the properties it targets, and every
  property is violated by some scenario. So the suite cannot quietly lose a scenario or a property.
- The generated topics have the rates of topics.yaml (also scaled by --rate-scale) within the
  jitter, and every line is a valid message of its type (`rvc msg encode`).
- `vehicle.py publish` puts a scenario on DDS (nine `rvc replay --type` processes); two `rvc
  monitor`s (discrete and dense) merging the nine typed topics give the oracle's verdicts.
rosbags is required: without it the tests fail, they do not skip.
"""
import glob
import json
import os
import subprocess
import sys

import pytest
import yaml

from conftest import PLATFORM, transports_built

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXAMPLE = os.path.join(ROOT, "examples", "autoware")
VEHICLE = os.path.join(EXAMPLE, "vehicle.py")
sys.path.insert(0, EXAMPLE)
import vehicle  # noqa: E402

SCENARIOS = sorted(os.path.splitext(os.path.basename(p))[0]
                   for p in glob.glob(os.path.join(EXAMPLE, "scenarios", "*.yaml")))
PROPERTIES = {False: os.path.join(EXAMPLE, "properties.yaml"), True: os.path.join(EXAMPLE, "properties-dense.yaml")}
TOPICS = vehicle.load_topics()


def load_expected():
    with open(os.path.join(EXAMPLE, "expected.yaml")) as f:
        return yaml.safe_load(f)["scenarios"]


def scenario(name):
    return vehicle.Scenario(os.path.join(EXAMPLE, "scenarios", name + ".yaml"))


@pytest.fixture(scope="module")
def bags(rvc):
    """rosbags (the bag writer) and rvc's MCAP reader (in its Rust library) are both required."""
    try:
        import rosbags  # noqa: F401
    except ImportError:
        pytest.fail("the rosbags package is missing (pip install rosbags): it writes the scenarios' bags")
    if "zenoh" not in transports_built(rvc):
        pytest.fail("this rvc was built without its Rust library (RVC_WITH_ZENOH=OFF): it cannot read MCAP bags")
    return {}


def test_the_oracle_covers_every_scenario_and_property():
    expected = load_expected()
    names = vehicle.property_names(PROPERTIES[False])
    assert vehicle.property_names(PROPERTIES[True]) == names, "discrete and dense files name different properties"
    assert len(names) >= 8 and len(set(names)) == len(names)
    assert sorted(expected) == SCENARIOS, "expected.yaml and scenarios/ name different scenarios"
    nominal = [s for s in SCENARIOS if scenario(s).kind == "nominal"]
    assert {"drive", "turn", "park", "emergency", "mrm"} <= set(nominal)
    for s in SCENARIOS:
        row = expected[s]
        assert sorted(row) == sorted(names), f"{s}: expected.yaml must give a verdict for every property"
        assert set(row.values()) <= {"held", "violated"}, s
        violated = sorted(p for p, v in row.items() if v == "violated")
        sc = scenario(s)
        if sc.kind == "nominal":
            assert violated == [], f"nominal scenario {s} must hold every property"
        else:
            assert sc.targets and violated == sorted(sc.targets), f"fault {s} must violate exactly its targets"
    for p in names:
        assert any(expected[s][p] == "violated" for s in SCENARIOS), f"no scenario violates {p}"
        assert all(expected[s][p] == "held" for s in nominal), p


@pytest.mark.parametrize("name", SCENARIOS)
def test_scenario_verdicts_equal_the_oracle(rvc, bags, tmp_path, name):
    want = load_expected()[name]
    msgs = vehicle.generate(scenario(name), TOPICS)
    bag = vehicle.write_bag(msgs, TOPICS, str(tmp_path / "bag"))
    total = sum(len(m) for m in msgs.values())
    for dense in (False, True):
        cmd = vehicle.check_command(rvc, bag, TOPICS, PROPERTIES[dense], dense) + ["--summary"]
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
        assert r.returncode in (0, 1), r.stderr
        assert f"{total} messages checked, 0 rejected, 0 warnings" in r.stderr, r.stderr
        got = {p: "held" if v else "violated" for p, (v, _) in vehicle.final_verdicts(r.stdout).items()}
        assert got == want, f"{name} ({'dense' if dense else 'discrete'}): {r.stdout}"
        assert r.returncode == (1 if "violated" in want.values() else 0)


def read_stamps(path):
    with open(path) as f:
        return [m["stamp"]["sec"] * 10**9 + m["stamp"]["nanosec"] for m in map(json.loads, f)]


@pytest.mark.parametrize("scale", [1, 10])
def test_generated_rates_match_the_topics(rvc, tmp_path, scale):
    name = "emergency"
    out = tmp_path / "jsonl"
    r = subprocess.run([sys.executable, VEHICLE, "generate", os.path.join(EXAMPLE, "scenarios", name + ".yaml"),
                        "--out", str(out), "--rate-scale", str(scale)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    duration = scenario(name).duration
    epoch = TOPICS["epoch"] * 10**9
    for t in TOPICS["topics"]:
        rate = t["rate"] * scale
        period = 1e9 / rate
        # the generator's jitter (at most 10% of the period), plus 2 us: a stamp taken by another
        # topic moves to the next free microsecond
        jitter = min(TOPICS["jitter_ms"] * 1e6, 0.1 * period) + 2000
        stamps = read_stamps(out / f"{t['name']}.jsonl")
        assert len(stamps) == round(duration * rate), t["name"]
        assert epoch <= stamps[0] <= epoch + 2 * jitter
        gaps = [b - a for a, b in zip(stamps, stamps[1:])]
        assert all(period - 2 * jitter <= g <= period + 2 * jitter for g in gaps), t["name"]
        measured = (len(stamps) - 1) * 1e9 / (stamps[-1] - stamps[0])
        assert abs(measured - rate) <= rate * 2 * jitter / (stamps[-1] - stamps[0]) + 1e-9, (t["name"], measured)
        assert len(set(gaps)) > 1, "no jitter"
        if scale == 1:  # each line is a message of the topic's type
            enc = subprocess.run([rvc, "msg", "encode", "--type", t["type"], str(out / f"{t['name']}.jsonl")],
                                 capture_output=True, text=True, timeout=60)
            assert enc.returncode == 0 and len(enc.stdout.splitlines()) == len(stamps), enc.stderr


def test_check_subcommand_prints_the_verdicts(rvc, bags):
    r = subprocess.run([sys.executable, VEHICLE, "check", os.path.join(EXAMPLE, "scenarios", "fault-hazard-late.yaml"),
                        "--rvc", rvc, "--dense"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 1, r.stderr
    lines = {line.split()[0]: line for line in r.stdout.splitlines()[1:]}
    assert "violated (first false at 10.0" in lines["hazard_on_emergency"], r.stdout
    assert all(line.split()[1] == "held" for p, line in lines.items() if p != "hazard_on_emergency"), r.stdout
    assert "--sync merge" in r.stderr and "--topic status=/api/external/get/vehicle/status" in r.stderr


def test_published_on_dds_the_monitors_give_the_oracle(rvc, tmp_path):
    """The simulated vehicle on DDS: nine typed topics published by `vehicle.py publish` (4x faster
    than real time; stamps unchanged), read by a discrete and a dense `rvc monitor` that merge them."""
    if "dds" not in transports_built(rvc):
        pytest.skip(PLATFORM + " rvc built without DDS")
    name = "fault-hazard-late"
    domain = str(180 + os.getpid() % 40)
    inputs = []
    for t in TOPICS["topics"]:
        inputs += ["--input", f"{t['name']}=dds:{t['topic']}", "--type", t["type"]]
    monitors = []
    for dense in (False, True):
        out = tmp_path / f"verdicts-{dense}.jsonl"
        cmd = [rvc, "monitor", *inputs, "--sync", "merge", "--max-delay", "1000", "--properties", PROPERTIES[dense],
               "--output", f"file:{out}", "--idle-timeout", "3", "--domain", domain] + (["--dense"] if dense else [])
        monitors.append((out, subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True)))
    try:
        pub = subprocess.run([sys.executable, VEHICLE, "publish", os.path.join(EXAMPLE, "scenarios", name + ".yaml"),
                              "--rvc", rvc, "--speed", "4", "--domain", domain, "--wait-subscribers", "2"],
                             capture_output=True, text=True, timeout=60)
        assert pub.returncode == 0, pub.stdout + pub.stderr
        results = [(out, p.communicate(timeout=60)[1], p.returncode) for out, p in monitors]
    finally:
        for _, p in monitors:
            if p.poll() is None:
                p.kill()
    want = load_expected()[name]
    total = sum(len(m) for m in vehicle.generate(scenario(name), TOPICS).values())
    for out, err, code in results:
        assert code == 1, err
        stats = json.loads([line for line in err.splitlines() if line.startswith('{"input"')][-1])
        assert stats["received"] == total and stats["checked"] == total and stats["gaps"] == 0, err
        got = {p: "held" if v else "violated" for p, (v, _) in vehicle.final_verdicts(out.read_text()).items()}
        assert got == want, out.read_text()
