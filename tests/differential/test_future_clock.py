"""Bounded future on a clock (issue 29, dense time): a delayed verdict is settled at its deadline
even if no message comes, as a runtime ticking at next_deadline() does (docs/cli.md, "Clocks").

The engine alone, driven by rvc_tick_driver --deadlines (tests/differential/tick_driver.cpp), the
harness test_clock_differential.py uses. Oracle: hand-computed instants.
"""
import json
import subprocess

from test_clock_differential import driver  # noqa: F401 (fixture)


def run(driver, spec, lines):  # noqa: F811
    text = "".join((l if isinstance(l, str) else json.dumps(l)) + "\n" for l in lines)
    proc = subprocess.run([driver, "--deadlines", spec], input=text, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return [json.loads(l) for l in proc.stdout.splitlines()]


def test_missing_ack_is_reported_at_the_deadline_without_a_message(driver):  # noqa: F811
    # req on [0, 0.2), no ack ever; the next line is a tick at 5 (nothing else comes before it).
    out = run(driver, "{req} -> eventually[0:1]{ack}",
              [{"time": 0, "req": True, "ack": False}, {"time": 0.2, "req": False, "ack": False}, "tick 5"])
    # The request at 0 had until 1 for its ack: the tick at the deadline 1 reports it violated, for time 0;
    # from 0.2 on no request is pending (known at 1.2, the next deadline).
    assert out == [{"tick": 1}, {"property": "f0", "time": 0, "known_at": 1, "value": False},
                   {"tick": 1.2}, {"property": "f0", "time": 0.2, "known_at": 1.2, "value": True}]


def test_ack_in_time_is_no_violation(driver):  # noqa: F811
    out = run(driver, "{req} -> eventually[0:1]{ack}",
              [{"time": 0, "req": True, "ack": False}, {"time": 0.2, "req": False, "ack": False},
               {"time": 0.5, "req": False, "ack": True}, {"time": 0.6, "req": False, "ack": False}, "tick 5"])
    verdicts = [o for o in out if "property" in o]
    assert verdicts == [{"property": "f0", "time": 0, "known_at": 1, "value": True}]
    assert {"tick": 1} in out  # the verdict for 0 waited for its horizon, not for a message
