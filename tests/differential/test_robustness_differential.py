"""rvc --robustness equals Reelay 25's robustness semantics (PyPI `reelay`,
`semantics="robustness"`) at every step in discrete time, at every change in dense time.

Random formulas over numeric and Boolean fields ({x > 2}: x - 2, {p}: 1 or 0,
{p: false}: +-inf, ...) and every operator rvc evaluates for robustness
(not, and, or, implies, pre, once and historically with and without bounds,
unbounded since); random traces where fields go missing (they hold) and an
extra real-valued field y. Values compared exactly: both sides compute them
with the same min, max, negation and subtraction. One `rvc check --all` run
per case checks all its formulas. Dense time: formulas without since
(refused there for now) over the same atoms, as test_dense_robustness_matches_reelay says.
"""
import json
import math
import os
import random
import subprocess

import pytest

reelay = pytest.importorskip("reelay")

from randspec import formula, trace, write_jsonl

CASES = int(os.environ.get("RVC_DIFF_CASES", "60"))
FORMULAS_PER_CASE = 12
NUMERIC = ["{y > 0.5}", "{y < -1.25}", "{x == 2}", "{x != 3}", "{x >= 1}", "{y}"]


def robust_formula(rng, depth):
    """A randspec formula without time-bounded since (no robustness in rvc yet), with
    more numeric atoms."""
    while True:
        f = formula(rng, depth, dense=False)
        if "since[" not in f:
            break
    # Swap some atoms for numeric ones, so margins are not all 0, 1 and infinities.
    for atom in ("{r}", "{x > 2}"):
        if atom in f and rng.random() < 0.7:
            f = f.replace(atom, rng.choice(NUMERIC), 1)
    return f


def value(v):
    if v == "inf":
        return math.inf
    if v == "-inf":
        return -math.inf
    return float(v)


def add_real_field(rng, events):
    """A real-valued y in most messages, so margins are not all 0, 1 and infinities."""
    for e in events:
        if rng.random() < 0.8:
            e["y"] = rng.choice([-2.5, -1.25, -0.5, 0, 0.25, 0.5, 1.75, 3])


def run_rvc(rvc, tmp_path, formulas, events, dense=False):
    props = tmp_path / "props.json"
    props.write_text(json.dumps({"properties": [{"name": f"f{i}", "spec": f} for i, f in enumerate(formulas)]}))
    tr = tmp_path / "trace.jsonl"
    write_jsonl(tr, events)
    proc = subprocess.run([rvc, "check", "--robustness", "--dense" if dense else "--all", "--properties", str(props),
                           str(tr)],
                          capture_output=True, text=True)
    assert proc.returncode in (0, 1), f"rvc failed ({proc.returncode}): {proc.stderr}"
    out = {f"f{i}": [] for i in range(len(formulas))}
    for line in proc.stdout.splitlines():
        v = json.loads(line)
        out[v["property"]].append((v["time"], value(v["value"])))
    return out


@pytest.mark.parametrize("seed", range(CASES))
def test_discrete_robustness_matches_reelay(rvc, tmp_path, seed):
    rng = random.Random(7000 + seed)
    formulas = [robust_formula(rng, rng.randint(1, 4)) for _ in range(FORMULAS_PER_CASE)]
    events = trace(rng, rng.randint(20, 60), dense=False)
    add_real_field(rng, events)
    ours = run_rvc(rvc, tmp_path, formulas, events)
    for i, f in enumerate(formulas):
        m = reelay.discrete_timed_monitor(pattern=f, semantics="robustness", condense=False)
        theirs = [(step, float(m.update(dict(e))["value"])) for step, e in enumerate(events)]
        assert ours[f"f{i}"] == theirs, (
            f"formula: {f}\nrvc:    {ours[f'f{i}']}\nreelay: {theirs}\ntrace: {json.dumps(events)}")


def test_condensed_output_reports_changes_only(rvc, tmp_path):
    tr = tmp_path / "t.jsonl"
    write_jsonl(tr, [{"x": 5}, {"x": 5}, {"x": 1}, {"x": 1}, {"x": 4}])
    proc = subprocess.run([rvc, "check", "--robustness", "--spec", "historically{x > 2}", str(tr)],
                          capture_output=True, text=True)
    assert proc.returncode == 1  # robustness <= 0: violated
    assert [json.loads(l) for l in proc.stdout.splitlines()] == [
        {"time": 0, "property": "p1", "value": 3}, {"time": 2, "property": "p1", "value": -1}]


def test_what_robustness_refuses(rvc, tmp_path):
    tr = tmp_path / "t.jsonl"
    write_jsonl(tr, [{"time": 0, "x": 1}])
    cases = [
        (["--spec", "{x > 1} since[1:3] {x < 0}"], "since with time bounds has no robustness semantics in rvc yet"),
        (["--spec", "{x > 1} since {x < 0}", "--dense"], "since has no dense-time robustness in rvc yet"),
    ]
    for extra, message in cases:
        proc = subprocess.run([rvc, "check", "--robustness", *extra, str(tr)], capture_output=True, text=True)
        assert proc.returncode == 2, proc.stderr
        assert message in proc.stderr, proc.stderr


def dense_robust_formula(rng, depth):
    """A dense randspec formula without since (no dense robustness for it in rvc yet), with more
    numeric atoms; no {x == c} or {x != c}, which Reelay's dense robustness monitors refuse."""
    while True:
        f = formula(rng, depth, dense=True)
        if "since" not in f:
            break
    for atom in ("{r}", "{x > 2}"):
        if atom in f and rng.random() < 0.7:
            f = f.replace(atom, rng.choice([a for a in NUMERIC if "!=" not in a and "==" not in a]), 1)
    return f


def leading_zero_dropped(changes):
    """Reelay's dense robustness monitors start from 0 and report changes from it; rvc reports
    the first value whatever it is."""
    return changes[1:] if changes and changes[0][1] == 0 else changes


@pytest.mark.parametrize("seed", range(CASES))
def test_dense_robustness_matches_reelay(rvc, tmp_path, seed):
    """Dense time: every change of the robustness signal, at the same times with the same values.
    Compared as the Boolean dense test compares (test_reelay_differential.py): Reelay on the trace
    with heartbeats (empty messages changing nothing), where every change point is a message."""
    from test_reelay_differential import condense, with_heartbeats
    rng = random.Random(8000 + seed)
    formulas = [dense_robust_formula(rng, rng.randint(1, 4)) for _ in range(FORMULAS_PER_CASE)]
    events = trace(rng, rng.randint(10, 40), dense=True)
    add_real_field(rng, events)
    ours = run_rvc(rvc, tmp_path, formulas, events, dense=True)
    probed = with_heartbeats(events)
    for i, f in enumerate(formulas):
        m = reelay.dense_timed_monitor(pattern=f, semantics="robustness")
        theirs = []
        for e in probed:
            theirs += [(r["time"], float(r["value"])) for r in m.update(dict(e))]
        assert leading_zero_dropped(condense(ours[f"f{i}"])) == leading_zero_dropped(condense(theirs)), (
            f"formula: {f}\nrvc:    {ours[f'f{i}']}\nreelay: {condense(theirs)}\ntrace: {json.dumps(events)}")
