"""Data references (exists[x]. / forall[x]. with {id: *x}) equal Reelay 25's
data monitors (PyPI `reelay`, discrete and dense, on patterns with
references) at every step and time point.

Random formulas quantify one to three variables, nested anywhere in the
formula, over tests that bind them from two string fields ({id: *x},
{o: *y}, also inside braces with other tests: {id: *x, p}); the bodies mix
them with plain tests and every temporal operator, with and without bounds.
Random traces over a few ids, where fields go missing (tests hold their
value, as for plain tests). One `rvc check` run per case. Dense time is
compared as the plain dense test compares it (test_reelay_differential.py):
Reelay on the trace with heartbeats, rvc without.

One deliberate difference (docs/semantics.md): Reelay's data monitors read
historically[a:b] as false during its first a+1 steps, even while its window
is empty; rvc keeps the meaning it has everywhere (and in Reelay's plain
monitors). Reelay is given the equivalent not once[a:b] not φ instead,
which it evaluates as rvc reads historically[a:b].
"""
import json
import os
import random
import re

import pytest

reelay = pytest.importorskip("reelay")

from randspec import operator, trace
from test_reelay_differential import condense, describe, run_rvc, with_heartbeats

CASES = int(os.environ.get("RVC_DIFF_CASES", "60"))
FORMULAS_PER_CASE = 10
PLAIN = ["{p}", "{q}", "{p: false}", "{x > 2}"]
IDS = ["a", "b", "c", "d"]


def data_formula(rng, depth, scope, fresh, dense=False):
    """A formula whose references use only variables in `scope`."""
    if depth == 0 or rng.random() < 0.2:
        if scope and rng.random() < 0.75:
            v = rng.choice(scope)
            return rng.choice([f"{{id: *{v}}}", f"{{o: *{v}}}", f"{{id: *{v}, p}}", f"{{o: *{v}, x > 1}}"])
        return rng.choice(PLAIN)
    choice = rng.choice(["not", "pre", "once", "hist", "and", "or", "implies", "since", "quant", "quant"])
    if choice == "quant" and fresh:
        v = fresh[0]
        body = data_formula(rng, depth - 1, scope + [v], fresh[1:], dense)
        if not re.search(rf"\*{v}\b", body):  # Reelay crashes on a variable its body never binds
            body = f"({body}) {rng.choice(['and', 'or', 'implies'])} ({{id: *{v}}})"
        return f"({rng.choice(['exists', 'forall'])}[{v}]. ({body}))"
    return operator(rng, "not" if choice == "quant" else choice,
                    lambda: data_formula(rng, depth - 1, scope, fresh, dense), dense)


def closed_formula(rng, dense=False):
    """Quantified at the top, so there is at least one reference."""
    names = ["x", "y", "z"]
    rng.shuffle(names)
    v = names[0]
    body = data_formula(rng, rng.randint(1, 4), [v], names[1:], dense)
    if not re.search(rf"\*{v}\b", body):
        body = f"({body}) and ({{id: *{v}}})"
    return f"{rng.choice(['exists', 'forall'])}[{v}]. ({body})"


def for_reelay(f):
    """historically[a:b] (φ) -> not (once[a:b] (not (φ))): the same in rvc, and what Reelay's
    data monitors evaluate as rvc does. The operand is the parenthesized group after it."""
    out, i = [], 0
    while True:
        m = re.compile(r"historically(\[[^\]]*\]) \(").search(f, i)
        if not m:
            out.append(f[i:])
            return "".join(out)
        out.append(f[i:m.start()])
        depth, j = 1, m.end()
        while depth:
            depth += {"(": 1, ")": -1}.get(f[j], 0)
            j += 1
        inner = for_reelay(f[m.end():j - 1])
        out.append(f"not (once{m.group(1)} (not ({inner})))")
        i = j


def data_trace(rng, length, dense=False):
    """randspec's trace (p, q, r, x, and times in dense time) with two string fields to bind,
    missing now and then like the others."""
    events = trace(rng, length, dense)
    for e in events:
        for key in ("id", "o"):
            if rng.random() < 0.8:
                e[key] = rng.choice(IDS)
    return events


@pytest.mark.parametrize("seed", range(CASES))
def test_data_references_match_reelay(rvc, tmp_path, seed):
    rng = random.Random(9000 + seed)
    formulas = [closed_formula(rng) for _ in range(FORMULAS_PER_CASE)]
    events = data_trace(rng, rng.randint(15, 50))
    ours = run_rvc(rvc, tmp_path, formulas, events, dense=False)
    for i, f in enumerate(formulas):
        m = reelay.discrete_timed_monitor(pattern=for_reelay(f), condense=False)
        theirs = [(step, bool(m.update(dict(e))["value"])) for step, e in enumerate(events)]
        assert ours[f"f{i}"] == theirs, (
            f"formula: {f}\nfor reelay: {for_reelay(f)}\nrvc:    {ours[f'f{i}']}\nreelay: {theirs}\n"
            f"trace: {json.dumps(events)}")


@pytest.mark.parametrize("seed", range(CASES))
def test_dense_data_references_match_reelay(rvc, tmp_path, seed):
    rng = random.Random(9500 + seed)
    formulas = [closed_formula(rng, dense=True) for _ in range(FORMULAS_PER_CASE)]
    events = data_trace(rng, rng.randint(10, 30), dense=True)
    ours = run_rvc(rvc, tmp_path, formulas, events, dense=True)
    probed = with_heartbeats(events)
    for i, f in enumerate(formulas):
        m = reelay.dense_timed_monitor(pattern=for_reelay(f))
        theirs = []
        for e in probed:
            theirs += [(r["time"], r["value"]) for r in m.update(dict(e))]
        assert leading_false_dropped(condense(ours[f"f{i}"])) == leading_false_dropped(condense(theirs)), describe(
            f, events, ours[f"f{i}"], condense(theirs))


def leading_false_dropped(changes):
    """Reelay's dense data monitors start from false and report only changes from it (its
    plain ones report the first value); rvc reports the first value in both."""
    return changes[1:] if changes and changes[0][1] is False else changes


def test_reelay_reads_bounded_historically_differently():
    """The one documented difference, pinned: if Reelay changes, this says so."""
    m = reelay.discrete_timed_monitor(pattern="exists[x]. historically[0:1] {id: *x}", condense=False)
    assert [m.update({"id": "a"})["value"] for _ in range(3)] == [False, True, True]
