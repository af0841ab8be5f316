"""Timescales: for the 10 families, rvc's verdicts on generated traces agree
with Reelay's at every step, discrete and dense, for the published formulas
and AbsentBQR's intended bracketing. Generated traces satisfy their property,
so each trace is also mutated (a few flipped values) to exercise violations.
"""
import json
import random
import subprocess

import pytest

reelay = pytest.importorskip("reelay")

FAMILIES = ["AbsentAQ", "AbsentBQR", "AbsentBR", "AlwaysAQ", "AlwaysBQR",
            "AlwaysBR", "RecurBQR", "RecurGLB", "RespondBQR", "RespondGLB"]


def generate(rvc, family, ubound, steps, seed):
    out = subprocess.run([rvc, "timescales", family, "--ubound", str(ubound), "--duration", str(steps),
                          "--seed", str(seed)], capture_output=True, text=True, check=True).stdout
    return [json.loads(line) for line in out.splitlines()]


def formula(rvc, family, ubound, intended):
    args = [rvc, "timescales", family, "--ubound", str(ubound), "--formula"] + (["--intended"] if intended else [])
    return subprocess.run(args, capture_output=True, text=True, check=True).stdout.strip()


def mutate(events, seed, rate=0.002):
    rng = random.Random(seed)
    out = []
    for e in events:
        e = dict(e)
        for k in ("p", "q", "r", "s"):
            if k in e and rng.random() < rate:
                e[k] = not e[k]
        out.append(e)
    return out


def rvc_check(rvc, tmp_path, spec, events, dense):
    path = tmp_path / "trace.jsonl"
    path.write_text("".join(json.dumps(e) + "\n" for e in events))
    # Dense: --clock off, no tick at the trace's end (Reelay reports nothing for the last message's instant).
    args = [rvc, "check", "--spec", spec, str(path)] + (["--dense", "--origin", "zero", "--clock", "off"] if dense else ["--all"])
    proc = subprocess.run(args, capture_output=True, text=True)
    assert proc.returncode in (0, 1), proc.stderr
    return [(json.loads(l)["time"], json.loads(l)["value"]) for l in proc.stdout.splitlines()]


@pytest.mark.parametrize("family", FAMILIES)
@pytest.mark.parametrize("ubound", [10, 100])
def test_discrete_timescales_match_reelay(rvc, tmp_path, family, ubound):
    events = generate(rvc, family, ubound, 6000, seed=ubound)
    for intended in ([False, True] if family == "AbsentBQR" else [False]):
        spec = formula(rvc, family, ubound, intended)
        for trace, label in ((events, "generated"), (mutate(events, ubound), "mutated")):
            ours = rvc_check(rvc, tmp_path, spec, trace, dense=False)
            m = reelay.discrete_timed_monitor(pattern=spec, condense=False)
            theirs = [(i, m.update(dict(e))["value"]) for i, e in enumerate(trace)]
            assert ours == theirs, f"{family}{ubound} {label}: first difference at step " + str(
                next(i for i, (a, b) in enumerate(zip(ours, theirs)) if a != b))
            if label == "generated":
                assert all(v for _, v in ours), f"{family}{ubound}: the generated trace should satisfy {spec}"


@pytest.mark.parametrize("family", FAMILIES)
def test_dense_timescales_match_reelay(rvc, tmp_path, family):
    # Integer times and bounds: every change point falls on a message, where
    # Reelay's dense monitors are exact, so the raw trace is a fair oracle.
    events = mutate(generate(rvc, family, 10, 1500, seed=3), 3, rate=0.01)
    spec = formula(rvc, family, 10, intended=True)
    ours = rvc_check(rvc, tmp_path, spec, events, dense=True)
    m = reelay.dense_timed_monitor(pattern=spec)
    theirs = []
    for e in events:
        for r in m.update(dict(e)):
            if not theirs or theirs[-1][1] != r["value"]:
                theirs.append((r["time"], r["value"]))
    assert ours == theirs
