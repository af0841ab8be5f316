"""rvc's own Python API (rvc.Monitor, rvc.check_bag): several properties at once, batches,
typed ROS 2 messages from CDR bytes, bags. Oracles: Reelay's package (each property alone,
update by update), rosbags (the CDR bytes and the bags), numpy's own rows, hand-computed values."""
import json
import os
import math
import random
import warnings

import pytest

reelay = pytest.importorskip("reelay")
import rvc  # noqa: E402

from randspec import formula, trace  # noqa: E402


def reelay_changes(pattern, events, **kw):
    """Reelay's condensed discrete verdicts as (step, value)."""
    m = reelay.discrete_timed_monitor(pattern=pattern, **kw)
    out = []
    for step, e in enumerate(events):
        r = m.update(dict(e))
        if r:
            out.append((step, r["value"]))
    return out


@pytest.mark.parametrize("seed", range(10))
def test_several_properties_each_as_reelay_alone(seed):
    rng = random.Random(41000 + seed)
    props = {f"f{i}": formula(rng, rng.randint(1, 4), dense=False) for i in range(8)}
    events = trace(rng, 40, dense=False)
    m = rvc.Monitor(props)
    got = {name: [] for name in props}
    for e in events:
        for v in m.update(e):
            got[v.property].append((v.time, v.value))
    for name, f in props.items():
        assert got[name] == reelay_changes(f, events), f
    assert m.stats["checked"] == len(events) and m.stats["rejected"] == 0


def test_batches_equal_single_updates():
    rng = random.Random(42)
    props = {f"f{i}": formula(rng, 3, dense=False) for i in range(6)}
    events = trace(rng, 200, dense=False)
    one = rvc.Monitor(props, all=True)
    singles = [(i, v.property, v.time, v.value) for i, e in enumerate(events) for v in one.update(e)]
    batch = rvc.Monitor(props, all=True).update_many(events)
    assert [(v.index, v.property, v.time, v.value) for v in batch] == singles


def test_numpy_rows_equal_dicts():
    np = pytest.importorskip("numpy")
    rng = random.Random(43)
    n = 300
    arr = np.zeros(n, dtype=[("speed", "<f8"), ("gear", "<i4"), ("brake", "?"), ("count", "<u2"), ("temp", "<f4")])
    for i in range(n):
        arr[i] = (rng.choice([0, 10.5, 29.9, 30.0, 42.25]), rng.randint(-1, 5), rng.random() < 0.3,
                  rng.randint(0, 70000 % 65536), rng.choice([20.5, 80.25, 99.0]))
    props = {"a": "historically[0:5]({speed < 30})", "b": "{gear == -1} -> {speed <= 10.5}",
             "c": "({brake}) since[1:4] ({temp > 90})", "d": "once{count >= 60000}"}
    from_rows = rvc.Monitor(props).update_many(arr)
    dicts = [{k: arr[k][i].item() for k in arr.dtype.names} for i in range(n)]
    from_dicts = rvc.Monitor(props).update_many(dicts)
    assert from_rows == from_dicts
    for name, f in props.items():  # and Reelay, property by property
        assert [(v.time, v.value) for v in from_rows if v.property == name] == reelay_changes(f, dicts), f


def test_bad_message_in_a_batch_costs_only_itself():
    m = rvc.Monitor({"a": "{x > 1}"}, dense=True)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = m.update_many([{"time": 1, "x": 5}, {"time": 0.5, "x": 0}, {"time": 2, "x": 0}, {"time": 3}])
    assert [str(w.message) for w in caught] == [
        "message 2: time 0.5 is not after the previous message's time 1 (dense time needs strictly increasing times)"
        " (message skipped)"]
    # The timeline starts at the first message (origin="first"): [1,2): 5 > 1; from 2: 0
    assert [(v.index, v.time, v.value) for v in out] == [(2, 1.0, True), (3, 2.0, False)]
    assert m.stats == {"messages": 4, "checked": 3, "rejected": 1, "warnings": 0, "violations": 1}
    # origin="zero" (Reelay's rule): [0,1) has x unset, false
    z = rvc.Monitor({"a": "{x > 1}"}, dense=True, origin="zero")
    out = z.update_many([{"time": 1, "x": 5}, {"time": 2, "x": 0}, {"time": 3}])
    assert [(v.index, v.time, v.value) for v in out] == [(0, 0.0, False), (1, 1.0, True), (2, 2.0, False)]
    with pytest.raises(ValueError, match="origin must be"):
        rvc.Monitor("{x}", dense=True, origin="last")


def test_value_json_cannot_hold_costs_only_its_message():
    m = rvc.Monitor("{p}", all=True)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = m.update_many([{"p": True}, {"p": b"raw"}, {"p": False}])
    assert [str(w.message) for w in caught] == [
        "message 2: field p: a value of type bytes (messages hold bool, int, float, str, None, dict, list)"
        " (message skipped)"]
    assert [(v.index, v.time, v.value) for v in out] == [(0, 0, True), (2, 1, False)]
    with pytest.raises(TypeError, match="bytes"):
        m.update({"p": b"raw"})
    assert m.stats == {"messages": 4, "checked": 2, "rejected": 2, "warnings": 0, "violations": 1}


def test_explain_says_why():
    m = rvc.Monitor({"limit": "historically({x < 3})", "echo": "{p}"}, explain=True)
    assert [v.explanation for v in m.update({"x": 1, "p": True})] == [None, None]
    (v,) = m.update({"x": 5})
    assert (v.property, v.time, v.value) == ("limit", 1, False)
    assert any("{x < 3} is false at step 1" in line for line in v.explanation), v.explanation


def test_robustness_values():
    m = rvc.Monitor({"r": "{y > 0.5}"}, robustness=True, all=True)
    got = [(v.value, v.robustness) for e in ({"y": 2.0}, {"y": 0.25}, {}) for v in m.update(e)]
    assert got == [(True, 1.5), (False, -0.25), (False, -0.25)]  # y - 0.5; a missing y holds


@pytest.fixture
def humble():
    pytest.importorskip("rosbags")
    from rosbags.typesys import Stores, get_typestore
    return get_typestore(Stores.ROS2_HUMBLE)


def twists(rng, n):
    return [(rng.choice([0.0, 0.4, 0.6, 1.5]), rng.choice([-0.2, 0.0, 0.3])) for _ in range(n)]


def test_update_cdr_reads_rosbags_bytes(humble):
    """geometry_msgs/msg/Twist samples serialized by rosbags: the verdicts of their CDR bytes are
    Reelay's on the same values as a flat dict."""
    Twist = humble.types["geometry_msgs/msg/Twist"]
    Vector3 = humble.types["geometry_msgs/msg/Vector3"]
    values = twists(random.Random(44), 60)
    ours = rvc.Monitor({"p": "historically[0:3](({linear.x > 0.5}) -> ({angular.z <= 0}))"})
    got = []
    for step, (lx, az) in enumerate(values):
        msg = Twist(linear=Vector3(x=lx, y=0.0, z=0.0), angular=Vector3(x=0.0, y=0.0, z=az))
        got += [(v.time, v.value) for v in ours.update_cdr("geometry_msgs/msg/Twist",
                                                           humble.serialize_cdr(msg, Twist.__msgtype__))]
    flat = [{"lx": lx, "az": az} for lx, az in values]
    assert got == reelay_changes("historically[0:3](({lx > 0.5}) -> ({az <= 0}))", flat)
    with pytest.raises(ValueError, match="reads geometry_msgs/msg/Twist"):
        ours.update_cdr("std_msgs/msg/Bool", b"\x00\x01\x00\x00\x01")


def write_bag(path, humble, values, storage="sqlite3"):
    from rosbags.rosbag2 import StoragePlugin, Writer
    Float64 = humble.types["std_msgs/msg/Float64"]
    plugin = StoragePlugin.SQLITE3 if storage == "sqlite3" else StoragePlugin.MCAP
    with Writer(path, version=8, storage_plugin=plugin) as w:
        c = w.add_connection("/speed", Float64.__msgtype__, typestore=humble)
        for i, v in enumerate(values):
            w.write(c, 1_000_000_000 + i * 100_000_000, humble.serialize_cdr(Float64(data=v), Float64.__msgtype__))


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_check_bag_verdicts_and_counts(humble, tmp_path, storage):
    if storage == "mcap" and not rvc.has_mcap:
        pytest.skip("this wheel was built without MCAP (RVC_WHEEL_MCAP=0 or no cargo)")
    rng = random.Random(45)
    values = [rng.choice([5.0, 12.5, 29.0, 31.0]) for _ in range(80)]
    write_bag(tmp_path / "drive", humble, values, storage)
    props = {"slow": "{data < 30}", "calm": "historically[0:2]({data < 30}) or once[0:1]({data < 10})"}
    r = rvc.check_bag(tmp_path / "drive", props)
    assert (r.topic, r.type, r.messages, r.received, r.checked, r.rejected) == (
        "/speed", "std_msgs/msg/Float64", 80, 80, 80, 0)
    flat = [{"data": v} for v in values]
    for name, f in props.items():
        assert [(v.time, v.value) for v in r.verdicts if v.property == name] == reelay_changes(f, flat), f
    assert r.violated and r.exit_code == 1
    pd = pytest.importorskip("pandas")
    df = r.to_dataframe()
    assert isinstance(df, pd.DataFrame) and len(df) == len(r.verdicts)
    assert list(df[df.property == "slow"].value) == [v.value for v in r.verdicts if v.property == "slow"]


def test_check_bag_errors_name_the_problem(humble, tmp_path):
    write_bag(tmp_path / "b", humble, [1.0])
    with pytest.raises(ValueError, match="/nope"):
        rvc.check_bag(tmp_path / "b", "{data < 30}", topic="/nope")
    with pytest.raises(ValueError, match="column"):
        rvc.check_bag(tmp_path / "b", "{data < }")


def test_camera_frames_and_the_size_cap(humble, tmp_path):
    """A 1024x768 rgb8 Image (2.4 MB CDR, over JSON's 1 MiB): update_cdr and check_bag check it by
    default (typed input is capped at 256 MiB); max_message_size= below its size refuses it,
    naming its size and the option; a cap outside 1 byte..1 GiB is a ValueError."""
    import numpy as np
    from rosbags.rosbag2 import StoragePlugin, Writer
    Image, Header = humble.types["sensor_msgs/msg/Image"], humble.types["std_msgs/msg/Header"]
    Time = humble.types["builtin_interfaces/msg/Time"]
    img = Image(header=Header(stamp=Time(sec=1, nanosec=0), frame_id="cam"), height=768, width=1024,
                encoding="rgb8", is_bigendian=0, step=3072, data=np.zeros(1024 * 768 * 3, dtype=np.uint8))
    cdr = bytes(humble.serialize_cdr(img, Image.__msgtype__))
    assert len(cdr) > 2_000_000
    spec = '{height == 768} and {width == 1024} and {header.frame_id == "cam"}'
    m = rvc.Monitor(spec, type="sensor_msgs/msg/Image")
    assert [v.value for v in m.update_cdr("sensor_msgs/msg/Image", cdr)] == [True]
    capped = rvc.Monitor(spec, type="sensor_msgs/msg/Image", max_message_size=1_000_000)
    with pytest.raises(ValueError, match=f"a sample of {len(cdr)} bytes, over the limit of 1000000 bytes.*"
                                         "--max-message-size"):
        capped.update_cdr("sensor_msgs/msg/Image", cdr)
    for bad in (0, -1, (1 << 30) + 1, 1.5, True):
        with pytest.raises(ValueError, match="max_message_size"):
            rvc.Monitor(spec, max_message_size=bad)
    with Writer(tmp_path / "camera", version=8, storage_plugin=StoragePlugin.SQLITE3) as w:
        c = w.add_connection("/camera", Image.__msgtype__, typestore=humble)
        for i in range(3):
            w.write(c, 1_000_000_000 + i, cdr)
    r = rvc.check_bag(tmp_path / "camera", spec)
    assert (r.received, r.checked, r.rejected, r.exit_code) == (3, 3, 0, 0)
    r = rvc.check_bag(tmp_path / "camera", spec, max_message_size=1_000_000)
    assert (r.received, r.checked, r.rejected) == (3, 0, 3) and f"a sample of {len(cdr)} bytes" in r.errors[0]


AUTOWARE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "shared", "data", "autoware-bags",
                        "bag_ego_trajectory_turn-right.db3")


def test_check_bag_on_a_real_autoware_recording_holds_from_its_first_stamp():
    # Epoch-stamped nav_msgs/Odometry (issue 36): a dense property that holds is reported as holding,
    # at the first message's stamp (rosbags' reading of it: 1703219718.026702445 s), not violated at 0.
    assert os.path.exists(AUTOWARE), f"{AUTOWARE}: the shared Autoware recording is this test's data"
    r = rvc.check_bag(AUTOWARE, {"sane": "historically({twist.twist.linear.x < 1000})"}, dense=True)
    assert (r.checked, r.rejected, r.exit_code) == (2819, 0, 0), r.errors
    assert [(v.time, v.value) for v in r.verdicts] == [(1703219718.026702445, True)]
    assert not r.violated
