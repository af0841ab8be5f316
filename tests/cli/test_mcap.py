"""ROS 2 bags (MCAP): `rvc check bag.mcap --topic T` and `rvc monitor --input mcap:bag.mcap`.

Independent writers: rosbags' rosbag2 writer with its MCAP storage (the layout `ros2 bag record -s
mcap` makes: a folder with metadata.yaml and the .mcap, CDR samples serialized by rosbags, schemas
as ros2msg text) and the `mcap` package from PyPI (Foxglove's reference writer) with each chunk
compression (zstd, lz4, none). The type of each topic comes from the bag's own schema: no
--msg-path. Oracle for verdicts: `rvc check` on the same values written as JSON lines.
"""
import json
import os
import random
import struct
import subprocess

import pytest

from conftest import transports_built

pytestmark = pytest.mark.needs_rust  # every test here reads a bag

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEFS = os.path.join(ROOT, "src", "msg", "definitions")
GEAR = "autoware_auto_vehicle_msgs/msg/GearReport"
STEER = "autoware_auto_vehicle_msgs/msg/SteeringReport"
GEAR_TOPIC, STEER_TOPIC = "/vehicle/status/gear_status", "/vehicle/status/steering_status"


@pytest.fixture
def typestore(rvc):
    if "zenoh" not in transports_built(rvc):  # the MCAP reader lives in the Rust library
        pytest.fail("this rvc was built without its Rust library (RVC_WITH_ZENOH=OFF): no MCAP")
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg
    ts = get_typestore(Stores.ROS2_HUMBLE)
    for name in (GEAR, STEER):
        with open(os.path.join(DEFS, name.split("/")[0], "msg", name.split("/")[-1] + ".msg")) as f:
            ts.register(get_types_from_msg(f.read(), name))
    return ts


def run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, timeout=120, **kw)


def gear_values(n, seed):
    rng = random.Random(seed)
    t, out = 1_700_000_000 * 10**9, []
    for _ in range(n):
        t += rng.choice([40, 100, 250]) * 10**6
        out.append((t, rng.choice([1, 2, 20, 22])))
    return out


def write_rosbag2(tmp_path, ts, gears, steers):
    """A rosbag2 folder in MCAP storage, as `ros2 bag record -s mcap` writes it."""
    from rosbags.rosbag2 import Writer
    from rosbags.rosbag2.enums import StoragePlugin
    Time = ts.types["builtin_interfaces/msg/Time"]
    folder = tmp_path / "drive"
    with Writer(folder, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        cg = w.add_connection(GEAR_TOPIC, GEAR, typestore=ts)
        cs = w.add_connection(STEER_TOPIC, STEER, typestore=ts)
        events = [(t, cg, ts.types[GEAR](stamp=Time(sec=t // 10**9, nanosec=t % 10**9), report=r), GEAR)
                  for t, r in gears]
        events += [(t, cs, ts.types[STEER](stamp=Time(sec=t // 10**9, nanosec=t % 10**9),
                                           steering_tire_angle=a), STEER) for t, a in steers]
        for t, conn, msg, name in sorted(events, key=lambda e: e[0]):
            w.write(conn, t, ts.serialize_cdr(msg, name))
    bags = list(folder.glob("*.mcap"))
    assert len(bags) == 1
    return str(bags[0])


def stamp(t):
    """Integer nanoseconds as a JSON Time object: the exact instant, independent of rvc's decimal reading."""
    return {"sec": t // 10**9, "nanosec": t % 10**9}


def json_trace(tmp_path, name, rows):
    p = tmp_path / name
    p.write_text("".join(json.dumps(r) + "\n" for r in rows))
    return str(p)


def test_rosbag2_bag_checks_like_its_json(rvc, tmp_path, typestore):
    gears = gear_values(60, 1)
    steers = [(t + 7, random.Random(t).uniform(-0.6, 0.6)) for t, _ in gear_values(80, 2)]
    bag = write_rosbag2(tmp_path, typestore, gears, steers)
    spec = "{report == REVERSE} -> pre {report == PARK}"
    got = run([rvc, "check", "--all", "--summary", "--spec", spec, bag, "--topic", GEAR_TOPIC])
    expected = run([rvc, "check", "--all", "--spec", "{report == 20} -> pre {report == 22}",
                    json_trace(tmp_path, "gear.jsonl", [{"report": r} for _, r in gears])])
    assert got.stdout == expected.stdout and '"value":false' in expected.stdout, got.stderr
    assert got.returncode == expected.returncode == 1
    assert f"topic {GEAR_TOPIC} ({GEAR}, 60 messages)" in got.stderr
    # The same bag through `rvc monitor --input mcap:` (one runtime): the same verdicts.
    mon = run([rvc, "monitor", "--all", "--spec", spec, "--input", f"mcap:{bag}", "--topic", GEAR_TOPIC])
    assert mon.stdout == expected.stdout, mon.stderr
    stats = json.loads(mon.stderr.strip().splitlines()[-1])
    assert (stats["topic"], stats["checked"], stats["rejected"]) == (GEAR_TOPIC, 60, 0)
    # Dense time reads each sample's stamp: equal to the JSON trace with the stamp as a number.
    steer_spec = "historically[0:0.3]{steering_tire_angle < 0.5}"
    dense = run([rvc, "check", "--dense", "--spec", steer_spec, bag, "--topic", STEER_TOPIC])
    f32 = lambda a: struct.unpack("<f", struct.pack("<f", a))[0]  # the wire type is float32
    rows = [{"t": stamp(t), "steering_tire_angle": f32(a)} for t, a in steers]
    want = run([rvc, "check", "--dense", "--time-field", "t", "--spec", steer_spec,
                json_trace(tmp_path, "steer.jsonl", rows)])
    assert dense.stdout == want.stdout and '"value":false' in want.stdout, dense.stderr


def test_rosbag2_robustness_like_its_json(rvc, tmp_path, typestore):
    """--robustness on a bag: each test's margin comes from the CDR sample as from the JSON value
    (io::test_margin on both paths), so every value equals the JSON trace's, discrete and dense,
    bounded since included."""
    gears = gear_values(60, 3)
    steers = [(t + 7, random.Random(t).uniform(-0.6, 0.6)) for t, _ in gear_values(80, 4)]
    bag = write_rosbag2(tmp_path, typestore, gears, steers)
    f32 = lambda a: struct.unpack("<f", struct.pack("<f", a))[0]  # the wire type is float32
    steer_rows = [{"t": stamp(t), "steering_tire_angle": f32(a)} for t, a in steers]
    steer_json = json_trace(tmp_path, "steer.jsonl", steer_rows)

    def values(out):
        return [json.loads(l)["value"] for l in out.splitlines()]

    cases = [  # (typed args, JSON args)
        (["--all", "--spec", "{report == REVERSE} since[0:2] {report != PARK}", bag, "--topic", GEAR_TOPIC],
         ["--all", "--spec", "{report == 20} since[0:2] {report != 22}",
          json_trace(tmp_path, "gear.jsonl", [{"report": r} for _, r in gears])]),
        (["--all", "--spec", "({steering_tire_angle < 0.5} since[1:3] {steering_tire_angle > -0.2}) or "
          "historically[0:2]{steering_tire_angle > -0.55}", bag, "--topic", STEER_TOPIC],
         ["--all", "--spec", "({steering_tire_angle < 0.5} since[1:3] {steering_tire_angle > -0.2}) or "
          "historically[0:2]{steering_tire_angle > -0.55}", steer_json]),
        (["--dense", "--spec", "{steering_tire_angle < 0.5} since[0.1:0.4] {steering_tire_angle > -0.2}", bag,
          "--topic", STEER_TOPIC],
         ["--dense", "--time-field", "t", "--spec",
          "{steering_tire_angle < 0.5} since[0.1:0.4] {steering_tire_angle > -0.2}", steer_json]),
    ]
    for typed_args, json_args in cases:
        got = run([rvc, "check", "--robustness", *typed_args])
        want = run([rvc, "check", "--robustness", *json_args])
        assert got.returncode == want.returncode and got.returncode in (0, 1), (got.stderr, want.stderr)
        assert got.stdout == want.stdout, got.stderr
        # margins, not only infinities
        assert any(isinstance(v, (int, float)) and v != 0 for v in values(want.stdout)), want.stdout


def test_choosing_the_topic(rvc, tmp_path, typestore):
    bag = write_rosbag2(tmp_path, typestore, gear_values(5, 3), [(10**9 * i, 0.1) for i in range(1, 4)])
    r = run([rvc, "check", "--spec", "{report == 2}", bag])
    assert r.returncode == 2
    assert "holds 2 topics: choose one with --topic" in r.stderr
    assert f"{GEAR_TOPIC} ({GEAR}, 5 messages)" in r.stderr and f"{STEER_TOPIC} ({STEER}, 3 messages)" in r.stderr
    r = run([rvc, "check", "--spec", "{report == 2}", bag, "--topic", "/vehicle/gear"])
    assert r.returncode == 2 and "has no topic '/vehicle/gear'" in r.stderr
    # A field the bag's type lacks is a spec error pointing at it, as with --type.
    r = run([rvc, "check", "--spec", "{gear == 2}", bag, "--topic", GEAR_TOPIC])
    assert r.returncode == 2 and "no field 'gear'" in r.stderr, r.stderr
    r = run([rvc, "check", "--spec", "{p}", "--topic", GEAR_TOPIC,
             json_trace(tmp_path, "x.jsonl", [{"p": True}])])
    assert r.returncode == 2 and "--topic chooses a topic of a bag" in r.stderr


def test_several_topics_of_a_bag_in_one_run(rvc, tmp_path, typestore):
    """--topic NAME=TOPIC twice: the two topics merged by their stamps into one stream, tested as
    {gear.…} and {steer.…}. Oracle: the merge written out here (each message an event at its stamp,
    the other topic's latest value held) through `rvc check` as JSON, discrete and dense."""
    gears = gear_values(50, 5)
    steers = [(t + 13 * 10**6, random.Random(t).uniform(-0.6, 0.6)) for t, _ in gear_values(70, 6)]
    bag = write_rosbag2(tmp_path, typestore, gears, steers)
    f32 = lambda a: struct.unpack("<f", struct.pack("<f", a))[0]
    events, latest = [], {}
    for t, name, value in sorted([(t, "gear", {"report": r}) for t, r in gears] +
                                 [(t, "steer", {"steering_tire_angle": f32(a)}) for t, a in steers]):
        latest[name] = value
        events.append(dict(latest, t=stamp(t)))
    trace = json_trace(tmp_path, "merged.jsonl", events)
    topics = ["--topic", f"gear={GEAR_TOPIC}", "--topic", f"steer={STEER_TOPIC}"]
    for mode, spec, numeric in [
        ([], "{gear.report == REVERSE} -> {steer.steering_tire_angle < 0.3}",
         "{gear.report == 20} -> {steer.steering_tire_angle < 0.3}"),
        (["--dense"], "historically[0:0.2]({gear.report == REVERSE} -> {steer.steering_tire_angle > -0.4})",
         "historically[0:0.2]({gear.report == 20} -> {steer.steering_tire_angle > -0.4})"),
    ]:
        got = run([rvc, "check", "--all", *mode, "--summary", "--spec", spec, bag, *topics])
        want = run([rvc, "check", "--all", *mode, "--time-field", "t", "--spec", numeric, trace])
        assert got.stdout == want.stdout and '"value":false' in want.stdout, got.stderr
        assert f"gear={GEAR_TOPIC} ({GEAR}, 50)" in got.stderr and "sync merge" in got.stderr, got.stderr
        mon = run([rvc, "monitor", "--all", *mode, "--spec", spec, "--input", f"mcap:{bag}", *topics])
        assert mon.stdout == want.stdout, mon.stderr
    # --explain across synchronized inputs: the same sentences as for the merged stream as one input
    # (a spec without message constants reads the same on both).
    for mode, spec in [([], "historically({steer.steering_tire_angle < 0.3} or {gear.report > 1})"),
                       (["--dense"], "historically[0:0.2]{steer.steering_tire_angle > -0.4}")]:
        got = run([rvc, "check", "--explain", *mode, "--spec", spec, bag, *topics])
        want = run([rvc, "check", "--explain", *mode, "--time-field", "t", "--spec", spec, trace])
        assert '"explain":[' in want.stdout, want.stdout
        assert got.stdout == want.stdout, got.stderr
    # A topic named by its last part; an unknown one is named with the bag's topics.
    r = run([rvc, "check", "--spec", "{gear_status.report == 2}", bag, "--topic", GEAR_TOPIC, "--topic", STEER_TOPIC])
    assert r.returncode in (0, 1), r.stderr
    r = run([rvc, "check", "--spec", "{a.report == 2}", bag, "--topic", f"a={GEAR_TOPIC}", "--topic", "b=/x"])
    assert r.returncode == 2 and "has no topic '/x'" in r.stderr, r.stderr


@pytest.mark.parametrize("compression", ["zstd", "lz4", "none"])
def test_mcap_writer_chunk_compressions(rvc, tmp_path, typestore, compression):
    """Foxglove's writer, each chunk compression; small chunks so the bag has many."""
    from mcap.writer import CompressionType, Writer
    gears = gear_values(300, 4)
    path = tmp_path / f"gear-{compression}.mcap"
    text, _ = typestore.generate_msgdef(GEAR, ros_version=2)
    Time = typestore.types["builtin_interfaces/msg/Time"]
    with open(path, "wb") as f:
        w = Writer(f, chunk_size=512, compression=getattr(CompressionType, compression.upper()))
        w.start(profile="ros2", library="rvc tests")
        schema = w.register_schema(name=GEAR, encoding="ros2msg", data=text.encode())
        ch = w.register_channel(topic=GEAR_TOPIC, message_encoding="cdr", schema_id=schema)
        for i, (t, r) in enumerate(gears):
            data = typestore.serialize_cdr(typestore.types[GEAR](stamp=Time(sec=t // 10**9, nanosec=t % 10**9),
                                                                 report=r), GEAR)
            w.add_message(channel_id=ch, log_time=t, publish_time=t, sequence=i, data=data)
        w.finish()
    spec = "{report == REVERSE} -> once[0:0.5]{report == PARK}"
    got = run([rvc, "check", "--dense", "--spec", spec, str(path)])  # one topic: no --topic needed
    want = run([rvc, "check", "--dense", "--time-field", "t", "--spec", "{report == 20} -> once[0:0.5]{report == 22}",
                json_trace(tmp_path, "g.jsonl", [{"t": stamp(t), "report": r} for t, r in gears])])
    assert got.stdout == want.stdout and '"value":false' in want.stdout, got.stderr


def test_json_messages_in_a_bag(rvc, tmp_path, typestore):
    from mcap.writer import Writer
    rows = [{"p": i % 3 != 0, "q": i % 2 == 0} for i in range(20)]
    path = tmp_path / "json.mcap"
    with open(path, "wb") as f:
        w = Writer(f)
        w.start(profile="", library="rvc tests")
        ch = w.register_channel(topic="/status", message_encoding="json", schema_id=0)
        for i, row in enumerate(rows):
            w.add_message(channel_id=ch, log_time=i, publish_time=i, sequence=i, data=json.dumps(row).encode())
        w.finish()
    got = run([rvc, "check", "--all", "--spec", "{p} -> {q}", str(path)])
    want = run([rvc, "check", "--all", "--spec", "{p} -> {q}", json_trace(tmp_path, "j.jsonl", rows)])
    assert got.stdout == want.stdout and got.returncode == want.returncode == 1, got.stderr


def test_broken_bags_are_named(rvc, tmp_path, typestore):
    bag = write_rosbag2(tmp_path, typestore, gear_values(400, 5), [])
    data = open(bag, "rb").read()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])  # a recording that stopped mid-file
    r = run([rvc, "check", "--all", "--spec", "{report >= 0}", str(cut)])
    # What was recorded before the break is checked (nothing valid is lost), the break is named: exit 3.
    assert r.returncode == 3 and "cut.mcap" in r.stderr and "the messages before it were checked" in r.stderr
    checked = len(r.stdout.splitlines())
    assert 100 < checked < 400, r.stderr
    whole = run([rvc, "check", "--all", "--spec", "{report >= 0}", bag])
    assert r.stdout == "".join(whole.stdout.splitlines(keepends=True)[:checked])
    assert "Traceback" not in r.stderr and "panic" not in r.stderr
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(data[:8] + bytes(random.Random(1).randrange(256) for _ in range(300)))
    r = run([rvc, "check", "--spec", "{report == 2}", str(junk)])
    assert r.returncode == 2 and "junk.mcap" in r.stderr, r.stderr


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
    from rosbags.typesys import Stores, get_typestore, get_types_from_idl
    if "zenoh" not in transports_built(rvc):  # the MCAP reader lives in the Rust library
        pytest.fail("this rvc was built without its Rust library (RVC_WITH_ZENOH=OFF): no MCAP")
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
    typed = run([rvc, "check", str(bag), "--all", "--spec", "{report == REVERSE} -> {speed <= 0}"])
    plain = run([rvc, "check", str(trace), "--all", "--spec", "{report == 20} -> {speed <= 0}"])
    assert typed.returncode == plain.returncode == 1, (typed.stderr, plain.stderr)
    assert typed.stdout == plain.stdout and len(typed.stdout.splitlines()) == 200


def test_data_references_on_typed_samples(rvc, tmp_path, typestore):
    """exists/forall binding a typed field (a uint8 here): the same verdicts as on the JSON of the
    same values, discrete and dense; binding a message field is a spec error pointing at it."""
    gears = gear_values(80, 9)
    bag = write_rosbag2(tmp_path, typestore, gears, [(10**9, 0.1)])
    spec = "exists[g]. ({report: *g} and pre(once[0:4]{report: *g}))"  # the gear was reported in the last 5
    got = run([rvc, "check", "--all", "--spec", spec, bag, "--topic", GEAR_TOPIC])
    want = run([rvc, "check", "--all", "--spec", spec, json_trace(tmp_path, "g.jsonl", [{"report": r} for _, r in gears])])
    assert got.stdout == want.stdout and '"value":false' in want.stdout and '"value":true' in want.stdout, got.stderr
    dense_spec = "forall[g]. ({report: *g} -> once[0.05:0.3]{report: *g})"
    got = run([rvc, "check", "--dense", "--spec", dense_spec, bag, "--topic", GEAR_TOPIC])
    want = run([rvc, "check", "--dense", "--time-field", "t", "--spec", dense_spec,
                json_trace(tmp_path, "gt.jsonl", [{"t": stamp(t), "report": r} for t, r in gears])])
    assert got.stdout == want.stdout and '"value":false' in want.stdout, got.stderr
    r = run([rvc, "check", "--spec", "exists[s]. {stamp: *s}", bag, "--topic", GEAR_TOPIC])
    assert r.returncode == 2 and "a reference binds a string, number or Boolean field" in r.stderr, r.stderr
    r = run([rvc, "check", "--spec", "exists[g]. {gear.report: *g}", bag, "--topic", f"gear={GEAR_TOPIC}",
             "--topic", f"steer={STEER_TOPIC}"])
    assert r.returncode == 2 and "data references (exists/forall) check one input for now" in r.stderr, r.stderr
