"""Bounded future (issue 29): hand-computed verdicts at the horizon's edges, at the stream's start
and end, in discrete and dense time, and the parser's refusals (docs/semantics.md, "Bounded future").

Oracle: each expected verdict list is worked out by hand from the definitions in the comments
(eventually[a:b] φ at t: φ at some s in [t+a, t+b] inside the stream; always: at every such s
inside the stream; the verdict for t is known at t + horizon, or at the stream's last instant).
"""
import json
import subprocess


def run(rvc, tmp_path, events, specs, *extra):
    tr = tmp_path / "trace.jsonl"
    tr.write_text("".join(json.dumps(e) + "\n" for e in events))
    args = [rvc, "check", str(tr)] + [a for s in specs for a in ("--spec", s)] + list(extra)
    return subprocess.run(args, capture_output=True, text=True)


def verdicts(proc):
    return [(v["property"], v["time"], v["value"], v.get("known_at")) for v in map(json.loads, proc.stdout.splitlines())]


P = [{"p": False}, {"p": False}, {"p": True}, {"p": False}, {"p": False}]


def test_discrete_eventually_every_step_with_its_delay(rvc, tmp_path):
    got = run(rvc, tmp_path, P, ["eventually[1:2]{p}"], "--all")
    assert got.returncode == 1, got.stderr
    # p only at step 2. t=0: steps 1..2 -> true; t=1: 2..3 -> true; t=2: 3..4 -> false; t=3: 4 (5 is past the
    # end) -> false; t=4: nothing left -> false. Known at t+2, the last two when the stream ends (step 4).
    assert verdicts(got) == [("p1", 0, True, 2), ("p1", 1, True, 3), ("p1", 2, False, 4), ("p1", 3, False, 4),
                             ("p1", 4, False, 4)]


def test_discrete_condensed_changes_carry_the_time_they_refer_to(rvc, tmp_path):
    got = run(rvc, tmp_path, P, ["eventually[1:2]{p}", "historically{p: false}"])
    # Changes only, in the order they become known: the past-only p2 at once, p1 two steps late.
    assert verdicts(got) == [("p2", 0, True, None), ("p1", 0, True, 2), ("p2", 2, False, None), ("p1", 2, False, 4)]


def test_point_window_and_until_at_the_horizon_edges(rvc, tmp_path):
    got = run(rvc, tmp_path, P, ["eventually[2:2]{p}", "{p} until[1:2] (not {p})", "always[0:0]{p}"], "--all")
    by = {}
    for name, t, v, known in verdicts(got):
        by.setdefault(name, []).append((t, v, known))
    # eventually[2:2]: p at t+2 -> only t=0.
    assert by["p1"] == [(0, True, 2), (1, False, 3), (2, False, 4), (3, False, 4), (4, False, 4)]
    # until[1:2]: some J in [t+1, t+2] with not p, p on [t, J). t=0: p(0) false; t=1: J=2 has p, J=3 needs
    # p(1), p(2): p(1) false; t=2: J=3, p(2) true -> true; t=3: J=4, p(3) false; t=4: no J in the stream.
    assert by["p2"] == [(0, False, 2), (1, False, 3), (2, True, 4), (3, False, 4), (4, False, 4)]
    # always[0:0] is the step itself, known at once (horizon 0: no delay, no known_at).
    assert by["p3"] == [(t, e["p"], None) for t, e in enumerate(P)]


def test_end_of_stream_cuts_the_windows(rvc, tmp_path):
    events = [{"p": True}, {"p": True}, {"p": True}]
    got = run(rvc, tmp_path, events, ["always[0:5]{p}", "next {p}", "eventually[1:3]{p}"], "--all")
    by = {}
    for name, t, v, known in verdicts(got):
        by.setdefault(name, []).append((t, v, known))
    # always: only the steps the stream has -> true; next at the last step: no next step -> false;
    # eventually[1:3] at the last step: no witness inside the stream -> false. All known at step 2.
    assert by["p1"] == [(0, True, 2), (1, True, 2), (2, True, 2)]
    assert by["p2"] == [(0, True, 1), (1, True, 2), (2, False, 2)]
    assert by["p3"] == [(0, True, 2), (1, True, 2), (2, False, 2)]


def test_past_operators_see_nothing_before_the_start(rvc, tmp_path):
    # once[0:3](not p) with p always true is false at every step; beside a future operator it is
    # checked 1 step late, and must not read the delayed p's "before the start" as false.
    events = [{"p": True, "q": False}] * 4
    got = run(rvc, tmp_path, events, ["(once[0:3] (not {p})) or eventually[0:1]{q}",
                                      "historically[0:2]{p} and eventually[0:1]{p}"], "--all")
    assert [(n, t, v) for n, t, v, _ in verdicts(got) if n == "p1"] == [("p1", t, False) for t in range(4)]
    assert [(n, t, v) for n, t, v, _ in verdicts(got) if n == "p2"] == [("p2", t, True) for t in range(4)]


def test_discrete_robustness(rvc, tmp_path):
    events = [{"x": 0}, {"x": 5}, {"x": 1}]
    got = run(rvc, tmp_path, events, ["eventually[0:1]{x > 2}"], "--all", "--robustness")
    # max of x - 2 over [t, t+1] inside the stream: max(-2, 3), max(3, -1), -1.
    assert verdicts(got) == [("p1", 0, 3, 1), ("p1", 1, 3, 2), ("p1", 2, -1, 2)]


LOWEST = -1.7976931348623157e308  # the start of an unbounded once (highest: historically), docs/semantics.md


def robust_value(v):
    return float(v) if isinstance(v, str) else v  # "inf"/"-inf" on verdict lines


def test_discrete_robustness_past_operators_beside_a_future_one_start_as_written(rvc, tmp_path):
    """A past operator checked at a delay (beside next/eventually) starts from the value the table
    gives it alone: unbounded once/historically from the lowest/highest finite double, pre at the
    first step the lowest finite double; bounded windows from -inf/+inf. Oracle: the table's rules
    evaluated in Python on random traces with fields missing at the start (margins -inf)."""
    import random
    inf = float("inf")
    rng = random.Random(36)
    for trial in range(25):
        n = rng.randint(1, 6)
        events = [{k: rng.randint(-3, 3) for k in ("p", "q", "x") if rng.random() < 0.5} for _ in range(n)]
        if trial == 0:
            events = [{"q": 1}, {"q": 1}, {"p": 1, "x": 1}]  # p and x unseen at first
        sig = {}
        for k in ("p", "q", "x"):
            cur, sig[k] = -inf, []
            for e in events:
                cur = e.get(k, cur) if k in e else cur
                sig[k].append(cur)
        nxt = lambda s, t: s[t + 1] if t + 1 < n else -inf  # strong next: -inf past the end
        def scan(op, start, f):  # unbounded once (max) / historically (min) of f(t)
            out, acc = [], start
            for t in range(n):
                acc = op(acc, f(t))
                out.append(acc)
            return out
        once_p = scan(max, LOWEST, lambda t: sig["p"][t])
        hist_q = scan(min, -LOWEST, lambda t: sig["q"][t])
        hist_not_p = scan(min, -LOWEST, lambda t: -sig["p"][t])
        once12_p = [max([sig["p"][s] for s in range(max(0, t - 2), t)], default=-inf) for t in range(n)]
        expected = {
            "pre (next {x > 0})": [LOWEST if t == 0 else nxt(sig["x"], t - 1) for t in range(n)],
            "(once {p}) or (next {p})": [max(once_p[t], nxt(sig["p"], t)) for t in range(n)],
            "(historically {q}) and (next {q})": [min(hist_q[t], nxt(sig["q"], t)) for t in range(n)],
            "(historically not {p}) and (next not {p})": [min(hist_not_p[t], nxt([-v for v in sig["p"]], t))
                                                          for t in range(n)],
            "(once[1:2] {p}) or (next {p})": [max(once12_p[t], nxt(sig["p"], t)) for t in range(n)],
        }
        for spec, want in expected.items():
            got = run(rvc, tmp_path, events, [spec], "--all", "--robustness")
            assert got.returncode in (0, 1), got.stderr
            values = [robust_value(v) for _, _, v, _ in verdicts(got)]
            assert values == want, f"{spec} on {events}"


def test_past_only_lines_have_no_known_at(rvc, tmp_path):
    got = run(rvc, tmp_path, P, ["once{p}"], "--all")
    assert all("known_at" not in json.loads(l) for l in got.stdout.splitlines())
    assert len(got.stdout.splitlines()) == 5


DENSE = [{"time": 0, "p": False}, {"time": 0.5, "p": True}, {"time": 1.0, "p": False}, {"time": 3.0, "p": False}]


def test_dense_eventually_and_always(rvc, tmp_path):
    got = run(rvc, tmp_path, DENSE, ["eventually[0:1]{p}", "always[0:1]{p}"], "--dense")
    # p holds on [0.5, 1): eventually[0:1] is true for t in [-0.5, 1) -> true from 0, false from 1
    # (known 1 time unit later); always[0:1] never holds (p is false at t+1 or before).
    # (One message's verdicts come property by property: compared per property.)
    assert sorted(verdicts(got)) == [("p1", 0, True, 1), ("p1", 1, False, 2), ("p2", 0, False, 1)]


def test_dense_end_of_stream(rvc, tmp_path):
    events = [{"time": 0, "p": True}, {"time": 1, "p": True}, {"time": 2, "p": False}]
    got = run(rvc, tmp_path, events, ["always[0:1]{p}", "eventually[0:1]{p}"], "--dense")
    # The end tick at 2 counts the last message's instant (p false at 2): always[0:1] fails from t=1
    # (its window reaches 2); eventually[0:1] holds until t=2, whose window is {2} only. The end's
    # verdicts are known at 2.
    assert verdicts(got) == [("p1", 0, True, 1), ("p2", 0, True, 1), ("p1", 1, False, 2), ("p2", 2, False, 2)]
    off = run(rvc, tmp_path, events, ["always[0:1]{p}"], "--dense", "--clock", "off")
    # Without the end tick the stream is [0, 2): p held all along.
    assert verdicts(off) == [("p1", 0, True, 1)]
    one = run(rvc, tmp_path, [{"time": 0, "p": True}], ["always[0:5]{p}", "eventually[0:1]{p}"], "--dense")
    # A stream of one instant: both decided by p at 0, known at 0.
    assert sorted(verdicts(one)) == [("p1", 0, True, 0), ("p2", 0, True, 0)]


def test_refusals(rvc, tmp_path):
    cases = [
        (["eventually {p}"], [], "unbounded future: 'eventually' needs an upper time bound"),
        (["always[2:] {p}"], [], "unbounded future: 'always' needs an upper time bound"),
        (["{p} until {q}"], [], "unbounded future: 'until' needs an upper time bound"),
        (["next[1:2] {p}"], [], "'next' takes no time bounds"),
        (["next {p}"], ["--dense"], "'next' has no meaning in dense time"),
        (["{p} until[0:1] {q}"], ["--dense"], "'until' is not supported in dense time"),
        (["({p} until[0:1] {q}) until[0:1] {p}"], [], None),
        (["{p} until[0:1] {q} until[0:1] {p}"], [], "chained 'until' is ambiguous"),
        (["{p} until[0:300] {q}"], [], "until[a:b] with b - a >= 256"),
        (["exists[x]. eventually[0:1] {id: *x}"], [], "with exists/forall is not supported"),
    ]
    for specs, extra, message in cases:
        got = run(rvc, tmp_path, [{"time": 0, "p": True, "q": True, "id": 1}], specs, *extra)
        if message is None:
            assert got.returncode in (0, 1), got.stderr
            continue
        assert got.returncode == 2, (specs, got.returncode, got.stderr)
        assert message in got.stderr, (specs, got.stderr)


def test_random_future_grammar_never_crashes(rvc, tmp_path):
    """A seeded grammar fuzz of the extended syntax through `rvc check` (the libFuzzer harness
    tests/fuzz/fuzz_spec.cpp covers the parser and engine under ASan): well-formed and broken
    mixes of future and past operators, bounds and parentheses end as verdicts (exit 0/1) or as a
    spec error naming a column (exit 2), never as a crash or another status."""
    import random
    rng = random.Random(29)
    words = ["eventually", "always", "next", "until", "since", "once", "historically", "pre", "not", "and", "or",
             "->", "(", ")", "{p}", "{q}", "{x > 2}", "[0:2]", "[1:]", "[:3]", "[2:1]", "[0:0]", "[0:999999]",
             "[0.5:1]", "[", "]", "true"]
    tr = tmp_path / "t.jsonl"
    tr.write_text("".join(json.dumps({"time": i * 0.5, "p": i % 2 == 0, "q": i % 3 == 0, "x": i}) + "\n"
                          for i in range(6)))
    seen = set()
    for _ in range(150):
        spec = " ".join(rng.choice(words) for _ in range(rng.randint(1, 9)))
        for extra in ([], ["--dense"], ["--robustness"]):
            got = subprocess.run([rvc, "check", str(tr), "--spec", spec] + extra, capture_output=True, text=True)
            assert got.returncode in (0, 1, 2), (spec, extra, got.returncode, got.stderr)
            if got.returncode == 2:
                assert "spec error at column" in got.stderr, (spec, got.stderr)
            seen.add(got.returncode)
    assert seen == {0, 1, 2}  # the mix reaches verdicts both ways and errors
