"""Timing atoms and window aggregates (issue 26) against Reelay.

Python computes every timing atom ({@age <= d}, {count[a:b](@arrived) >= n},
{avg[a:b](x) > v}, ...) itself, from the documented semantics
(docs/semantics.md, "Timing atoms and window aggregates"), at every instant
where one can change; each becomes a plain proposition p0, p1, ... that
Reelay's discrete and dense timed monitors (PyPI `reelay`) check under the
same temporal formula. rvc, given the messages only, must report the same
verdicts: so its windows, ages, change instants and the stepping between
messages agree with an independent computation, and its temporal operators
over them with Reelay's.

Every time, bound and value is a multiple of 0.25 (integers for values): all
sums and instants are exact in binary, so the oracle and rvc compare equal
numbers, and an event every 0.25 s lands on every change instant (where
Reelay's dense monitors are exact, see test_reelay_differential.py).
"""
import json
import math
import os
import random
import subprocess

import pytest

reelay = pytest.importorskip("reelay")

CASES = int(os.environ.get("RVC_DIFF_CASES", "40"))
FORMULAS = 8
Q = 0.25  # the grid every instant and bound lies on
OPS = {"<": lambda a, b: a < b, "<=": lambda a, b: a <= b, ">": lambda a, b: a > b, ">=": lambda a, b: a >= b}


def quarter(rng, lo, hi):
    return rng.randint(int(lo / Q), int(hi / Q)) * Q


def num(v):
    return str(int(v)) if v == int(v) else str(v)


def random_atom(rng, dense):
    """(rye text, description) of one timing atom or aggregate."""
    kinds = ["age", "count", "field"] if dense else ["count", "field"]
    kind = rng.choice(kinds)
    if kind == "age":
        op = rng.choice(["<=", "<", ">", ">="])
        d = quarter(rng, 0.25, 2)
        return f"{{@age {op} {num(d)}}}", ("age", op, d)
    if dense:
        a = rng.choice([0, 0, quarter(rng, 0.25, 1)])
        b = a + quarter(rng, 0, 2.5)
    else:
        a = rng.choice([0, 0, rng.randint(1, 3)])
        b = a + rng.randint(0, 6)
    op = rng.choice(list(OPS))
    if kind == "count":
        n = rng.randint(0, 4)
        return f"{{count[{num(a)}:{num(b)}](@arrived) {op} {n}}}", ("agg", "count", a, b, op, n)
    func = rng.choice(["sum", "avg", "min", "max"])
    v = rng.randint(-1, 8) + rng.choice([0, 0.5])
    return f"{{{func}[{num(a)}:{num(b)}](x) {op} {num(v)}}}", ("agg", func, a, b, op, v)


def random_formula(rng, dense):
    """(rye text for rvc, the same with {pK} for Reelay, the atoms)."""
    atoms = [random_atom(rng, dense) for _ in range(2)]
    w = num(quarter(rng, 0.25, 2)) if dense else str(rng.randint(1, 4))
    shapes = [
        "historically({A})", "once[0:W]({A})", "({A}) since ({B})", "({A}) and not ({B})",
        "historically[0:W](({A}) or {y})", "({A}) -> once[0:W]({B})", "({A})", "pre({A}) or {y}",
    ]
    shape = rng.choice(shapes if not dense else [s for s in shapes if not s.startswith("pre")])
    ours = shape.replace("W", w).replace("{A}", atoms[0][0]).replace("{B}", atoms[1][0])
    theirs = shape.replace("W", w).replace("{A}", "{p0}").replace("{B}", "{p1}")
    return ours, theirs, [atoms[0][1], atoms[1][1]]


def random_trace(rng, dense):
    """Messages: time (dense), x (an integer, sometimes missing), y (a Boolean)."""
    events, t = [], quarter(rng, 0, 1)
    for _ in range(rng.randint(8, 30)):
        e = {}
        if dense:
            e["time"] = t
            t += rng.choice([0.25, 0.25, 0.5, 0.5, 0.75, 1, 1.5, 2.5])
        if rng.random() < 0.8:
            e["x"] = rng.randint(-2, 9)
        e["y"] = rng.random() < 0.5
        events.append(e)
    return events


def aggregate(func, values):
    if func == "count":
        return len(values)
    if func == "sum":
        return sum(values)
    if not values:
        return None  # empty window: avg/min/max do not exist, every comparison is false
    return {"avg": sum(values) / len(values), "min": min(values), "max": max(values)}[func]


def atom_value(atom, now, samples, last, dense):
    """The atom at `now` (dense: the value holding from now on, right-continuous).

    samples: [(time, x or None)] of the messages at or before now; last: the
    time of the last one (None: none yet)."""
    if atom[0] == "age":
        _, op, d = atom
        if last is None:
            return OPS[op](math.inf, d)
        # just after now: age = now - last + epsilon
        return now < last + d if op in ("<", "<=") else now >= last + d
    _, func, a, b, op, c = atom
    inside = []
    for s, x in samples:
        if not (s + a <= now and (now < s + b if dense else now <= s + b)):
            continue
        if func == "count":
            inside.append(1)
        elif x is not None:
            inside.append(x)
    v = aggregate(func, inside)
    return v is not None and OPS[op](v, c)


def run_rvc(rvc, tmp_path, formulas, events, dense):
    props = tmp_path / "props.json"
    props.write_text(json.dumps({"properties": [{"name": f"f{i}", "spec": f} for i, f in enumerate(formulas)]}))
    tr = tmp_path / "trace.jsonl"
    tr.write_text("".join(json.dumps(e) + "\n" for e in events))
    # --clock off: Reelay tells nothing at the last message's own instant, which the end-of-input
    # tick adds (the clock tests compare that tick with heartbeats instead).
    args = [rvc, "check", "--properties", str(props), str(tr)] + (["--dense", "--origin", "zero", "--clock", "off"] if dense else ["--all"])
    proc = subprocess.run(args, capture_output=True, text=True)
    assert proc.returncode in (0, 1), f"rvc failed ({proc.returncode}): {proc.stderr}"
    out = {f"f{i}": [] for i in range(len(formulas))}
    for line in proc.stdout.splitlines():
        v = json.loads(line)
        out[v["property"]].append((v["time"], v["value"]))
    return out


def condense(changes):
    out = []
    for t, v in changes:
        if not out or out[-1][1] != v:
            out.append((t, v))
    return out


@pytest.mark.parametrize("seed", range(CASES))
def test_discrete_timed_atoms_match_reelay(rvc, tmp_path, seed):
    rng = random.Random(2600 + seed)
    cases = [random_formula(rng, dense=False) for _ in range(FORMULAS)]
    events = random_trace(rng, dense=False)
    ours = run_rvc(rvc, tmp_path, [c[0] for c in cases], events, dense=False)
    for i, (text, pattern, atoms) in enumerate(cases):
        m = reelay.discrete_timed_monitor(pattern=pattern, condense=False)
        theirs = []
        for step, e in enumerate(events):
            samples = [(j, events[j].get("x")) for j in range(step + 1)]
            props = {f"p{k}": atom_value(a, step, samples, step, dense=False) for k, a in enumerate(atoms)}
            props["y"] = e["y"]
            theirs.append((step, m.update(props)["value"]))
        assert ours[f"f{i}"] == theirs, f"formula {text}\nreelay: {pattern}\ntrace {json.dumps(events)}"


@pytest.mark.parametrize("seed", range(CASES))
def test_dense_timed_atoms_match_reelay(rvc, tmp_path, seed):
    rng = random.Random(7600 + seed)
    cases = [random_formula(rng, dense=True) for _ in range(FORMULAS)]
    events = random_trace(rng, dense=True)
    ours = run_rvc(rvc, tmp_path, [c[0] for c in cases], events, dense=True)
    end = events[-1]["time"]
    for i, (text, pattern, atoms) in enumerate(cases):
        m = reelay.dense_timed_monitor(pattern=pattern)
        theirs = []
        # One event every Q from 0 to the last message: each carries every
        # proposition's value from that instant on (computed by the oracle).
        for k in range(int(end / Q) + 1):
            now = k * Q
            seen = [e for e in events if e["time"] <= now]
            samples = [(e["time"], e.get("x")) for e in seen]
            last = seen[-1]["time"] if seen else None
            props = {f"p{j}": atom_value(a, now, samples, last, dense=True) for j, a in enumerate(atoms)}
            props["y"] = bool(seen and [e["y"] for e in seen][-1])
            props["time"] = now
            theirs += [(r["time"], r["value"]) for r in m.update(props)]
        assert condense(ours[f"f{i}"]) == condense(theirs), (
            f"formula {text}\nreelay: {pattern}\nrvc {condense(ours[f'f{i}'])}\nreelay {condense(theirs)}\n"
            f"trace {json.dumps(events)}")
