"""Booleans and numbers in one field, and now(), through rvc's Reelay API and Reelay 25's own
package by the same calls (every update()'s return compared as it is).

Reelay 25, measured: a Boolean test ({p}, {p: true}, {p: false}) reads a number as Python's bool()
does (0 false, any other number true) and None as false; a numeric test ({p > 0}, {p == 1}) reads
True as 1 and False as 0. So a 0/1 flag in a ROS 2 uint8 field reads as a bool field does.
now() is {t_name: -1} before the first discrete update(), {t_name: 0.0} before the first dense one.
"""
import random
import zlib

import pytest

reelay = pytest.importorskip("reelay")
import rvc  # noqa: E402

NUMBERS = [0, 1, 2, -1, 0.5, 0.0, 1.0, True, False]
BOOLEAN_TESTS = ["{p}", "{p: true}", "{p: false}"]
NUMERIC_TESTS = ["{p > 0}", "{p >= 1}", "{p < 0.5}", "{p == 1}", "{p != 0}", "{p <= 0}"]
# All-or-nothing equality with a number literal ({p: 1}): same Boolean verdicts, but Reelay's
# robustness is +-inf where rvc's is -|p - 1| (docs/semantics.md, robustness): Boolean only.
COLON_NUMBER_TESTS = ["{p: 1}", "{p: 0}"]
TEMPORAL = ["once[0:2] ({p: false})", "({p: true}) since ({q: false})", "pre ({p: false})",
            "historically[1:3] ({p > 0})", "({p: false}) and ({q >= 1})", "not ({q: true})"]


def traces(seed, pool, n=6, length=12):
    rng = random.Random(seed)
    out = [[{"p": v, "q": rng.choice(pool)} for v in pool]]  # every value once, from the first call
    for _ in range(n):
        out.append([{k: rng.choice(pool) for k in ("p", "q") if rng.random() < 0.9} for _ in range(length)])
    return out


def discrete_pairs(pattern, events, **kw):
    ours = rvc.discrete_timed_monitor(pattern=pattern, **kw)
    theirs = reelay.discrete_timed_monitor(pattern=pattern, **kw)
    return [(ours.update(dict(e)), theirs.update(dict(e))) for e in events] + [(ours.now(), theirs.now())]


def dense_pairs(pattern, events, **kw):
    ours = rvc.dense_timed_monitor(pattern=pattern, **kw)
    theirs = reelay.dense_timed_monitor(pattern=pattern, **kw)
    return [(ours.update(dict(e, time=i)), theirs.update(dict(e, time=i))) for i, e in enumerate(events)]


def assert_same(pairs, pattern, events):
    for i, (a, b) in enumerate(pairs):
        assert a == b, f"{pattern}, call {i}: rvc={a} reelay={b}\ntrace: {events}"


CASES = ([(p, NUMBERS + [None]) for p in BOOLEAN_TESTS] + [(p, NUMBERS) for p in NUMERIC_TESTS + COLON_NUMBER_TESTS] +
         [(p, NUMBERS) for p in TEMPORAL])


@pytest.mark.parametrize("condense", [True, False])
@pytest.mark.parametrize("pattern,pool", CASES)
def test_discrete_boolean_verdicts(pattern, pool, condense):
    for events in traces(zlib.crc32(pattern.encode()), pool):
        assert_same(discrete_pairs(pattern, events, condense=condense), pattern, events)


# Dense time has no pre; Reelay 25's dense monitors have no == / != on numbers.
DENSE_CASES = [(p, pool) for p, pool in CASES if not p.startswith("pre") and "==" not in p and "!=" not in p]


@pytest.mark.parametrize("pattern,pool", DENSE_CASES)
def test_dense_boolean_verdicts(pattern, pool):
    for events in traces(zlib.crc32(pattern.encode()), pool):
        assert_same(dense_pairs(pattern, events), pattern, events)


# Robustness: Reelay raises on None where a number is tested ({p} included); the pool leaves it out.
ROBUST = [p for p in BOOLEAN_TESTS + NUMERIC_TESTS + TEMPORAL if not p.startswith("historically")]


@pytest.mark.parametrize("pattern", ROBUST)
def test_discrete_robustness(pattern):
    for events in traces(7 + len(pattern), NUMBERS):
        assert_same(discrete_pairs(pattern, events, semantics="robustness", condense=False), pattern, events)


def test_a_uint8_flag_reads_as_a_bool_flag():
    """The issue's case: {p: false} on 0 is true, {p: true} on 1 after 0 turns true, as with bools."""
    for pattern in ("{p: false}", "{p: true}"):
        as_ints = [rvc.discrete_timed_monitor(pattern=pattern).update({"p": v}) for v in (0, 1)]
        as_bools = [rvc.discrete_timed_monitor(pattern=pattern).update({"p": v}) for v in (False, True)]
        assert as_ints == as_bools
    m = rvc.discrete_timed_monitor(pattern="{p: true}")
    assert [m.update({"p": v}) for v in (0, 1, 1, 0)] == [{"time": 0, "value": False}, {"time": 1, "value": True},
                                                          {}, {"time": 3, "value": False}]


def test_now_before_any_update_is_reelays():
    for kw in ({}, {"t_name": "t"}, {"semantics": "robustness"}):
        ours, theirs = rvc.discrete_timed_monitor(pattern="{p}", **kw), reelay.discrete_timed_monitor(pattern="{p}", **kw)
        assert ours.now() == theirs.now()
        assert list(ours.now().values()) == [-1]
        ours.update({"p": True}), theirs.update({"p": True})
        assert ours.now() == theirs.now()
        ours, theirs = rvc.dense_timed_monitor(pattern="{p}", **kw), reelay.dense_timed_monitor(pattern="{p}", **kw)
        assert ours.now() == theirs.now()
        ours.update({"time": 2.5, "p": True}), theirs.update({"time": 2.5, "p": True})
        assert ours.now() == theirs.now()
