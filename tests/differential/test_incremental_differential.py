"""Issue 27: rvc's default evaluation (comparisons of one field with many constants evaluated
together; only the operators whose operands changed stepped) gives the verdicts of the plain path
(`--plain-eval`: every test, every operator, every message), and Reelay's.

Each case: a seeded random suite of many properties over numeric fields compared with many
constants, and a random trace (values walking and jumping, fields missing now and then).
- against `--plain-eval`: the same stdout, stderr and exit status, discrete (changes only, --all,
  --explain) and dense, Boolean and robustness (tests/unit/incremental_test.cpp does typed input);
- against Reelay 25 (PyPI `reelay`): discrete verdict changes of a sample of the suites.
"""
import json
import random
import subprocess

import pytest

from randspec import operator, write_jsonl

FIELDS = ("x", "y")
CONSTANTS = (-2, 0, 0.5, 1, 2, 3, 3.5, 5, 8, 13)


def atom(rng):
    r = rng.random()
    if r < 0.2:
        return rng.choice(["{p}", "{q}", "{p: false}"])
    op = rng.choice([">", ">=", "<", "<=", ">", "<", "=="])
    return f"{{{rng.choice(FIELDS)} {op} {rng.choice(CONSTANTS)}}}"


def formula(rng, depth, dense):
    if depth == 0 or rng.random() < 0.25:
        return atom(rng)
    choice = rng.choice(["not", "pre", "once", "hist", "and", "or", "implies", "since", "since"])
    return operator(rng, choice, lambda: formula(rng, depth - 1, dense), dense)


def suite(rng, n, dense):
    """Single thresholds (every grouped atom seen), random formulas, and the benchmark's shape,
    whose outer historically falls false for good (its cone is no longer stepped)."""
    out = []
    for k in range(n):
        if k % 3 == 0:
            out.append(atom(rng))
        elif k % 5 == 1:
            out.append(f"(historically(({formula(rng, 2, dense)}) implies ({formula(rng, 2, dense)}))) or ({atom(rng)})")
        else:
            out.append(formula(rng, rng.randint(1, 4), dense))
    return out


def trace(rng, length, dense):
    events, t, walk = [], 0.0, {f: 2.0 for f in FIELDS}
    for _ in range(length):
        e = {"time": t} if dense else {}
        t += rng.choice([0.5, 1, 1, 1.5, 2])
        for key in ("p", "q"):
            if rng.random() < 0.85:
                e[key] = rng.random() < 0.6
        for f in FIELDS:
            walk[f] = rng.choice([-3, 14]) if rng.random() < 0.1 else walk[f] + rng.choice([-1, -0.5, 0, 0.5, 1])
            if rng.random() < 0.85:
                e[f] = walk[f]
        events.append(e)
    return events


def rvc_run(rvc, tmp_path, formulas, events, extra):
    props = tmp_path / "props.json"
    props.write_text(json.dumps({"properties": [{"name": f"f{i}", "spec": f} for i, f in enumerate(formulas)]}))
    tr = tmp_path / "trace.jsonl"
    write_jsonl(tr, events)
    return subprocess.run([rvc, "check", "--properties", str(props), str(tr)] + extra, capture_output=True, text=True)


MODES = {
    "discrete": [],
    "discrete-all": ["--all"],
    "discrete-explain": ["--explain"],
    "discrete-robustness": ["--robustness"],
    "dense": ["--dense", "--origin", "zero"],
    "dense-explain": ["--dense", "--origin", "zero", "--explain"],
    "dense-robustness": ["--dense", "--origin", "zero", "--robustness"],
}


@pytest.mark.parametrize("mode", sorted(MODES))
@pytest.mark.parametrize("seed", range(5))
def test_same_verdicts_as_plain_eval(rvc, tmp_path, mode, seed):
    dense = mode.startswith("dense")
    rng = random.Random(2700 + seed)
    formulas = suite(rng, 120, dense)
    events = trace(rng, 250, dense)
    fast = rvc_run(rvc, tmp_path, formulas, events, MODES[mode])
    plain = rvc_run(rvc, tmp_path, formulas, events, MODES[mode] + ["--plain-eval"])
    assert fast.returncode in (0, 1), fast.stderr
    assert len(plain.stdout.splitlines()) > len(formulas)  # the suite says something
    assert (fast.returncode, fast.stderr) == (plain.returncode, plain.stderr)
    ours, theirs = fast.stdout.splitlines(), plain.stdout.splitlines()
    for i, (a, b) in enumerate(zip(ours, theirs)):
        assert a == b, f"line {i}: {a} != {b}"
    assert len(ours) == len(theirs)


def condense(values):
    out = []
    for step, v in values:
        if not out or out[-1][1] != v:
            out.append((step, v))
    return out


@pytest.mark.parametrize("seed", range(6))
def test_changes_match_reelay(rvc, tmp_path, seed):
    reelay = pytest.importorskip("reelay")
    rng = random.Random(2800 + seed)
    formulas = suite(rng, 40, dense=False)
    events = trace(rng, 120, dense=False)
    proc = rvc_run(rvc, tmp_path, formulas, events, [])
    assert proc.returncode in (0, 1), proc.stderr
    ours = {f"f{i}": [] for i in range(len(formulas))}
    for line in proc.stdout.splitlines():
        v = json.loads(line)
        ours[v["property"]].append((v["time"], v["value"]))
    for i, f in enumerate(formulas):
        m = reelay.discrete_timed_monitor(pattern=f, condense=False)
        theirs = condense([(step, m.update(dict(e))["value"]) for step, e in enumerate(events)])
        assert ours[f"f{i}"] == theirs, f"formula: {f}\ntrace: {json.dumps(events)}"
