"""Timing atoms and aggregates on the command line: spec errors name the column (exit 2), and a
JSON-lines file with a gap is checked like the bag (tests/cli/test_timed_bag.py), hand-computed."""
import json
import subprocess


def run(rvc, *args, stdin=None):
    return subprocess.run([rvc, *args], input=stdin, capture_output=True, text=True, timeout=60)


def caret_column(stderr):
    """The column the caret line points at (1-based)."""
    lines = stderr.splitlines()
    caret = next(line for line in lines if line.strip() == "^")
    return len(caret) - len("  ^") + 1


def test_bad_timing_syntax_points_at_the_column(rvc):
    for args, spec, column, words in [
        (["--dense"], "once[0:1]{count[0:1(@arrived) >= 2}", 20, "expected ']'"),
        (["--dense"], "{count[0:1](@arrived) >= }", 26, "expected a value"),
        (["--dense"], "{sum[0:1](@arrived) > 2}", 11, "arrivals are counted"),
        (["--dense"], "{p} and {@arrived}", 10, "an arrival is an instant"),
        (["--dense"], "{@age}", 6, "compare it"),
        ([], "{@latency < 1}", 2, "needs dense time"),
        (["--dense", "--robustness"], "{@age < 1}", 2, "--robustness"),
        (["--dense"], "{imu.@age < 1}", 2, "names an input"),
    ]:
        r = run(rvc, "check", *args, "--spec", spec, "-", stdin="")
        assert r.returncode == 2, (spec, r.stderr)
        assert words in r.stderr and caret_column(r.stderr) == column, (spec, r.stderr)


def test_a_gap_in_a_file_is_reported_where_it_starts(rvc, tmp_path):
    # messages every 0.25 s, none between 1.0 and 2.0: {@age <= 0.5} is false on [1.5, 2.0)
    times = [0, 0.25, 0.5, 0.75, 1.0, 2.0, 2.25]
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(f'{{"time": {t}, "x": {i}}}\n' for i, t in enumerate(times)))
    r = run(rvc, "check", "--dense", "--spec", "{@age <= 0.5}", str(trace))
    assert r.returncode == 1, r.stderr
    assert r.stdout.splitlines() == ['{"time":0,"property":"p1","value":true}',
                                     '{"time":1.5,"property":"p1","value":false}',
                                     '{"time":2,"property":"p1","value":true}'], r.stdout
    # discrete: sum of x over the last two steps (steps t-1, t), x = 0, 1, 2, ...
    r = run(rvc, "check", "--all", "--spec", "{sum[0:1](x) >= 5}", str(trace))
    assert [line.endswith("true}") for line in r.stdout.splitlines()] == [False, False, False, True, True, True, True]


def test_robustness_of_aggregates_is_value_minus_threshold(rvc, tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(f'{{"time": {t}, "x": {i}}}\n' for i, t in enumerate([0, 0.25, 0.5, 1.5])))
    # discrete: sum of the last two steps' x (0, 1, 3, 5) minus 5
    r = run(rvc, "check", "--robustness", "--all", "--spec", "{sum[0:1](x) >= 5}", str(trace))
    assert [json.loads(line)["value"] for line in r.stdout.splitlines()] == [-5, -4, -2, 0], r.stderr
    # dense: max over (t-0.5, t]: 0 on [0,0.25), 1 on [0.25,0.5), 2 on [0.5,1), empty on [1,1.5): -inf,
    # and 3 from the last message at 1.5 (told by the end-of-input tick, docs/cli.md "Clocks")
    r = run(rvc, "check", "--robustness", "--dense", "--spec", "{max[0:0.5](x) > 1}", str(trace))
    assert [(json.loads(line)["time"], json.loads(line)["value"]) for line in r.stdout.splitlines()] == \
        [(0, -1), (0.25, 0), (0.5, 1), (1, "-inf"), (1.5, 2)], r.stdout
