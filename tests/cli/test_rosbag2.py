"""ROS 2 bags as rosbag2 writes them: sqlite3 storage (.db3, the default up to Humble), MCAP, bag
folders (metadata.yaml + split files, merged by log time), zstd per file and per message; `rvc bag
info`, `rvc echo BAG --topic T`, `rvc check BAG`, `rvc monitor --input bag:BAG`.

Oracles: rosbags' Reader (PyPI, an independent rosbag2 reader and CDR decoder) for every value and
count of ROS 2's own test bags (tests/data/ros2-bags, copied from ros2/rosbag2), and the bags' own
metadata.yaml; for verdicts, the same messages written by rosbags' Writer as a db3 bag and as its MCAP
twin must give identical output, equal to `rvc check` on the values written as JSON lines.
"""
import json
import math
import os
import shutil
import sqlite3
import subprocess

import pytest

from conftest import transports_built

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BAGS = os.path.join(ROOT, "tests", "data", "ros2-bags")
MSGS = os.path.join(ROOT, "tests", "data", "ros2-msgs")  # rcl_interfaces/msg/Log: talker.db3 records a stand-in

# (folder, topic): every topic with messages in the test bags whose type rvc reads today.
TOPICS = [
    ("talker", "/topic"), ("talker", "/rosout"),
    ("cdr_test", "/test_topic"), ("cdr_test", "/array_topic"),
    ("services", "/test_topic1"), ("services", "/test_topic2"),
    ("services", "/test_service1/_service_event"), ("services", "/test_service2/_service_event"),
]
# MCAP needs rvc's Rust library: deselected where it is not built (RVC_NO_RUST, conftest.py).
STORAGES = ["sqlite3", pytest.param("mcap", marks=pytest.mark.needs_rust)]


def run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, timeout=120, **kw)


def storage_file(folder):
    return [os.path.join(folder, f) for f in sorted(os.listdir(folder)) if f.endswith((".db3", ".mcap"))][0]


def needs_mcap(rvc, storage):
    if storage == "mcap" and "zenoh" not in transports_built(rvc):  # the MCAP reader lives in the Rust library
        pytest.fail("this rvc was built without its Rust library (RVC_WITH_ZENOH=OFF): no MCAP")


# --- the oracle: rosbags ---------------------------------------------------------------------------

def plain(v):
    """A rosbags message as plain JSON-like values (numpy arrays and scalars unwrapped)."""
    import numpy as np
    import dataclasses
    if dataclasses.is_dataclass(v):
        # Fields only: rosbags lists constants (UPPER_CASE) among them, and gives an empty message
        # its placeholder byte (ROS 2's CDR has it; rvc prints an empty message as {}).
        return {f.name: plain(getattr(v, f.name)) for f in dataclasses.fields(v)
                if not f.name.startswith("__") and not f.name.isupper()
                and f.name != "structure_needs_at_least_one_member"}
    if isinstance(v, np.ndarray):
        return [plain(x) for x in v.tolist()]
    if isinstance(v, (list, tuple)):
        return [plain(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    return v


def typestore_for(folder):
    """Humble's types plus test_msgs, whose definitions rosbags parses from the MCAP twin's records."""
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg
    ts = get_typestore(Stores.ROS2_JAZZY)  # Jazzy: it has service_msgs (service events)
    twin = os.path.join(BAGS, os.path.basename(folder).rsplit("_", 1)[0] + "_mcap")
    with Reader(twin) as r:
        for c in r.connections:
            if c.msgtype.startswith("test_msgs/msg/") and c.msgdef and c.msgdef.data:
                ts.register(get_types_from_msg(c.msgdef.data, c.msgtype))
            elif c.msgtype.startswith("test_msgs/srv/") and c.msgtype.endswith("_Event") and c.msgdef and c.msgdef.data:
                # rosbag2 records a service event topic's .srv text; rosidl's layout of the three
                # types it makes, registered under msg names (rosbags renames pkg/srv/ types).
                base = c.msgtype[len("test_msgs/srv/"):-len("_Event")]
                request, response = c.msgdef.data.split("\n---\n")
                ts.register(get_types_from_msg(request, f"test_msgs/msg/{base}_Request"))
                ts.register(get_types_from_msg(response, f"test_msgs/msg/{base}_Response"))
                ts.register(get_types_from_msg(
                    "service_msgs/msg/ServiceEventInfo info\n"
                    f"test_msgs/msg/{base}_Request[<=1] request\n"
                    f"test_msgs/msg/{base}_Response[<=1] response\n", f"test_msgs/msg/{base}_Event"))
    return ts


def raw_messages(folder, topic):
    """[(log time ns, type, CDR bytes)] of one topic, read independently of rvc. sqlite3: Python's
    sqlite3 module on rosbag2's tables; MCAP: the `mcap` package. (rosbags' own Reader yields no message
    of the talker bags, whose metadata.yaml is version 4.)"""
    if folder.endswith("_sqlite3"):
        con = sqlite3.connect(f"file:{storage_file(folder)}?immutable=1", uri=True)
        rows = con.execute("SELECT m.timestamp, t.type, m.data FROM messages m JOIN topics t ON t.id = m.topic_id "
                           "WHERE t.name = ? ORDER BY m.timestamp, m.id", (topic,)).fetchall()
        con.close()
        return rows
    from mcap.reader import make_reader  # Foxglove's reader: rosbags' yields nothing for talker's version-4 bag
    with open(storage_file(folder), "rb") as f:
        return [(m.log_time, sc.name, m.data) for sc, _, m in make_reader(f).iter_messages(topics=[topic])]


def rosbags_messages(folder, topic):
    """[(log time ns, message as plain values)] of one topic, decoded by rosbags."""
    ts = typestore_for(folder)
    return [(t, plain(ts.deserialize_cdr(raw, msgtype.replace("/srv/", "/msg/"))))
            for t, msgtype, raw in raw_messages(folder, topic)]


def same(a, b, path="$"):
    """rvc's JSON equals rosbags' values: floats to float32 precision, byte/char as numbers."""
    if isinstance(b, bool) or isinstance(a, bool):
        assert a == b, path
    elif isinstance(b, float) or isinstance(a, float):
        if isinstance(a, str) or isinstance(b, str):
            assert str(a).lower().replace("infinity", "inf") == str(b).lower(), (path, a, b)
        elif math.isnan(b):
            assert a is None or (isinstance(a, float) and math.isnan(a)), (path, a, b)
        else:
            assert math.isclose(a, b, rel_tol=1e-6, abs_tol=1e-30), (path, a, b)
    elif isinstance(b, dict):
        assert isinstance(a, dict) and set(a) == set(b), (path, sorted(a), sorted(b))
        for k in b:
            same(a[k], b[k], path + "." + k)
    elif isinstance(b, list):
        assert isinstance(a, list) and len(a) == len(b), (path, a, b)
        for i, (x, y) in enumerate(zip(a, b)):
            same(x, y, f"{path}[{i}]")
    elif isinstance(b, int) and "byte" in path and a != b:
        # ROS 2's byte is an unsigned octet (0..255; Arrays.msg's default [0, 1, 255]); rosbags
        # decodes it as a signed int8. The same bits: equal modulo 256.
        assert isinstance(a, int) and 0 <= a <= 255 and (a - b) % 256 == 0, (path, a, b)
    else:
        assert a == b, (path, a, b)


# --- values: rvc echo against rosbags -----------------------------------------------------------

@pytest.mark.parametrize("storage", STORAGES)
@pytest.mark.parametrize("name,topic", TOPICS)
def test_echo_gives_rosbags_values(rvc, name, topic, storage):
    needs_mcap(rvc, storage)
    folder = os.path.join(BAGS, f"{name}_{storage}")
    want = rosbags_messages(folder, topic)
    assert want, "the oracle read nothing"
    # The folder, the storage file alone, and bag:FILE: the same messages.
    for target in (folder, storage_file(folder), "bag:" + storage_file(folder), "mcap:" + folder):
        r = run([rvc, "echo", target, "--topic", topic, "--msg-path", MSGS])
        assert r.returncode == 0, (target, r.stderr)
        got = [json.loads(line) for line in r.stdout.splitlines()]
        assert len(got) == len(want), (target, len(got), len(want))
        for g, (_, w) in zip(got, want):
            same(g, w)


@pytest.mark.parametrize("storage", STORAGES)
@pytest.mark.parametrize("name", ["talker", "cdr_test", "services"])
def test_bag_info_matches_metadata_and_rosbags(rvc, name, storage):
    needs_mcap(rvc, storage)
    from rosbags.rosbag2 import Reader
    folder = os.path.join(BAGS, f"{name}_{storage}")
    r = run([rvc, "bag", "info", folder, "--json"])
    assert r.returncode == 0, r.stderr
    info = json.loads(r.stdout)
    with Reader(folder) as bag:  # topics, types and counts as metadata.yaml records them
        want = {c.topic: (c.msgtype, c.msgcount) for c in bag.connections}
        assert info["messages"] == bag.message_count
    times = {topic: [t for t, _, _ in raw_messages(folder, topic)] for topic in want}
    assert {k: len(v) for k, v in times.items()} == {k: n for k, (_, n) in want.items()}
    assert info["start_ns"] == min(min(v) for v in times.values() if v)
    assert info["end_ns"] == max(max(v) for v in times.values() if v)
    assert info["storage"] == storage
    assert {t["name"]: (t["type"], t["messages"]) for t in info["topics"]} == want
    for t in info["topics"]:
        ts = times.get(t["name"], [])
        if len(ts) >= 2:
            assert t["first_ns"] == min(ts) and t["last_ns"] == max(ts)
            assert math.isclose(t["frequency_hz"], (len(ts) - 1) / ((max(ts) - min(ts)) * 1e-9), rel_tol=1e-9)
    # The table names every topic with its type and count, as `ros2 bag info` does.
    table = run([rvc, "bag", "info", storage_file(folder)])
    assert table.returncode == 0, table.stderr
    assert f"Storage id:        {storage}" in table.stdout
    for name_, (type_, count) in want.items():
        if count:  # a storage file alone knows the topics that have messages (and, for db3, all)
            assert any(name_ in line and type_ in line and f" {count} " in line for line in table.stdout.splitlines())


# --- check and monitor on the test bags ----------------------------------------------------------

@pytest.mark.parametrize("storage", STORAGES)
def test_check_and_monitor_on_talker(rvc, storage, tmp_path):
    """`rvc check BAG` and `rvc monitor --input bag:BAG` on /rosout: the verdict follows rosbags' levels."""
    needs_mcap(rvc, storage)
    folder = os.path.join(BAGS, f"talker_{storage}")
    levels = [m["level"] for _, m in rosbags_messages(folder, "/rosout")]
    spec = "historically({level <= 20})"
    want_violated = any(lv > 20 for lv in levels)
    c = run([rvc, "check", folder, "--topic", "/rosout", "--msg-path", MSGS, "--spec", spec, "--stats"])
    m = run([rvc, "monitor", "--input", "bag:" + folder, "--topic", "/rosout", "--msg-path", MSGS, "--spec", spec])
    assert c.returncode == m.returncode == (1 if want_violated else 0), (c.stderr, m.stderr)
    assert c.stdout == m.stdout
    counters = json.loads(c.stderr.strip().splitlines()[-1])
    assert counters["received"] == counters["checked"] == len(levels) and counters["rejected"] == 0


def test_talker_db3_stand_in_definition_needs_msg_path(rvc):
    """talker.db3 records `uint8 level` as Log's definition: --msg-path's real one is used instead."""
    db3 = storage_file(os.path.join(BAGS, "talker_sqlite3"))
    with_defs = run([rvc, "echo", db3, "--topic", "/rosout", "--msg-path", MSGS, "--count", "1"])
    assert with_defs.returncode == 0, with_defs.stderr
    assert set(json.loads(with_defs.stdout)) == {"stamp", "level", "name", "msg", "file", "function", "line"}
    # Without it: every sample has bytes left over after `level`, so none is printed as if it were a
    # Log; rvc says the recorded definition may be wrong and how to give the right one.
    for args in (["echo", db3, "--topic", "/rosout"], ["check", db3, "--topic", "/rosout", "--spec", "{level < 30}"]):
        r = run([rvc, *args])
        assert r.returncode == (3 if args[0] == "echo" else 6) and r.stdout == "", (args, r.returncode, r.stderr)
        assert "bytes left over" in r.stderr and "give the type's .msg with --msg-path DIR" in r.stderr, r.stderr


# --- generated twins: a db3 bag and its MCAP twin give identical verdicts ----------------------------

def write_twins(tmp_path, typestore, compression=None):
    from rosbags.rosbag2 import CompressionFormat, StoragePlugin, Writer
    Float64 = typestore.types["std_msgs/msg/Float64"]
    Header = typestore.types["std_msgs/msg/Header"]
    Time = typestore.types["builtin_interfaces/msg/Time"]
    speeds = [1.0, 2.5, 31.0, 4.0, 5.5, 6.0]  # 31.0 violates {speed.data < 30}
    accels = [0.1, 0.2, 0.3]
    bags = {}
    for storage, plugin in (("sqlite3", StoragePlugin.SQLITE3), ("mcap", StoragePlugin.MCAP)):
        path = tmp_path / f"twin_{storage}"
        kw = {"version": 8, "storage_plugin": plugin}
        writer = Writer(path, **kw)
        if compression:
            writer.set_compression(compression, CompressionFormat.ZSTD)
        with writer:
            cs = writer.add_connection("/speed", Float64.__msgtype__, typestore=typestore)
            ca = writer.add_connection("/frame", Header.__msgtype__, typestore=typestore)
            for i, v in enumerate(speeds):
                t = 1_000_000_000 + i * 100_000_000
                writer.write(cs, t, typestore.serialize_cdr(Float64(data=v), Float64.__msgtype__))
                if i < len(accels):
                    h = Header(stamp=Time(sec=1, nanosec=i * 100_000_000 + 50_000_000), frame_id=f"f{i}")
                    writer.write(ca, t + 50_000_000, typestore.serialize_cdr(h, Header.__msgtype__))
        bags[storage] = str(path)
    return bags, speeds


@pytest.fixture
def humble():
    from rosbags.typesys import Stores, get_typestore
    return get_typestore(Stores.ROS2_HUMBLE)


@pytest.mark.needs_rust
@pytest.mark.parametrize("compression", [None, "file", "message"])
def test_db3_and_mcap_twins_give_identical_verdicts(rvc, humble, tmp_path, compression):
    if "zenoh" not in transports_built(rvc):
        pytest.fail("this rvc was built without its Rust library (RVC_WITH_ZENOH=OFF): no MCAP")
    from rosbags.rosbag2 import CompressionMode
    mode = {None: None, "file": CompressionMode.FILE, "message": CompressionMode.MESSAGE}[compression]
    bags, speeds = write_twins(tmp_path, humble, mode)
    start = os.path.getmtime(tmp_path) - 1  # decompressed copies rvc makes are removed: none newer than this
    # Oracle: the same speeds as JSON lines through `rvc check`.
    trace = tmp_path / "speeds.jsonl"
    trace.write_text("".join(json.dumps({"time": i, "data": v}) + "\n" for i, v in enumerate(speeds)))
    spec = "historically({data < 30})"
    want = run([rvc, "check", "--spec", spec, str(trace)])
    assert want.returncode == 1
    outs = {}
    for storage, path in bags.items():
        target = path  # the folder: its metadata.yaml and its (compressed) file
        c = run([rvc, "check", target, "--topic", "/speed", "--spec", spec, "--stats"])
        m = run([rvc, "monitor", "--input", "bag:" + target, "--topic", "/speed", "--spec", spec])
        assert c.returncode == m.returncode == 1, (storage, c.stderr, m.stderr)
        assert c.stdout == m.stdout
        counters = json.loads(c.stderr.strip().splitlines()[-1])
        assert counters["received"] == counters["checked"] + counters["rejected"] == len(speeds)
        # Two synced topics: the merge in log time across them, with the end-of-recording tick.
        s = run([rvc, "check", target, "--topic", "speed=/speed", "--topic", "frame=/frame", "--spec",
                 "historically({speed.data < 30})", "--stats"])
        assert s.returncode == 1, s.stderr
        sc = json.loads(s.stderr.strip().splitlines()[-1])
        dropped = sum(sc["dropped"].values()) if isinstance(sc["dropped"], dict) else sc["dropped"]
        assert sc["received"] == sc["checked"] + sc["rejected"] + dropped
        info = json.loads(run([rvc, "bag", "info", target, "--json"]).stdout)
        assert info["compression_mode"] == (compression or "")
        outs[storage] = (c.stdout, s.stdout)
        if compression == "file":  # the compressed storage file alone (x.db3.zstd, x.mcap.zstd): the same
            alone = [os.path.join(path, f) for f in os.listdir(path) if f.endswith(".zstd")]
            assert len(alone) == 1
            a = run([rvc, "check", alone[0], "--topic", "/speed", "--spec", spec])
            assert a.returncode == 1 and a.stdout == c.stdout, a.stderr
            ai = json.loads(run([rvc, "bag", "info", alone[0], "--json"]).stdout)
            assert (ai["compression_format"], ai["compression_mode"], ai["messages"]) == ("zstd", "file", 9)
            assert not [f for f in os.listdir(os.environ.get("TMPDIR", "/tmp")) if f.startswith("rvc-bag-")
                        and os.path.getmtime(os.path.join(os.environ.get("TMPDIR", "/tmp"), f)) > start]
    assert outs["sqlite3"] == outs["mcap"]
    # Verdict times are the messages' positions in the speed topic: the same as the JSON trace's.
    assert [json.loads(x)["value"] for x in outs["sqlite3"][0].splitlines()] == \
           [json.loads(x)["value"] for x in want.stdout.splitlines()]


@pytest.mark.parametrize("storage", STORAGES)
def test_split_bag_folder_is_merged_in_log_time(rvc, humble, tmp_path, storage):
    """Two storage files of one bag, their messages interleaved in time: read as one, in log-time order."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    Float64 = humble.types["std_msgs/msg/Float64"]
    ext = ".db3" if storage == "sqlite3" else ".mcap"
    plugin = StoragePlugin.SQLITE3 if storage == "sqlite3" else StoragePlugin.MCAP
    parts = []
    for k in range(2):
        p = tmp_path / f"part{k}"
        with Writer(p, version=8, storage_plugin=plugin) as w:
            c = w.add_connection("/x", Float64.__msgtype__, typestore=humble)
            for i in range(k, 10, 2):  # part0: 0,2,4..; part1: 1,3,5..
                w.write(c, 1_000 + i, humble.serialize_cdr(Float64(data=float(i)), Float64.__msgtype__))
        parts.append(p)
    bag = tmp_path / "split"
    bag.mkdir()
    for k, p in enumerate(parts):
        shutil.copy(next(p.glob("*" + ext)), bag / f"split_{k}{ext}")
    import yaml
    md = yaml.safe_load((parts[0] / "metadata.yaml").read_text())
    info = md["rosbag2_bagfile_information"]
    info["relative_file_paths"] = ["split_0" + ext, "split_1" + ext]
    info["message_count"] = 10
    (bag / "metadata.yaml").write_text(yaml.safe_dump(md))
    r = run([rvc, "echo", str(bag), "--topic", "/x"])
    assert r.returncode == 0, r.stderr
    assert [json.loads(x)["data"] for x in r.stdout.splitlines()] == [float(i) for i in range(10)]
    info = json.loads(run([rvc, "bag", "info", str(bag), "--json"]).stdout)
    assert info["messages"] == 10 and len(info["files"]) == 2


# --- refusals: what is not a bag, or not JSON lines ----------------------------------------------

def test_binary_file_where_json_lines_are_expected_is_named(rvc, tmp_path):
    gz = tmp_path / "trace.jsonl.gz"
    gz.write_bytes(b"\x1f\x8b\x08\x00" + bytes(60))
    for args in (["check", "--spec", "{a}", str(gz)], ["monitor", "--spec", "{a}", "--input", "file:" + str(gz)],
                 ["echo", str(gz)]):
        r = run([rvc, *args])
        assert r.returncode == 2, r.stderr
        assert "is a gzip file, not JSON lines" in r.stderr and len(r.stderr.splitlines()) == 1, r.stderr


def test_db3_is_read_as_a_bag_not_as_json(rvc):
    """The issue's first finding: `rvc check talker.db3` printed a wall of "invalid JSON"."""
    db3 = storage_file(os.path.join(BAGS, "talker_sqlite3"))
    r = run([rvc, "check", db3, "--spec", "{true}"])
    assert r.returncode == 2 and "invalid JSON" not in r.stderr, r.stderr
    assert "holds 2 topics: choose one with --topic" in r.stderr and "/rosout (rcl_interfaces/msg/Log, 10" in r.stderr


def test_db3_is_never_modified(rvc, tmp_path):
    src = storage_file(os.path.join(BAGS, "cdr_test_sqlite3"))
    db3 = tmp_path / "ro.db3"
    shutil.copy(src, db3)
    os.chmod(db3, 0o444)
    os.chmod(tmp_path, 0o555)  # nothing may be created beside it either (no journal, no -wal, no -shm)
    try:
        before = db3.read_bytes()
        r = run([rvc, "echo", str(db3), "--topic", "/test_topic"])
        assert r.returncode == 0, r.stderr
        assert db3.read_bytes() == before and sorted(os.listdir(tmp_path)) == ["ro.db3"]
    finally:
        os.chmod(tmp_path, 0o755)


def test_a_fifo_is_read_as_json_lines_not_sniffed(rvc, tmp_path):
    """Telling a bag or a binary file by its first bytes must not eat a pipe's first bytes."""
    fifo = tmp_path / "trace.fifo"
    os.mkfifo(fifo)
    p = subprocess.Popen([rvc, "check", "--spec", "{a}", "--all", str(fifo)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    with open(fifo, "w") as f:
        f.write('{"a": true}\n{"a": false}\n')
    out, err = p.communicate(timeout=60)
    assert p.returncode == 1, err
    assert [json.loads(x)["value"] for x in out.splitlines()] == [True, False]


@pytest.mark.parametrize("storage", STORAGES)
def test_end_of_recording_tick_on_every_storage(rvc, tmp_path, storage):
    """test_clock_end's recording (gear reports 2 until 1.0 s, steering goes on to 3.0 s) as a db3 bag
    and as MCAP: the tick at the recording's end reports once[0:0.5] falling at 1.5 (by hand), through
    `rvc check` and `rvc monitor --input bag:`, the same on both storages."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg
    defs = os.path.join(ROOT, "src", "msg", "definitions")
    gear, steer = "autoware_auto_vehicle_msgs/msg/GearReport", "autoware_auto_vehicle_msgs/msg/SteeringReport"
    ts = get_typestore(Stores.ROS2_HUMBLE)
    for name in (gear, steer):
        with open(os.path.join(defs, name.split("/")[0], "msg", name.split("/")[-1] + ".msg")) as f:
            ts.register(get_types_from_msg(f.read(), name))
    Time = ts.types["builtin_interfaces/msg/Time"]
    t0 = 1_700_000_000 * 10**9
    ns = lambda s: int(round(s * 1e9))  # noqa: E731
    folder = tmp_path / f"silent_gear_{storage}"
    plugin = StoragePlugin.SQLITE3 if storage == "sqlite3" else StoragePlugin.MCAP
    with Writer(folder, version=8, storage_plugin=plugin) as w:
        cg, cs = w.add_connection("/gear", gear, typestore=ts), w.add_connection("/steer", steer, typestore=ts)
        events = [(s, cg, gear, ts.types[gear](stamp=Time(sec=int(s), nanosec=ns(s % 1)), report=r))
                  for s, r in [(0.25, 2), (0.5, 2), (0.75, 2), (1.0, 20)]]
        events += [(s, cs, steer, ts.types[steer](stamp=Time(sec=int(s), nanosec=ns(s % 1)), steering_tire_angle=0.0))
                   for s in [0.5 * k for k in range(1, 7)]]
        for s, conn, name, msg in sorted(events, key=lambda e: e[0]):
            w.write(conn, t0 + ns(s), ts.serialize_cdr(msg, name))
    spec = "once[0:0.5]{report == 2}"
    c = run([rvc, "check", "--dense", "--topic", "/gear", "--spec", spec, str(folder)])
    m = run([rvc, "monitor", "--dense", "--input", f"bag:{folder}", "--topic", "/gear", "--spec", spec])
    want = [(0.25, True), (1.5, False)]  # the timeline starts at the first message (--origin first)
    for r in (c, m):
        assert r.returncode == 1, r.stderr
        assert [(v["time"], v["value"]) for v in map(json.loads, r.stdout.splitlines())] == want


# --- real-size messages: camera frames are read, their pixels stepped over -------------------------

def write_images(folder, typestore, storage, sizes, compression=None):
    """sensor_msgs/Image messages (rgb8) of the given (width, height), written by rosbags."""
    import numpy as np
    from rosbags.rosbag2 import CompressionFormat, StoragePlugin, Writer
    Image, Header = typestore.types["sensor_msgs/msg/Image"], typestore.types["std_msgs/msg/Header"]
    Time = typestore.types["builtin_interfaces/msg/Time"]
    w = Writer(folder, version=8, storage_plugin=StoragePlugin.SQLITE3 if storage == "sqlite3" else StoragePlugin.MCAP)
    if compression:
        w.set_compression(compression, CompressionFormat.ZSTD)
    with w:
        c = w.add_connection("/camera/image_raw", Image.__msgtype__, typestore=typestore)
        for i, (width, height) in enumerate(sizes):
            img = Image(header=Header(stamp=Time(sec=1_700_000_000 + i, nanosec=0), frame_id="cam"), height=height,
                        width=width, encoding="rgb8", is_bigendian=0, step=3 * width,
                        data=np.full(3 * width * height, i, dtype=np.uint8))
            w.write(c, (1_700_000_000 + i) * 10**9, typestore.serialize_cdr(img, Image.__msgtype__))
    return str(folder)


@pytest.mark.parametrize("storage", STORAGES)
@pytest.mark.parametrize("compression", [None, "message"])
def test_camera_frames_are_checked_whole(rvc, humble, tmp_path, storage, compression):
    """Six 1024x768 rgb8 frames (2.4 MB each, over the 1 MiB that JSON lines keep): every one checked
    (typed input is capped at 256 MiB by default), exit 0; --max-message-size below a frame's size
    rejects it, naming its size and the option, and still checks the small frame after it."""
    needs_mcap(rvc, storage)
    from rosbags.rosbag2 import CompressionMode
    mode = {None: None, "message": CompressionMode.MESSAGE}[compression]
    bag = write_images(tmp_path / "camera", humble, storage, [(1024, 768)] * 6 + [(8, 6)], mode)
    frame = 4 + len(humble.serialize_cdr(humble.types["sensor_msgs/msg/Image"](
        header=humble.types["std_msgs/msg/Header"](stamp=humble.types["builtin_interfaces/msg/Time"](sec=0, nanosec=0),
                                                   frame_id="cam"), height=768, width=1024, encoding="rgb8",
        is_bigendian=0, step=3072, data=__import__("numpy").zeros(1024 * 768 * 3, dtype="uint8")),
        "sensor_msgs/msg/Image")) - 4  # the CDR sample's size, as rosbags writes it (header included)
    assert frame > 2_000_000
    spec = 'historically({height <= 768} and {width <= 1024} and {header.frame_id == "cam"} and {step == 3 * width})'
    for args in (["check", bag, "--stats"], ["monitor", "--input", "bag:" + bag]):
        r = run([rvc, *args, "--spec", spec])
        assert r.returncode == 0, (args, r.stderr)
        counters = json.loads(r.stderr.strip().splitlines()[-1])
        assert (counters["received"], counters["checked"], counters["rejected"]) == (7, 7, 0), (args, counters)
        assert json.loads(r.stdout.splitlines()[0])["value"] is True
    small = run([rvc, "check", bag, "--stats", "--spec", spec, "--max-message-size", "1000000"])
    assert small.returncode == 3, small.stderr
    said = (f"message 1 on /camera/image_raw: zstd: its frame declares {frame} bytes decompressed, over the limit "
            "of 1000000 (--max-message-size)") if compression else \
        f"message 1: a sample of {frame} bytes, over the limit of 1000000 bytes for typed input (raise it with " \
        "--max-message-size)"
    assert said in small.stderr, small.stderr
    assert "--msg-path" not in small.stderr  # no hint that the bag's definition is wrong: only the size is
    counters = json.loads(small.stderr.strip().splitlines()[-1])
    assert (counters["received"], counters["checked"], counters["rejected"]) == (7, 1, 6)
