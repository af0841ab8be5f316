"""Clock ticks in dense time (engine::Checker::tick, next_deadline) against Reelay 25 (PyPI `reelay`).

A tick is an empty message: every field holds. So rvc ticking at some instants must give exactly
the verdicts Reelay's dense monitor gives on the same trace with heartbeat messages (no fields)
inserted at those instants, and exactly what rvc itself gives on that heartbeat trace. The ticks
are made by rvc_tick_driver (tests/differential/tick_driver.cpp: the engine alone, as the runtime
will drive it): at random instants, or where next_deadline() says (a runtime sleeping between
messages). Reelay also gets the heartbeats every 0.25 of test_reelay_differential.py, where it is
exact. Deadlines must be exact or early: every change after the first message is reported by a
tick at its own instant.
"""
import json
import os
import random
import subprocess

import pytest

reelay = pytest.importorskip("reelay")

from randspec import formula, trace, write_jsonl
from test_reelay_differential import condense, describe, with_heartbeats

CASES = int(os.environ.get("RVC_DIFF_CASES", "60"))
FORMULAS_PER_CASE = 12


@pytest.fixture(scope="session")
def driver():
    path = os.environ.get("RVC_TICK_DRIVER")
    if not path and os.environ.get("RVC_BIN"):
        path = os.path.join(os.path.dirname(os.environ["RVC_BIN"]), "tests", "rvc_tick_driver")
    if not path or not os.path.exists(path):
        pytest.skip("rvc_tick_driver not built (cmake --build ... --target rvc_tick_driver)")
    return path


def run_driver(driver, formulas, lines, deadlines=False, robustness=False):
    """(verdicts per formula, the ticks made at deadlines)."""
    args = [driver] + (["--deadlines"] if deadlines else []) + (["--robustness"] if robustness else []) + formulas
    text = "".join((l if isinstance(l, str) else json.dumps(l)) + "\n" for l in lines)
    proc = subprocess.run(args, input=text, capture_output=True, text=True)
    assert proc.returncode == 0, f"rvc_tick_driver failed ({proc.returncode}): {proc.stderr}"
    out = {f"f{i}": [] for i in range(len(formulas))}
    ticks = []
    for line in proc.stdout.splitlines():
        v = json.loads(line)
        if "tick" in v:
            ticks.append(v["tick"])
        else:
            value = v["value"]
            if isinstance(value, str):
                value = float(value)
            out[v["property"]].append((v["time"], value))
    return out, ticks


def random_ticks(rng, events):
    """A few instants strictly between messages (multiples of 1/1024: exact sums), none before the first."""
    out = []
    for e, nxt in zip(events, events[1:]):
        for _ in range(rng.choice([0, 0, 1, 2, 3])):
            t = round(rng.uniform(e["time"], nxt["time"]) * 1024) / 1024
            if e["time"] < t < nxt["time"]:
                out.append(t)
    return sorted(set(out))


def merged(events, instants, as_line):
    """The messages with `as_line(t)` inserted at each instant (none equal to a message's time)."""
    times = {e["time"] for e in events}
    lines = [(e["time"], 1, e) for e in events] + [(t, 0, as_line(t)) for t in instants if t not in times]
    return [l for _, _, l in sorted(lines, key=lambda x: (x[0], x[1]))]


def reelay_verdicts(f, events, heartbeats, robustness=False):
    probed = merged(with_heartbeats(events), heartbeats, lambda t: {"time": t})
    kwargs = {"semantics": "robustness"} if robustness else {}
    m = reelay.dense_timed_monitor(pattern=f, **kwargs)
    out = []
    for e in probed:
        out += [(r["time"], float(r["value"]) if robustness else r["value"]) for r in m.update(dict(e))]
    return condense(out)


def case(seed):
    rng = random.Random(9100 + seed)
    formulas = [formula(rng, rng.randint(1, 4), dense=True) for _ in range(FORMULAS_PER_CASE)]
    events = trace(rng, rng.randint(10, 30), dense=True)
    return rng, formulas, events


def before(changes, end):
    """Reelay reports nothing after the last message; ticks there are not made."""
    return [c for c in changes if c[0] < end]


@pytest.mark.parametrize("seed", range(CASES))
def test_ticks_at_random_instants_match_reelay_with_heartbeats_there(driver, seed):
    rng, formulas, events = case(seed)
    ticks = random_ticks(rng, events)
    ours, _ = run_driver(driver, formulas, merged(events, ticks, lambda t: f"tick {t!r}"))
    for i, f in enumerate(formulas):
        theirs = reelay_verdicts(f, events, ticks)
        mine = before(condense(ours[f"f{i}"]), events[-1]["time"])
        assert mine == theirs, describe(f, events, mine, theirs) + f"\nticks: {ticks}"


@pytest.mark.parametrize("seed", range(CASES))
def test_ticks_at_deadlines_match_reelay_and_come_at_every_change(driver, seed):
    _, formulas, events = case(seed)
    ours, ticks = run_driver(driver, formulas, events, deadlines=True)
    assert ticks == sorted(ticks)
    first, last = events[0]["time"], events[-1]["time"]
    for i, f in enumerate(formulas):
        theirs = reelay_verdicts(f, events, ticks)
        mine = before(condense(ours[f"f{i}"]), last)
        assert mine == theirs, describe(f, events, mine, theirs) + f"\ndeadline ticks: {ticks}"
        # Never late: each change from the first message on was a deadline, where a tick reported it.
        late = [t for t, _ in theirs if first <= t < last and t not in ticks]
        assert not late, f"formula: {f}\nchanges at {late} were no deadline\nticks: {ticks}\ntrace: {json.dumps(events)}"


@pytest.mark.parametrize("seed", range(CASES))
def test_ticks_equal_heartbeat_messages_in_rvc(rvc, driver, tmp_path, seed):
    """The engine ticking vs `rvc check --dense` reading empty messages at the same instants."""
    rng, formulas, events = case(seed)
    ticks = random_ticks(rng, events)
    ours, _ = run_driver(driver, formulas, merged(events, ticks, lambda t: f"tick {t!r}"))
    props = tmp_path / "props.json"
    props.write_text(json.dumps({"properties": [{"name": f"f{i}", "spec": f} for i, f in enumerate(formulas)]}))
    tr = tmp_path / "trace.jsonl"
    write_jsonl(tr, merged(events, ticks, lambda t: {"time": t}))
    # --clock off: no tick at the trace's end (it would add the last message's own value, which the
    # driver, ticking only between messages, does not report; test_check_ticks_at_the_end covers it).
    proc = subprocess.run([rvc, "check", "--dense", "--origin", "zero", "--clock", "off", "--properties", str(props), str(tr)],
                          capture_output=True, text=True)
    assert proc.returncode in (0, 1), proc.stderr
    beats = {f"f{i}": [] for i in range(len(formulas))}
    for line in proc.stdout.splitlines():
        v = json.loads(line)
        beats[v["property"]].append((v["time"], v["value"]))
    for i, f in enumerate(formulas):
        assert before(ours[f"f{i}"], events[-1]["time"]) == beats[f"f{i}"], f"formula: {f}\nticks: {ticks}"


@pytest.mark.parametrize("seed", range(CASES // 2))
def test_robustness_ticks_at_deadlines_match_reelay(driver, seed):
    from test_robustness_differential import add_real_field, leading_zero_dropped, robust_formulas
    rng = random.Random(9300 + seed)
    formulas = [robust_formulas(rng, rng.randint(1, 4), dense=True)[0] for _ in range(FORMULAS_PER_CASE)]
    events = trace(rng, rng.randint(10, 30), dense=True)
    add_real_field(rng, events)
    ours, ticks = run_driver(driver, formulas, events, deadlines=True, robustness=True)
    first, last = events[0]["time"], events[-1]["time"]
    for i, f in enumerate(formulas):
        theirs = leading_zero_dropped(reelay_verdicts(f, events, ticks, robustness=True))
        mine = leading_zero_dropped(before(condense(ours[f"f{i}"]), last))
        assert mine == theirs, f"formula: {f}\nrvc:    {mine}\nreelay: {theirs}\nticks: {ticks}\ntrace: {json.dumps(events)}"
        late = [t for t, _ in theirs if first <= t < last and t not in ticks]
        assert not late, f"formula: {f}\nchanges at {late} were no deadline\nticks: {ticks}\ntrace: {json.dumps(events)}"
