"""Seeded random Rye formulas and traces for differential tests against Reelay.

Formulas stay inside the syntax Reelay 25 accepts (every operand parenthesized,
no `true`/`false`, no upper bound 0, which Reelay reads as unbounded), so any
difference is a semantic one.
"""
import json
import random

ATOMS = ["{p}", "{q}", "{r}", "{p: false}", "{x > 2}", "{x <= 1}", "{q: true}"]


def bounds(rng, dense):
    kind = rng.choice(["none", "none", "ab", "a", "b"])
    if dense:
        num = lambda lo, hi: rng.choice([0.25, 0.5, 1, 1.5, 2, 2.5, 3, 4]) if hi > 0 else 0
        lo = rng.choice([0, 0, 0.5, 1, 2, 3])
        width = rng.choice([0.5, 1, 1.5, 2, 3, 5])
    else:
        lo = rng.choice([0, 0, 1, 2, 3, 5])
        width = rng.choice([0, 1, 2, 3, 4, 7])
    hi = lo + width
    if hi == 0:
        hi = 1
    fmt = lambda v: str(int(v)) if float(v).is_integer() else str(v)
    if kind == "none":
        return ""
    if kind == "ab":
        return f"[{fmt(lo)}:{fmt(hi)}]"
    if kind == "a":
        return f"[{fmt(lo)}:]"
    return f"[:{fmt(hi)}]"


def formula(rng, depth, dense):
    if depth == 0 or rng.random() < 0.2:
        return rng.choice(ATOMS)
    choice = rng.choice(["not", "pre", "once", "hist", "and", "or", "implies", "since", "since"])
    return operator(rng, choice, lambda: formula(rng, depth - 1, dense), dense)


def operator(rng, choice, sub, dense):
    """The operator `choice` (not, pre, once, hist, since, and, or, implies) over formulas from
    sub(); random bounds. Dense time has no pre: once instead."""
    if dense and choice == "pre":
        choice = "once"
    if choice == "not":
        return f"not ({sub()})"
    if choice == "pre":
        return f"pre ({sub()})"
    if choice == "once":
        return f"once{bounds(rng, dense)} ({sub()})"
    if choice == "hist":
        return f"historically{bounds(rng, dense)} ({sub()})"
    if choice == "since":
        return f"({sub()}) since{bounds(rng, dense)} ({sub()})"
    return f"({sub()}) {choice} ({sub()})"


def trace(rng, length, dense):
    """Messages over p, q, r, x; fields go missing now and then (they hold)."""
    events = []
    t = rng.choice([0, 0, 0.5, 1, 3]) if dense else 0
    for i in range(length):
        e = {}
        if dense:
            e["time"] = t
            t += rng.choice([0.25, 0.5, 0.5, 1, 1, 1.5, 2, 3])
        for key in ("p", "q", "r"):
            if rng.random() < 0.85:
                e[key] = rng.random() < 0.5
        if rng.random() < 0.8:
            e["x"] = rng.randint(0, 4)
        events.append(e)
    return events


def write_jsonl(path, events):
    with open(path, "w") as f:
        for e in events:
            f.write(json.dumps(e) + "\n")
