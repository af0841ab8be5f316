"""rvc --robustness equals Reelay 25's robustness semantics (PyPI `reelay`,
`semantics="robustness"`) at every step in discrete time, at every change in dense time.

Random formulas over numeric and Boolean fields ({x > 2}: x - 2, {p}: 1 or 0,
{p: false}: +-inf, ...) and every operator rvc evaluates for robustness
(not, and, or, implies, pre, once, historically and since, with and without
bounds); random traces where fields go missing (they hold) and an extra
real-valued field y. Values compared exactly: both sides compute them
with the same min, max, negation and subtraction. One `rvc check --all` run
per case checks all its formulas.

One exception, in discrete time only: `φ since[lo:] ψ` (no upper bound). Reelay 25 computes every
bounded since as min(historically[0:lo](φ since ψ), once[lo:hi] ψ), but its discrete since[lo:]
drops the once part to -inf every few steps (on a constant trace, true one step and -inf the next),
which its dense time does not do; rvc gives the rewriting's value. There Reelay is given the
rewriting written out (test_discrete_since_without_upper_bound_is_reelays_rewriting shows why).
"""
import json
import math
import os
import random
import subprocess

import pytest

reelay = pytest.importorskip("reelay")

from randspec import ATOMS, bounds, trace, write_jsonl

CASES = int(os.environ.get("RVC_DIFF_CASES", "60"))
FORMULAS_PER_CASE = 12
NUMERIC = ["{y > 0.5}", "{y < -1.25}", "{x == 2}", "{x != 3}", "{x >= 1}", "{y}"]
DENSE_NUMERIC = [a for a in NUMERIC if "!=" not in a and "==" not in a]  # Reelay's dense robustness refuses them


def since_for_reelay(left, right, written):
    """What Reelay is given for (left) since{written} (right): the same, except discrete since[lo:]."""
    if not written.endswith(":]"):
        return f"({left}) since{written} ({right})"
    lo = written[1:-2]
    unbounded = f"({left}) since ({right})"
    # historically[0:0] would read as unbounded in Reelay; over one step it is the value itself.
    hold = unbounded if float(lo) == 0 else f"historically[0:{lo}] ({unbounded})"
    return f"({hold}) and (once{written} ({right}))"


def robust_formulas(rng, depth, dense):
    """(for rvc, for Reelay): a random formula as randspec makes them, more numeric atoms, and
    since with every kind of bounds in both time models."""
    if depth == 0 or rng.random() < 0.2:
        atom = rng.choice(ATOMS)
        if atom in ("{r}", "{x > 2}") and rng.random() < 0.5:
            atom = rng.choice(DENSE_NUMERIC if dense else NUMERIC)
        return atom, atom
    choice = rng.choice(["not", "pre", "once", "hist", "and", "or", "implies", "since", "since"])
    if dense and choice == "pre":
        choice = "once"
    sub = lambda: robust_formulas(rng, depth - 1, dense)
    if choice in ("not", "pre"):
        (a, b) = sub()
        return f"{choice} ({a})", f"{choice} ({b})"
    if choice in ("once", "hist"):
        name = "once" if choice == "once" else "historically"
        written = bounds(rng, dense)
        (a, b) = sub()
        return f"{name}{written} ({a})", f"{name}{written} ({b})"
    (l1, l2), (r1, r2) = sub(), sub()
    if choice == "since":
        written = bounds(rng, dense)
        ours = f"({l1}) since{written} ({r1})"
        return ours, (ours if dense else since_for_reelay(l2, r2, written))
    return f"({l1}) {choice} ({r1})", f"({l2}) {choice} ({r2})"


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
    # --clock off: no tick at the trace's end (it adds the last message's own value, which Reelay
    # does not report; test_reelay_differential checks the tick changes nothing else).
    proc = subprocess.run([rvc, "check", "--robustness", *(["--dense", "--origin", "zero"] if dense else ["--all"]), "--clock", "off",
                           "--properties", str(props), str(tr)],
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
    pairs = [robust_formulas(rng, rng.randint(1, 4), dense=False) for _ in range(FORMULAS_PER_CASE)]
    events = trace(rng, rng.randint(20, 60), dense=False)
    add_real_field(rng, events)
    ours = run_rvc(rvc, tmp_path, [f for f, _ in pairs], events)
    for i, (f, g) in enumerate(pairs):
        m = reelay.discrete_timed_monitor(pattern=g, semantics="robustness", condense=False)
        theirs = [(step, float(m.update(dict(e))["value"])) for step, e in enumerate(events)]
        assert ours[f"f{i}"] == theirs, (
            f"formula: {f}\nreelay's: {g}\nrvc:    {ours[f'f{i}']}\nreelay: {theirs}\ntrace: {json.dumps(events)}")


def test_discrete_since_without_upper_bound_is_reelays_rewriting(rvc, tmp_path):
    """{a} since[1:] {b} with a = 9 and b = 5 at every step: 5 from step 1 on, as Reelay's
    rewriting (and its dense time) say; Reelay 25's discrete since[1:] itself alternates
    with -inf. If a Reelay release fixes that, its values equal rvc's again and this test says so."""
    events = [{"a": 9, "b": 5}] * 6
    ours = run_rvc(rvc, tmp_path, ["{a} since[1:] {b}"], events)["f0"]
    assert [v for _, v in ours] == [-math.inf, 5, 5, 5, 5, 5]
    for pattern in ("(historically[0:1]({a} since {b})) and (once[1:]{b})", "{a} since[1:] {b}"):
        m = reelay.discrete_timed_monitor(pattern=pattern, semantics="robustness", condense=False)
        theirs = [float(m.update(dict(e))["value"]) for e in events]
        if pattern.startswith("(historically"):
            assert theirs == [v for _, v in ours]
        else:
            assert theirs == [-math.inf, 5, -math.inf, -math.inf, 5, -math.inf], (
                f"Reelay's discrete since[1:] changed: {theirs}; compare it directly again")


def test_condensed_output_reports_changes_only(rvc, tmp_path):
    tr = tmp_path / "t.jsonl"
    write_jsonl(tr, [{"x": 5}, {"x": 5}, {"x": 1}, {"x": 1}, {"x": 4}])
    proc = subprocess.run([rvc, "check", "--robustness", "--spec", "historically{x > 2}", str(tr)],
                          capture_output=True, text=True)
    assert proc.returncode == 1  # robustness <= 0: violated
    assert [json.loads(l) for l in proc.stdout.splitlines()] == [
        {"time": 0, "property": "p1", "value": 3}, {"time": 2, "property": "p1", "value": -1}]


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
    formulas = [robust_formulas(rng, rng.randint(1, 4), dense=True)[0] for _ in range(FORMULAS_PER_CASE)]
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
