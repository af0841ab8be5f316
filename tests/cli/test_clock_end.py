"""Dense time on a recording's own clock (issue 26): `rvc check --dense` ticks at the recording's
end, so what falls after the last message of the checked topic, before the recording ends, is
reported; `--clock off` keeps the old behaviour (no verdict for the time after the last message).

Oracles: hand-computed instants. The bag is written by rosbags' rosbag2 writer (MCAP storage),
with stamps in simulation time (from 0) and log times in epoch nanoseconds, so the end tick's
instant (last stamp + log time after it) is checked too.
"""
import json

import pytest

from test_mcap import DEFS, GEAR, GEAR_TOPIC, STEER, STEER_TOPIC, run, typestore  # noqa: F401 (fixture)

T0 = 1_700_000_000 * 10**9  # log times: epoch ns


def verdicts(stdout):
    return [(v["property"], v["time"], v["value"]) for v in map(json.loads, stdout.splitlines())]


def write_bag(tmp_path, ts):
    """gear_status: report 2 at stamps 0.25, 0.5, 0.75, then 20 at 1.0, and nothing more;
    steering_status goes on every 0.5 s until 3.0: the recording ends at log time T0 + 3 s."""
    from rosbags.rosbag2 import Writer
    from rosbags.rosbag2.enums import StoragePlugin
    Time = ts.types["builtin_interfaces/msg/Time"]
    folder = tmp_path / "silent_gear"
    ns = lambda s: int(round(s * 1e9))
    with Writer(folder, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        cg = w.add_connection(GEAR_TOPIC, GEAR, typestore=ts)
        cs = w.add_connection(STEER_TOPIC, STEER, typestore=ts)
        events = [(s, cg, GEAR, ts.types[GEAR](stamp=Time(sec=int(s), nanosec=ns(s % 1)), report=r))
                  for s, r in [(0.25, 2), (0.5, 2), (0.75, 2), (1.0, 20)]]
        events += [(s, cs, STEER, ts.types[STEER](stamp=Time(sec=int(s), nanosec=ns(s % 1)), steering_tire_angle=0.0))
                   for s in [0.5 * k for k in range(1, 7)]]
        for s, conn, name, msg in sorted(events, key=lambda e: e[0]):
            w.write(conn, T0 + ns(s), ts.serialize_cdr(msg, name))
    return str(next(folder.glob("*.mcap")))


@pytest.mark.needs_rust  # the MCAP reader is in the Rust library
def test_bag_end_tick_reports_a_fall_after_the_topics_last_message(rvc, tmp_path, typestore):  # noqa: F811
    bag = write_bag(tmp_path, typestore)
    args = [rvc, "check", "--dense", "--topic", GEAR_TOPIC, "--spec", "once[0:0.5]{report == 2}",
            "--spec", "once[0:5]{report == 2}", bag]
    got = run(args)
    assert got.returncode == 1, got.stderr  # p1 falls at 1.5 (the timeline starts at the first message, 0.25)
    # By hand: report 2 holds over [0.25, 1.0); once[0:0.5] falls at 1.0 + 0.5 = 1.5, after the last
    # gear message (1.0) and before the recording's end (stamp 1.0 + 2 s of log time = 3.0).
    # once[0:5] would fall at 6.0, after the recording: not reported.
    assert verdicts(got.stdout) == [("p1", 0.25, True), ("p2", 0.25, True), ("p1", 1.5, False)]
    off = run(args[:2] + ["--clock", "off"] + args[2:])
    # Without the tick the fall is never seen.
    assert verdicts(off.stdout) == [("p1", 0.25, True), ("p2", 0.25, True)]


@pytest.mark.needs_rust  # the MCAP reader is in the Rust library
def test_bag_end_tick_through_rvc_monitor(rvc, tmp_path, typestore):  # noqa: F811
    bag = write_bag(tmp_path, typestore)
    got = run([rvc, "monitor", "--dense", "--input", f"mcap:{bag}", "--topic", GEAR_TOPIC,
               "--spec", "once[0:0.5]{report == 2}"])
    assert ("p1", 1.5, False) in verdicts(got.stdout), got.stderr


def test_json_trace_end_tick_reports_the_last_messages_value(rvc, tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"time": 1, "p": true}\n{"time": 2, "p": false}\n')
    got = run([rvc, "check", "--dense", "--spec", "{p}", str(trace)])
    # From the first message at 1 (the timeline's start): [1, 2) true; at 2, the last message's own value: false.
    assert verdicts(got.stdout) == [("p1", 1, True), ("p1", 2, False)], got.stderr
    off = run([rvc, "check", "--dense", "--clock", "off", "--spec", "{p}", str(trace)])
    assert verdicts(off.stdout) == [("p1", 1, True)]
    # Discrete time has no clock: --clock changes nothing there.
    disc = run([rvc, "check", "--spec", "{p}", str(trace)])
    assert verdicts(disc.stdout) == [("p1", 0, True), ("p1", 1, False)]


def test_monitor_file_input_ticks_at_its_end_like_check(rvc, tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"time": 1, "p": true}\n{"time": 2, "p": false}\n')
    got = run([rvc, "monitor", "--dense", "--spec", "{p}", "--input", f"file:{trace}"])
    chk = run([rvc, "check", "--dense", "--spec", "{p}", str(trace)])
    assert got.stdout == chk.stdout and verdicts(got.stdout)[-1] == ("p1", 2, False), got.stderr


def test_clock_values_are_checked(rvc, tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"time": 1, "p": true}\n')
    bad = run([rvc, "check", "--dense", "--clock", "wall", "--spec", "{p}", str(trace)])
    assert bad.returncode == 2 and "--clock" in bad.stderr
    bad = run([rvc, "monitor", "--dense", "--clock", "sundial", "--spec", "{p}", "--input", f"file:{trace}"])
    assert bad.returncode == 2 and "--clock" in bad.stderr
    bad = run([rvc, "monitor", "--dense", "--tick", "-1", "--spec", "{p}", "--input", f"file:{trace}"])
    assert bad.returncode == 2 and "--tick" in bad.stderr
