"""rvc's verdicts equal Reelay 25's (PyPI `reelay`) at every step / time point.

Each case: a seeded batch of random formulas, one random trace, all formulas
checked by one `rvc check` run (a properties file) and by Reelay one by one.
On failure the formula, trace and first differing step are printed, so a case
can be replayed by hand.
"""
import json
import os
import random
import subprocess

import pytest

reelay = pytest.importorskip("reelay")

from randspec import formula, trace, write_jsonl

CASES = int(os.environ.get("RVC_DIFF_CASES", "60"))
FORMULAS_PER_CASE = 12


def run_rvc(rvc, tmp_path, formulas, events, dense):
    props = tmp_path / "props.json"
    props.write_text(json.dumps({"properties": [{"name": f"f{i}", "spec": f} for i, f in enumerate(formulas)]}))
    tr = tmp_path / "trace.jsonl"
    write_jsonl(tr, events)
    args = [rvc, "check", "--properties", str(props), str(tr)]
    args += ["--dense", "--origin", "zero"] if dense else ["--all"]

    def verdicts(extra):
        proc = subprocess.run(args + extra, capture_output=True, text=True)
        assert proc.returncode in (0, 1), f"rvc failed ({proc.returncode}): {proc.stderr}"
        out = {f"f{i}": [] for i in range(len(formulas))}
        for line in proc.stdout.splitlines():
            v = json.loads(line)
            out[v["property"]].append((v["time"], v["value"]))
        return out
    if not dense:
        return verdicts([])
    # Dense: by default `rvc check` ticks at the trace's end, which reports the last message's own
    # value; Reelay reports nothing for that instant, so the comparison uses --clock off. The tick
    # may add verdicts at the last message's time and must change nothing else.
    off, ticked = verdicts(["--clock", "off"]), verdicts([])
    last = events[-1]["time"]
    for name in off:
        assert [v for v in ticked[name] if v[0] != last] == [v for v in off[name] if v[0] != last], name
    return off


def condense(changes):
    out = []
    for t, v in changes:
        if not out or out[-1][1] != v:
            out.append((t, v))
    return out


def describe(f, events, ours, theirs):
    for i, (a, b) in enumerate(zip(ours, theirs)):
        if a != b:
            return f"formula: {f}\nfirst difference at index {i}: rvc={a} reelay={b}\ntrace: {json.dumps(events)}"
    return f"formula: {f}\nlengths differ rvc={len(ours)} reelay={len(theirs)}\nrvc={ours}\nreelay={theirs}\ntrace: {json.dumps(events)}"


@pytest.mark.parametrize("seed", range(CASES))
def test_discrete_matches_reelay(rvc, tmp_path, seed):
    rng = random.Random(1000 + seed)
    formulas = [formula(rng, rng.randint(1, 4), dense=False) for _ in range(FORMULAS_PER_CASE)]
    events = trace(rng, rng.randint(20, 60), dense=False)
    ours = run_rvc(rvc, tmp_path, formulas, events, dense=False)
    for i, f in enumerate(formulas):
        m = reelay.discrete_timed_monitor(pattern=f, condense=False)
        theirs = [(step, m.update(dict(e))["value"]) for step, e in enumerate(events)]
        assert ours[f"f{i}"] == theirs, describe(f, events, ours[f"f{i}"], theirs)


def with_heartbeats(events, step=0.25):
    """The same signal with an empty message every `step` time units.

    Empty messages change no value (fields hold), so the signal is the same;
    but every change point of every subformula now falls on a message time.
    That is where Reelay 25's dense monitors are exact: without heartbeats,
    it (1) drops candidates of `since` for a whole segment when the left
    operand falls inside it, and (2) does not report a false stretch that
    starts at a message and turns true later in the same segment. rvc's
    verdicts do not depend on heartbeats (test_dense_heartbeats_change_nothing).
    """
    out = []
    t = 0.0  # the timeline starts at 0, before the first message too
    while t < events[0]["time"] - 1e-9:
        out.append({"time": t})
        t += step
    for e, nxt in zip(events, events[1:] + [None]):
        out.append(e)
        if nxt is None:
            break
        t = e["time"] + step
        while t < nxt["time"] - 1e-9:
            out.append({"time": t})
            t += step
    return out


def dense_case(seed):
    rng = random.Random(5000 + seed)
    formulas = [formula(rng, rng.randint(1, 4), dense=True) for _ in range(FORMULAS_PER_CASE)]
    events = trace(rng, rng.randint(10, 40), dense=True)
    return formulas, events


@pytest.mark.parametrize("seed", range(CASES))
def test_dense_matches_reelay(rvc, tmp_path, seed):
    formulas, events = dense_case(seed)
    ours = run_rvc(rvc, tmp_path, formulas, events, dense=True)
    probed = with_heartbeats(events)
    for i, f in enumerate(formulas):
        m = reelay.dense_timed_monitor(pattern=f)
        theirs = []
        for e in probed:
            theirs += [(r["time"], r["value"]) for r in m.update(dict(e))]
        theirs = condense(theirs)
        assert condense(ours[f"f{i}"]) == theirs, describe(f, events, ours[f"f{i}"], theirs)


@pytest.mark.parametrize("seed", range(CASES))
def test_dense_heartbeats_change_nothing(rvc, tmp_path, seed):
    formulas, events = dense_case(seed)
    plain = run_rvc(rvc, tmp_path, formulas, events, dense=True)
    probed = run_rvc(rvc, tmp_path, formulas, with_heartbeats(events), dense=True)
    assert plain == probed
