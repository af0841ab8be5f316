"""rvc's Reelay API (rvc.discrete_timed_monitor / rvc.dense_timed_monitor) against Reelay's own
PyPI package through the same Python calls: random formulas and traces (tests/differential's
generators), every update()'s return value compared as it is, first call included.

Where docs/semantics.md lists a deliberate difference, Reelay is given what it evaluates as rvc
does, as the differential tier does: discrete robustness since[lo:] written out, data references'
bounded historically as not once not; dense time compared on traces with heartbeats (empty
messages; rvc's verdicts do not depend on them, Reelay 25's dense monitors are exact only at
message times).
"""
import json
import math
import os
import random

import pytest

reelay = pytest.importorskip("reelay")
import rvc  # noqa: E402

from randspec import formula, trace  # noqa: E402
from test_data_differential import closed_formula, data_trace, for_reelay  # noqa: E402
from test_reelay_differential import with_heartbeats  # noqa: E402
from test_robustness_differential import add_real_field, robust_formulas  # noqa: E402

CASES = int(os.environ.get("RVC_PY_DIFF_CASES", "25"))
FORMULAS = 8


def same_calls(make, events, pattern_ours, pattern_theirs, **kw):
    """Both packages' monitors, built and fed by the same calls: [(ours, theirs)] per update()."""
    ours = make(rvc)(pattern=pattern_ours, **kw)
    theirs = make(reelay)(pattern=pattern_theirs, **kw)
    return [(ours.update(dict(e)), theirs.update(dict(e))) for e in events]


def assert_same(pairs, f, events, g=None):
    for i, (a, b) in enumerate(pairs):
        assert a == b, (f"formula: {f}\n" + (f"reelay's: {g}\n" if g and g != f else "") +
                        f"update {i}: rvc={a} reelay={b}\ntrace: {json.dumps(events)}")


@pytest.mark.parametrize("condense", [True, False])
@pytest.mark.parametrize("seed", range(CASES))
def test_discrete_boolean(seed, condense):
    rng = random.Random(31000 + seed)
    events = trace(rng, rng.randint(15, 50), dense=False)
    for _ in range(FORMULAS):
        f = formula(rng, rng.randint(1, 4), dense=False)
        assert_same(same_calls(lambda m: m.discrete_timed_monitor, events, f, f, condense=condense), f, events)


@pytest.mark.parametrize("condense", [True, False])
@pytest.mark.parametrize("seed", range(CASES))
def test_discrete_robustness(seed, condense):
    rng = random.Random(32000 + seed)
    events = trace(rng, rng.randint(15, 50), dense=False)
    add_real_field(rng, events)
    for _ in range(FORMULAS):
        f, g = robust_formulas(rng, rng.randint(1, 4), dense=False)
        pairs = same_calls(lambda m: m.discrete_timed_monitor, events, f, g, semantics="robustness",
                           condense=condense, t_name="t", y_name="rho")
        assert_same(pairs, f, events, g)


@pytest.mark.parametrize("seed", range(CASES))
def test_discrete_data_references(seed):
    rng = random.Random(33000 + seed)
    events = data_trace(rng, rng.randint(15, 40))
    for _ in range(FORMULAS):
        f = closed_formula(rng)
        ours = rvc.discrete_timed_monitor(pattern=f)
        theirs = reelay.discrete_timed_monitor(pattern=for_reelay(f))
        assert_same([(ours.update(dict(e)), theirs.update(dict(e))) for e in events], f, events, for_reelay(f))


def flatten(pairs):
    return [(a, b) for a, b in pairs]


@pytest.mark.parametrize("seed", range(CASES))
def test_dense_boolean(seed):
    rng = random.Random(34000 + seed)
    events = with_heartbeats(trace(rng, rng.randint(8, 30), dense=True))
    for _ in range(FORMULAS):
        f = formula(rng, rng.randint(1, 4), dense=True)
        assert_same(same_calls(lambda m: m.dense_timed_monitor, events, f, f), f, events)


@pytest.mark.parametrize("seed", range(CASES))
def test_dense_robustness(seed):
    rng = random.Random(35000 + seed)
    events = trace(rng, rng.randint(8, 30), dense=True)
    add_real_field(rng, events)
    events = with_heartbeats(events)
    for _ in range(FORMULAS):
        f, _ = robust_formulas(rng, rng.randint(1, 4), dense=True)
        pairs = same_calls(lambda m: m.dense_timed_monitor, events, f, f, semantics="robustness",
                           t_name="ts", y_name="margin")
        assert_same(pairs, f, events)


@pytest.mark.parametrize("seed", range(CASES))
def test_dense_data_references(seed):
    rng = random.Random(36000 + seed)
    events = with_heartbeats(data_trace(rng, rng.randint(8, 25), dense=True))
    for _ in range(FORMULAS):
        f = closed_formula(rng, dense=True)
        ours = rvc.dense_timed_monitor(pattern=f)
        theirs = reelay.dense_timed_monitor(pattern=for_reelay(f))
        assert_same([(ours.update(dict(e)), theirs.update(dict(e))) for e in events], f, events, for_reelay(f))


def test_now_and_first_calls_as_reelay():
    for mod in (rvc, reelay):
        d = mod.discrete_timed_monitor(pattern="{p}", t_name="step", y_name="ok")
        assert d.update({"p": False}) == {"step": 0, "ok": False}
        assert d.update({"p": False}) == {}
        assert d.now() == {"step": 1}
        c = mod.dense_timed_monitor(pattern="{p}")
        assert c.update({"time": 0, "p": True}) == []  # [0, 0) holds nothing
        assert c.update({"time": 1.5}) == [{"time": 0.0, "value": True}]
        assert c.now() == {"time": 1.5}


def test_reelay_errors_kept():
    """The constructor's argument checks and the dense monitors' "time" key, as Reelay raises them."""
    for mod in (rvc, reelay):
        with pytest.raises(AttributeError):
            mod.discrete_timed_monitor(pattern="{p}", semantics="fuzzy")
        with pytest.raises(AttributeError):
            mod.dense_timed_monitor(pattern="{p}", piecewise="cubic")
        with pytest.raises(KeyError):
            mod.dense_timed_monitor(pattern="{p}").update({"p": True})


def test_rvc_errors_name_the_problem():
    with pytest.raises(ValueError, match="column 9"):
        rvc.discrete_timed_monitor(pattern="once[:2 {p}")
    m = rvc.dense_timed_monitor(pattern="{p}")
    m.update({"time": 2, "p": True})
    with pytest.raises(ValueError, match="not after the previous message's time 2"):
        m.update({"time": 1, "p": False})
    assert m.update({"time": 3, "p": False}) == [{"time": 2.0, "value": True}]  # the refused one cost only itself
    with pytest.raises(TypeError, match="bytes"):
        rvc.discrete_timed_monitor(pattern="{p}").update({"p": b"x"})
