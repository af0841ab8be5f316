"""--output mcap:PATH: verdicts as rvc_msgs/msg/Verdict in a ROS 2 MCAP file (docs/mcap-output.md).

Oracles: the `mcap` package from PyPI (Foxglove's reader: records, summary, CRCs) and rosbags
(AnyReader with an empty typestore: the type comes only from the ros2msg schema in the file, the
samples are deserialized by rosbags' own CDR code). The verdicts must equal the JSON lines that
`--output file:` writes in the same run; their log times are the times of the steps they are about
(dense: the verdict's time; a bag: the log time of the message at that step).
"""
import json
import os
import signal
import subprocess
import time

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEFS = os.path.join(ROOT, "src", "msg", "definitions")
GEAR = "autoware_auto_vehicle_msgs/msg/GearReport"
GEAR_TOPIC = "/vehicle/status/gear_status"


def run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, timeout=120, **kw)


def check_crcs(path):
    """The data section's CRC (checked by the mcap package's stream reader) and the summary's CRC in
    the Footer (checked here with zlib: the package does not check that one)."""
    import struct
    import zlib
    from mcap.records import DataEnd
    from mcap.stream_reader import StreamReader
    with open(path, "rb") as f:
        ends = [r for r in StreamReader(f, validate_crcs=True).records if isinstance(r, DataEnd)]
    assert len(ends) == 1 and ends[0].data_section_crc != 0
    data = open(path, "rb").read()
    footer = data[-37:-8]
    assert footer[:9] == b"\x02" + struct.pack("<Q", 20)
    summary_start, offsets_start, crc = struct.unpack("<QQI", footer[9:])
    assert 0 < summary_start < offsets_start < len(data) - 37
    assert crc == zlib.crc32(data[summary_start:len(data) - 12])


def read_mcap(path):
    """(header, summary, [(topic, log_time, publish_time, sequence, data)]) through the mcap package,
    every CRC the file carries checked."""
    from mcap.reader import make_reader
    check_crcs(path)
    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        header, summary = reader.get_header(), reader.get_summary()
        msgs = [(c.topic, m.log_time, m.publish_time, m.sequence, m.data) for _, c, m in reader.iter_messages()]
    return header, summary, msgs


def read_rosbags(path):
    """[(topic, log_time, message)] through rosbags, with the type taken from the file's schema only."""
    from pathlib import Path
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore
    out = []
    with AnyReader([Path(path)], default_typestore=get_typestore(Stores.EMPTY)) as reader:
        for conn, t, raw in reader.messages():
            out.append((conn.topic, conn.msgtype, t, reader.deserialize(raw, conn.msgtype)))
    return out


def json_lines(text):
    return [json.loads(l) for l in text.splitlines() if l.strip()]


def assert_equal_verdicts(mcap_path, jsonl_text, log_times):
    """The MCAP file holds exactly the JSON verdicts, each at its log time, in both readers."""
    want = json_lines(jsonl_text)
    assert want, "the run gave no verdict"
    header, summary, msgs = read_mcap(mcap_path)
    assert header.profile == "ros2"
    (schema,) = summary.schemas.values()
    assert (schema.name, schema.encoding) == ("rvc_msgs/msg/Verdict", "ros2msg")
    (channel,) = summary.channels.values()
    assert (channel.topic, channel.message_encoding) == ("/rvc/verdicts", "cdr")
    assert summary.statistics.message_count == len(want) == len(msgs)
    assert [m[1] for m in msgs] == log_times
    assert [m[3] for m in msgs] == list(range(1, len(want) + 1))
    got = read_rosbags(mcap_path)
    assert [(g[0], g[1], g[2]) for g in got] == [("/rvc/verdicts", "rvc_msgs/msg/Verdict", t) for t in log_times]
    for (_, _, t, v), w in zip(got, want):
        assert (v.time, v.property) == (w["time"], w["property"])
        assert (v.stamp.sec, v.stamp.nanosec) == divmod(t, 10**9)
        assert list(v.explanation) == w.get("explain", [])
        if isinstance(w["value"], bool):
            assert v.value is w["value"] and v.robustness != v.robustness  # NaN: a Boolean verdict
        else:
            r = {"inf": float("inf"), "-inf": float("-inf")}.get(w["value"], w["value"])
            assert v.robustness == r and v.value is (r > 0)
    return got


TRACE = [{"time": 0.0, "x": 1}, {"time": 0.25, "x": 2}, {"time": 1.5, "x": 7}, {"time": 2.0, "x": 1},
         {"time": 3.125, "x": 4}, {"time": 4.0, "x": 0}]


@pytest.mark.parametrize("mode", [[], ["--dense"], ["--dense", "--robustness"], ["--robustness"], ["--explain"]])
def test_verdicts_equal_the_json_lines_of_the_same_run(rvc, tmp_path, mode):
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(json.dumps(r) + "\n" for r in TRACE))
    out, mc = tmp_path / "v.jsonl", tmp_path / "v.mcap"
    spec = "{x < 5} since[0:2] {x < 2}"
    r = run([rvc, "monitor", "--all", *mode, "--spec", spec, "--spec", "historically({x < 6})",
             "--input", f"file:{trace}", "--output", f"file:{out}", "--output", f"mcap:{mc}"])
    assert r.returncode == 1, r.stderr  # x = 7 violates the second property
    want = json_lines(out.read_text())
    dense = "--dense" in mode
    # Dense time: the verdict's time in seconds; discrete: the step index (as nanoseconds).
    log_times = [round(w["time"] * 1e9) if dense else int(w["time"]) for w in want]
    got = assert_equal_verdicts(mc, out.read_text(), log_times)
    assert {g[3].property for g in got} == {"p1", "p2"}
    # rvc check -o mcap: writes the same file content as the monitor's output.
    mc2 = tmp_path / "check.mcap"
    c = run([rvc, "check", "--all", *mode, "--spec", spec, "--spec", "historically({x < 6})", str(trace),
             "-o", f"mcap:{mc2}"])
    assert c.returncode == 1 and c.stdout == "", c.stderr
    assert mc2.read_bytes() == mc.read_bytes()


@pytest.mark.needs_rust  # reads a bag (the MCAP reader is rvc's Rust library)
def test_bag_verdicts_sit_at_their_messages_log_times(rvc, tmp_path):
    """A verdict about step k of a bag's topic is placed at that message's log time, so Foxglove shows
    it beside the message on the bag's timeline."""
    from rosbags.rosbag2 import Writer
    from rosbags.rosbag2.enums import StoragePlugin
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg
    ts = get_typestore(Stores.ROS2_HUMBLE)
    with open(os.path.join(DEFS, "autoware_auto_vehicle_msgs", "msg", "GearReport.msg")) as f:
        ts.register(get_types_from_msg(f.read(), GEAR))
    Time = ts.types["builtin_interfaces/msg/Time"]
    reports = [2, 2, 20, 22, 20, 2, 1, 22, 2, 20]
    times = [1_700_000_000 * 10**9 + i * 137_000_000 + (i * i) * 1000 for i in range(len(reports))]
    with Writer(tmp_path / "drive", version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conn = w.add_connection(GEAR_TOPIC, GEAR, typestore=ts)
        for t, rep in zip(times, reports):
            msg = ts.types[GEAR](stamp=Time(sec=t // 10**9, nanosec=t % 10**9), report=rep)
            w.write(conn, t, ts.serialize_cdr(msg, GEAR))
    (bag,) = (tmp_path / "drive").glob("*.mcap")
    spec = "{report == REVERSE} -> pre {report == PARK}"
    jl, mc = tmp_path / "v.jsonl", tmp_path / "v.mcap"
    r = run([rvc, "check", "--all", "--spec", spec, str(bag), "--topic", GEAR_TOPIC, "-o", str(jl)])
    m = run([rvc, "check", "--all", "--spec", spec, str(bag), "--topic", GEAR_TOPIC, "-o", f"mcap:{mc}"])
    assert r.returncode == m.returncode == 1, (r.stderr, m.stderr)
    want = json_lines(jl.read_text())
    assert len(want) == len(reports)
    assert_equal_verdicts(mc, jl.read_text(), [times[int(w["time"])] for w in want])
    # ?inputs=1: the bag's messages too, byte-equal, at their log times, with the bag's schema.
    both = tmp_path / "both.mcap"
    b = run([rvc, "check", "--all", "--spec", spec, str(bag), "--topic", GEAR_TOPIC, "-o", f"mcap:{both}?inputs=1"])
    assert b.returncode == 1 and not (tmp_path / "both.mcap?inputs=1").exists(), b.stderr
    from mcap.reader import make_reader
    with open(bag, "rb") as f:
        reader = make_reader(f)
        (bag_schema,) = reader.get_summary().schemas.values()
        bag_msgs = [(m.log_time, m.data) for _, _, m in reader.iter_messages()]
    _, summary, msgs = read_mcap(both)
    copied = [(m[1], m[4]) for m in msgs if m[0] == GEAR_TOPIC]
    assert copied == bag_msgs and len(copied) == len(reports)
    schema = next(s for s in summary.schemas.values() if s.name == GEAR)
    assert (schema.encoding, schema.data) == (bag_schema.encoding, bag_schema.data)
    verdicts_only = [m for m in msgs if m[0] == "/rvc/verdicts"]
    assert verdicts_only == read_mcap(mc)[2]
    # rosbags reads both topics from the one file: the data and its verdicts on one timeline.
    got = read_rosbags(both)
    gears = [(t, g.report) for topic, _, t, g in got if topic == GEAR_TOPIC]
    assert gears == list(zip(times, reports))
    assert [t for topic, _, t, _ in got] == sorted(t for topic, _, t, _ in got)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_stopped_run_leaves_a_valid_file(rvc, tmp_path, sig):
    """rvc check - reading a pipe that stays open, stopped by a signal: the summary and footer are
    written at shutdown, and the file holds every verdict of what was read."""
    mc = tmp_path / "v.mcap"
    rows = "".join(json.dumps(r) + "\n" for r in TRACE[:4])
    p = subprocess.Popen([rvc, "check", "--all", "--spec", "historically({x < 8})", "-", "-o", f"mcap:{mc}"],
                         stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        p.stdin.write(rows.encode())
        p.stdin.flush()
        # Wait (bounded) until the fourth verdict is in the file: each Message record is flushed
        # while the input is quiet, and the last verdict has its step index 3 as its log time.
        record_end = None
        for _ in range(400):
            data = mc.read_bytes() if mc.exists() else b""
            if data.count(b"\x05") and data.find(b"/rvc/verdicts") > 0:
                record_end = data
                if data.count(b"p1") >= 4:
                    break
            time.sleep(0.025)
        assert record_end is not None and record_end.count(b"p1") >= 4, "no verdicts were written"
        p.send_signal(sig)
        _, err = p.communicate(timeout=30)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 6, err  # incomplete: the input was cut
    jl = tmp_path / "v.jsonl"
    run([rvc, "check", "--all", "--spec", "historically({x < 8})", "-", "-o", str(jl)], input=rows)
    assert_equal_verdicts(mc, jl.read_text(), [0, 1, 2, 3])


def test_never_writes_over_a_file_rvc_did_not_create(rvc, tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(json.dumps(r) + "\n" for r in TRACE))
    foreign = tmp_path / "recording.mcap"
    foreign.write_bytes(b"someone else's bytes")
    r = run([rvc, "check", "--spec", "{x < 5}", str(trace), "-o", f"mcap:{foreign}"])
    assert r.returncode == 2 and "rvc did not write it" in r.stderr, r.stderr
    assert foreign.read_bytes() == b"someone else's bytes"
    # Its own file (marked) is written over by a second run.
    own = tmp_path / "own.mcap"
    for _ in range(2):
        r = run([rvc, "check", "--spec", "{x < 5}", str(trace), "-o", f"mcap:{own}"])
        assert r.returncode == 1, r.stderr
    assert read_mcap(own)[1].statistics.message_count == 3  # true, false at x = 7, true again
    # ?inputs=1 copies a bag's messages: with JSON lines nothing would be copied, so it is refused.
    for cmd in ([rvc, "check", "--spec", "{x < 5}", str(trace), "-o", f"mcap:{tmp_path / 'in.mcap'}?inputs=1"],
                [rvc, "monitor", "--spec", "{x < 5}", "--input", f"file:{trace}", "--output",
                 f"mcap:{tmp_path / 'in.mcap'}?inputs=1"]):
        r = run(cmd)
        assert r.returncode == 2 and "copies the messages of a ROS 2 bag" in r.stderr, r.stderr
        assert not (tmp_path / "in.mcap").exists()
    # Reading a file and writing verdicts over it is refused.
    r = run([rvc, "monitor", "--spec", "{x < 5}", "--input", f"file:{trace}", "--output", f"mcap:{trace}"])
    assert r.returncode == 2, r.stderr
    assert trace.read_text().startswith('{"time"')
