"""Bounded future in dense time (issue 29): rvc's delayed verdicts equal an independent interval
oracle, on random formulas mixing eventually/always with once/historically and Boolean
connectives, Boolean semantics, including the end of the stream.

RTAMT's dense-time online monitor interprets its samples differently (and has no until), so the
oracle here is a direct implementation of the definitions over piecewise-constant signals, each a
list of disjoint half-open intervals [u, w) where it holds, inside the stream's domain [0, T):
  once[a:b] φ holds at t iff [t-b, t-a] meets φ's set:        [u, w) -> [u+a, w+b)
  eventually[a:b] φ holds at t iff [t+a, t+b] meets φ's set:  [u, w) -> [u-b, w-a)
historically and always are their duals (not ... not, the complement taken inside [0, T)), so
windows are cut to the stream at both ends (docs/semantics.md, "Bounded future"). Times and bounds
are multiples of 0.25: every instant is exact in binary. rvc runs with --clock off (the stream is
[0, last stamp)); its changes, shifted to the instants they are about, give its sets.
"""
import json
import os
import random
import subprocess

import pytest

CASES = int(os.environ.get("RVC_DIFF_CASES", "60"))
FORMULAS_PER_CASE = 8
ATOMS = {"{p}": lambda e: e["p"], "{q}": lambda e: e["q"], "{x > 2}": lambda e: e["x"] > 2}


def norm(ivs):
    out = []
    for u, w in sorted(ivs):
        if w <= u:
            continue
        if out and u <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], w))
        else:
            out.append((u, w))
    return out


def clip(ivs, T):
    return norm([(max(u, 0), min(w, T)) for u, w in ivs])


def complement(ivs, T):
    out, at = [], 0
    for u, w in ivs:
        out.append((at, u))
        at = w
    out.append((at, T))
    return norm(out)


def intersect(a, b):
    out = []
    for u1, w1 in a:
        for u2, w2 in b:
            out.append((max(u1, u2), min(w1, w2)))
    return norm(out)


def evaluate(f, atoms, T):
    op = f[0]
    if op == "atom":
        return atoms[f[1]]
    if op == "not":
        return complement(evaluate(f[1], atoms, T), T)
    if op in ("and", "or", "implies"):
        a, b = evaluate(f[1], atoms, T), evaluate(f[2], atoms, T)
        if op == "and":
            return intersect(a, b)
        if op == "or":
            return norm(a + b)
        return norm(complement(a, T) + b)
    lo, hi, sub = f[1], f[2], f[3]
    if op == "once":
        return clip([(u + lo, w + hi) for u, w in evaluate(sub, atoms, T)], T)
    if op == "eventually":
        return clip([(u - hi, w - lo) for u, w in evaluate(sub, atoms, T)], T)
    dual = {"historically": "once", "always": "eventually"}[op]
    return complement(evaluate((dual, lo, hi, ("not", sub)), atoms, T), T)


def text(f):
    op = f[0]
    if op == "atom":
        return f[1]
    if op == "not":
        return f"not ({text(f[1])})"
    if op in ("and", "or", "implies"):
        return f"({text(f[1])}) {op} ({text(f[2])})"
    return f"{op}[{f[1]}:{f[2]}] ({text(f[3])})"


def horizon(f):
    op = f[0]
    if op == "atom":
        return 0
    if op == "not":
        return horizon(f[1])
    if op in ("and", "or", "implies"):
        return max(horizon(f[1]), horizon(f[2]))
    return horizon(f[3]) + (f[2] if op in ("eventually", "always") else 0)


def formula(rng, depth, future):
    if depth == 0 or rng.random() < 0.2:
        return ("atom", rng.choice(list(ATOMS)))
    op = rng.choice(["not", "and", "or", "implies", "once", "historically", "eventually", "always",
                     "eventually", "always"])
    sub = lambda: formula(rng, depth - 1, future)
    if op == "not":
        return ("not", sub())
    if op in ("and", "or", "implies"):
        return (op, sub(), sub())
    lo = rng.choice([0, 0, 0.25, 0.5, 1, 2])
    hi = lo + rng.choice([0, 0.25, 0.5, 1, 1.5, 3])
    return (op, lo, hi, sub())


def trace(rng):
    events, t = [], 0.0
    for _ in range(rng.randint(3, 14)):
        events.append({"time": t, "p": rng.random() < 0.5, "q": rng.random() < 0.5, "x": rng.randint(0, 4)})
        t += rng.choice([0.25, 0.5, 0.75, 1, 1.5, 2])
    return events


def atom_sets(events):
    T = events[-1]["time"]
    sets = {}
    for name, test in ATOMS.items():
        sets[name] = norm([(e["time"], n["time"]) for e, n in zip(events, events[1:]) if test(e)])
    return sets, T


def rvc_sets(rvc, tmp_path, formulas, events):
    props = tmp_path / "props.json"
    props.write_text(json.dumps({"properties": [{"name": f"f{i}", "spec": text(f)} for i, f in enumerate(formulas)]}))
    tr = tmp_path / "trace.jsonl"
    tr.write_text("".join(json.dumps(e) + "\n" for e in events))
    proc = subprocess.run([rvc, "check", "--dense", "--origin", "zero", "--clock", "off", "--properties", str(props), str(tr)],
                          capture_output=True, text=True)
    assert proc.returncode in (0, 1), proc.stderr
    T = events[-1]["time"]
    changes = {f"f{i}": [] for i in range(len(formulas))}
    for line in proc.stdout.splitlines():
        v = json.loads(line)
        changes[v["property"]].append((v["time"], v["value"], v.get("known_at", v["time"])))
    out = {}
    for name, cs in changes.items():
        ivs = []
        for k, (t, value, _) in enumerate(cs):
            end = cs[k + 1][0] if k + 1 < len(cs) else T
            if value:
                ivs.append((t, end))
        out[name] = (norm(ivs), cs)
    return out


@pytest.mark.parametrize("seed", range(CASES))
def test_dense_boolean_matches_interval_oracle(rvc, tmp_path, seed):
    rng = random.Random(seed)
    formulas = [formula(rng, rng.randint(1, 4), True) for _ in range(FORMULAS_PER_CASE)]
    events = trace(rng)
    atoms, T = atom_sets(events)
    got = rvc_sets(rvc, tmp_path, formulas, events)
    for i, f in enumerate(formulas):
        want = evaluate(f, atoms, T)
        ours, changes = got[f"f{i}"]
        assert ours == want, f"seed {seed}: {text(f)}\nrvc {ours}\noracle {want}\nchanges {changes}\n{events}"
        h = horizon(f)
        # Each change is known h later, or when the stream ends (T): never before the instant + h.
        for t, _, known in changes:
            assert known == min(t + h, T) or (h == 0 and known == t), (text(f), t, known, h, T)
        # The first verdict is about 0.
        assert not changes or changes[0][0] == 0


# ---- Robustness: the same formulas over numeric atoms, against a grid oracle ----------------------
# Every breakpoint is a multiple of 0.25 (stamps and bounds), so each signal is constant on the cells
# [k/4, (k+1)/4): the oracle computes one value per cell. once[a:b] at t takes the max over the
# cells meeting [t-b, t-a] inside [0, T) (-inf when none), eventually over [t+a, t+b]; historically
# and always the min (+inf when none); not negates, and/or/implies are min/max, as RTAMT and Reelay.
STEP = 0.25
ROBUST_ATOMS = {"{x > 2}": lambda e: e["x"] - 2, "{y < 1}": lambda e: 1 - e["y"]}


def robust_cells(f, atoms, n):
    op = f[0]
    if op == "atom":
        return atoms[f[1]]
    if op == "not":
        return [-v for v in robust_cells(f[1], atoms, n)]
    if op in ("and", "or", "implies"):
        a, b = robust_cells(f[1], atoms, n), robust_cells(f[2], atoms, n)
        if op == "implies":
            a = [-v for v in a]
        return [min(x, y) if op == "and" else max(x, y) for x, y in zip(a, b)]
    lo, hi, sub = int(f[1] / STEP), int(f[2] / STEP), robust_cells(f[3], atoms, n)
    out = []
    for k in range(n):
        cells = range(k - hi, k - lo + 1) if op in ("once", "historically") else range(k + lo, k + hi + 1)
        vals = [sub[c] for c in cells if 0 <= c < n]
        if op in ("once", "eventually"):
            out.append(max(vals) if vals else float("-inf"))
        else:
            out.append(min(vals) if vals else float("inf"))
    return out


def robust_formula(rng, depth):
    f = formula(rng, depth, True)

    def swap(g):
        if g[0] == "atom":
            return ("atom", rng.choice(list(ROBUST_ATOMS)))
        if g[0] == "not":
            return ("not", swap(g[1]))
        if g[0] in ("and", "or", "implies"):
            return (g[0], swap(g[1]), swap(g[2]))
        return (g[0], g[1], g[2], swap(g[3]))
    return swap(f)


@pytest.mark.parametrize("seed", range(CASES))
def test_dense_robustness_matches_grid_oracle(rvc, tmp_path, seed):
    rng = random.Random(20_000 + seed)
    formulas = [robust_formula(rng, rng.randint(1, 4)) for _ in range(FORMULAS_PER_CASE)]
    events = trace(rng)
    for e in events:
        e["y"] = rng.choice([-1.5, 0.25, 0.5, 2, 3.25])
    T = events[-1]["time"]
    n = int(T / STEP)
    atoms = {name: [] for name in ROBUST_ATOMS}
    for k in range(n):
        e = [e for e in events if e["time"] <= k * STEP][-1]
        for name, margin in ROBUST_ATOMS.items():
            atoms[name].append(float(margin(e)))
    props = tmp_path / "props.json"
    props.write_text(json.dumps({"properties": [{"name": f"f{i}", "spec": text(f)} for i, f in enumerate(formulas)]}))
    tr = tmp_path / "trace.jsonl"
    tr.write_text("".join(json.dumps(e) + "\n" for e in events))
    proc = subprocess.run([rvc, "check", "--dense", "--origin", "zero", "--robustness", "--clock", "off", "--properties", str(props),
                           str(tr)], capture_output=True, text=True)
    assert proc.returncode in (0, 1), proc.stderr
    changes = {f"f{i}": [] for i in range(len(formulas))}
    for line in proc.stdout.splitlines():
        v = json.loads(line)
        value = v["value"]
        value = {"inf": float("inf"), "-inf": float("-inf")}.get(value, value) if isinstance(value, str) else value
        changes[v["property"]].append((v["time"], float(value)))
    for i, f in enumerate(formulas):
        want = robust_cells(f, atoms, n)
        cs = changes[f"f{i}"]
        ours = []
        for k in range(n):
            at = [v for t, v in cs if t <= k * STEP]
            ours.append(at[-1] if at else None)
        assert ours == want, f"seed {seed}: {text(f)}\nrvc {cs}\noracle {want}\n{events}"
