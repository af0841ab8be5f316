"""`rvc check` end to end: exit codes, error messages with positions, and
that bad input never costs a valid message. Expected values are hand-computed."""
import json
import subprocess


def run(rvc, *args, stdin=None):
    return subprocess.run([rvc, *args], input=stdin, capture_output=True, text=True)


def verdicts(stdout):
    return [(v["time"], v["property"], v["value"]) for v in map(json.loads, stdout.splitlines())]


def write(tmp_path, name, lines):
    p = tmp_path / name
    p.write_text("".join(l + "\n" for l in lines))
    return str(p)


def test_condensed_verdicts_and_exit_status(rvc, tmp_path):
    trace = write(tmp_path, "t.jsonl", ['{"p":true}', '{"p":true}', '{"p":false}', '{"p":true}'])
    r = run(rvc, "check", "--spec", "historically[:1]{p}", trace)
    # H[:1] p over T,T,F,T: T,T,F,F -> changes at 0 (true) and 2 (false)
    assert verdicts(r.stdout) == [(0, "p1", True), (2, "p1", False)]
    assert r.returncode == 1
    r = run(rvc, "check", "--all", "--spec", "once{p}", trace)
    assert verdicts(r.stdout) == [(i, "p1", True) for i in range(4)]
    assert r.returncode == 0


def test_stdin_and_many_properties(rvc):
    r = run(rvc, "check", "--spec", "{a}", "--spec", "pre {a}", "-", stdin='{"a":true}\n{"a":false}\n')
    assert verdicts(r.stdout) == [(0, "p1", True), (0, "p2", False), (1, "p1", False), (1, "p2", True)]


def test_properties_file_yaml_and_json(rvc, tmp_path):
    trace = write(tmp_path, "t.jsonl", ['{"speed": 10}', '{"speed": 30}'])
    y = tmp_path / "props.yaml"
    y.write_text("properties:\n  - name: slow\n    spec: '{speed < 20}'\n  - name: fast\n    spec: '{speed > 20}'\n")
    r = run(rvc, "check", "--properties", str(y), trace)
    assert verdicts(r.stdout) == [(0, "slow", True), (0, "fast", False), (1, "slow", False), (1, "fast", True)]
    j = tmp_path / "props.json"
    j.write_text(json.dumps({"slow": "{speed < 20}"}))
    r = run(rvc, "check", "--properties", str(j), trace)
    assert verdicts(r.stdout) == [(0, "slow", True), (1, "slow", False)]


def test_bad_spec_points_at_the_column(rvc, tmp_path):
    trace = write(tmp_path, "t.jsonl", ['{"p":true}'])
    r = run(rvc, "check", "--spec", "once[:2 {p}", trace)
    assert r.returncode == 2
    assert "column 9" in r.stderr and "expected ']'" in r.stderr
    lines = r.stderr.splitlines()
    caret = lines[-1]
    source = lines[-2]
    assert source.strip() == "once[:2 {p}"
    assert caret.index("^") - source.index("o") == 8   # under '{', the 9th character
    assert r.stdout == ""


def test_malformed_lines_are_reported_and_valid_ones_kept(rvc, tmp_path):
    trace = write(tmp_path, "t.jsonl", [
        '{"p":true}',          # line 1
        '{"p":',               # line 2: truncated
        'not json',            # line 3
        '[1, 2]',              # line 4: not an object
        '',                    # line 5: blank, ignored
        '{"p":false}',         # line 6
        '{"p":"yes"}',         # line 7: wrong type -> warning, keeps false
        '{"p":true}',          # line 8
    ])
    r = run(rvc, "check", "--all", "--spec", "{p}", trace)
    # valid messages: lines 1, 6, 7, 8 -> steps 0..3 with p = T, F, F(kept), T; {p} fails at step 1
    assert [v for _, _, v in verdicts(r.stdout)] == [True, False, False, True]
    assert r.returncode == 1
    assert "found: not json" in r.stderr
    for n in (2, 3, 4):
        assert f"line {n}" in r.stderr
    assert "line 7" in r.stderr and "keeps its previous value" in r.stderr
    assert "line 5" not in r.stderr and "line 6" not in r.stderr


def test_exit_status_prefers_violation_over_rejects(rvc, tmp_path):
    trace = write(tmp_path, "t.jsonl", ['{"p":true}', 'oops', '{"p":false}'])
    r = run(rvc, "check", "--spec", "{p}", trace)
    assert r.returncode == 1
    trace = write(tmp_path, "u.jsonl", ['{"p":true}', 'oops', '{"p":true}'])
    r = run(rvc, "check", "--spec", "{p}", trace)
    assert r.returncode == 3 and "line 2" in r.stderr


def test_dense_time_order_errors(rvc, tmp_path):
    trace = write(tmp_path, "t.jsonl", [
        '{"time": 0, "p": true}',
        '{"time": 2, "p": false}',
        '{"time": 1, "p": true}',   # line 3: goes back in time
        '{"time": 2, "p": true}',   # line 4: not after 2
        '{"p": true}',              # line 5: no time
        '{"time": 5, "p": true}',
        '{"time": 7}',
    ])
    r = run(rvc, "check", "--dense", "--spec", "{p}", trace)
    # p: T on [0,2), F on [2,5), T on [5,7)
    assert verdicts(r.stdout) == [(0, "p1", True), (2, "p1", False), (5, "p1", True)]
    assert "line 3" in r.stderr and "not after the previous" in r.stderr
    assert "line 4" in r.stderr and "line 5" in r.stderr and "missing time field" in r.stderr


def test_strict_mode_rejects_missing_fields(rvc, tmp_path):
    trace = write(tmp_path, "t.jsonl", ['{"p":true,"q":1}', '{"p":false}', '{"q":2,"p":true}'])
    r = run(rvc, "check", "--all", "--spec", "{p} and {q > 0}", trace)
    assert [v for _, _, v in verdicts(r.stdout)] == [True, False, True]   # q held at 1
    r = run(rvc, "check", "--all", "--strict", "--spec", "{p} and {q > 0}", trace)
    assert [v for _, _, v in verdicts(r.stdout)] == [True, True]          # line 2 rejected
    assert 'line 2: missing field "q"' in r.stderr and r.returncode == 3


def test_oversized_message_is_skipped(rvc, tmp_path):
    big = '{"p": false, "pad": "' + "x" * 5000 + '"}'
    trace = write(tmp_path, "t.jsonl", ['{"p":true}', big, '{"p":true}'])
    r = run(rvc, "check", "--all", "--max-message-size", "1000", "--spec", "{p}", trace)
    assert [v for _, _, v in verdicts(r.stdout)] == [True, True]
    assert "line 2" in r.stderr and "longer than 1000" in r.stderr


def test_unreadable_trace(rvc, tmp_path):
    r = run(rvc, "check", "--spec", "{p}", str(tmp_path / "nope.jsonl"))
    assert r.returncode == 2 and "nope.jsonl" in r.stderr


def test_timescales_is_deterministic(rvc):
    a = run(rvc, "timescales", "RespondGLB", "--ubound", "100", "--duration", "5000", "--seed", "9").stdout
    b = run(rvc, "timescales", "RespondGLB", "--ubound", "100", "--duration", "5000", "--seed", "9").stdout
    c = run(rvc, "timescales", "RespondGLB", "--ubound", "100", "--duration", "5000", "--seed", "10").stdout
    assert a == b and a != c and len(a.splitlines()) == 5000


def test_explain_names_the_deciding_subformulas_and_steps(rvc, tmp_path):
    trace = write(tmp_path, "e.jsonl", [
        '{"emergency":false,"hazard":false}', '{"emergency":true,"hazard":true}', '{"emergency":true,"hazard":false}',
        '{"emergency":true,"hazard":false}', '{"emergency":false,"hazard":false}'])
    r = run(rvc, "check", "--explain", "--spec", "historically({emergency} -> once[0:1]{hazard})",
            "--spec", "{emergency} or {hazard}", trace)
    assert r.returncode == 1, r.stderr
    assert [json.loads(l) for l in r.stdout.splitlines()] == [
        {"time": 0, "property": "p1", "value": True},
        {"time": 0, "property": "p2", "value": False, "explain": [
            "{emergency} is false at step 0", "{hazard} is false at step 0"]},
        {"time": 1, "property": "p2", "value": True},
        {"time": 3, "property": "p1", "value": False, "explain": [
            "(historically ({emergency} implies (once[:1] {hazard}))) is false: ({emergency} implies "
            "(once[:1] {hazard})) failed at least once at steps 0..3",
            "{emergency} is true at step 3",
            "(once[:1] {hazard}) is false: {hazard} never held at steps 2..3",
            "{hazard} is false at step 3"]},
        {"time": 4, "property": "p2", "value": False, "explain": [
            "{emergency} is false at step 4", "{hazard} is false at step 4"]},
    ]
    # Without --explain the verdicts are the same, without the reasons.
    plain = run(rvc, "check", "--spec", "historically({emergency} -> once[0:1]{hazard})",
                "--spec", "{emergency} or {hazard}", trace)
    assert [json.loads(l) for l in plain.stdout.splitlines()] == [
        {k: v for k, v in json.loads(l).items() if k != "explain"} for l in r.stdout.splitlines()]


def test_explain_in_dense_time_and_with_data_references(rvc, tmp_path):
    """--explain beyond discrete Boolean properties: dense time names intervals in seconds (a verdict
    may start between two messages), data references name the value that decided. Sentences written
    by hand; the verdicts are those without --explain; robustness values are refused."""
    def explained(args, trace):
        r = run(rvc, "check", "--explain", *args, trace)
        assert r.returncode == 1, r.stderr
        plain = run(rvc, "check", *args, trace)
        assert plain.returncode == 1, plain.stderr
        lines = [json.loads(l) for l in r.stdout.splitlines()]
        assert [json.loads(l) for l in plain.stdout.splitlines()] == [
            {k: v for k, v in l.items() if k != "explain"} for l in lines]
        return lines

    trace = write(tmp_path, "d.jsonl", [
        '{"time":0,"emergency":false,"hazard":false,"brake":true}',
        '{"time":1,"emergency":true,"hazard":true,"brake":false}',
        '{"time":2,"emergency":true,"hazard":false,"brake":false}',
        '{"time":4,"emergency":false,"hazard":false,"brake":false}'])
    # once[0:1]{hazard} holds on [1, 3): the implication fails at 3, inside [2, 4); brake held on
    # [0, 1), so once[0:1.5]{brake} ends at 2.5.
    assert explained(["--dense", "--spec", "historically({emergency} -> once[0:1]{hazard})",
                      "--spec", "once[0:1.5]{brake}"], trace) == [
        {"time": 0, "property": "p1", "value": True},
        {"time": 0, "property": "p2", "value": True},
        {"time": 3, "property": "p1", "value": False, "explain": [
            "(historically ({emergency} implies (once[:1] {hazard}))) is false: ({emergency} implies "
            "(once[:1] {hazard})) failed at least once in [0, 3]",
            "{emergency} is true throughout [2, 4)",
            "(once[:1] {hazard}) is false: {hazard} never held in [2, 3]",
            "{hazard} is false throughout [2, 4)"]},
        {"time": 2.5, "property": "p2", "value": False, "explain": [
            "(once[:1.5] {brake}) is false: {brake} never held in [1, 2.5]",
            "{brake} is false throughout [2, 4)"]},
    ]

    ops = write(tmp_path, "ops.jsonl", [
        '{"op":"open","file":"a.txt"}', '{"op":"close","file":"a.txt"}', '{"op":"close","file":"b.txt"}'])
    body = ('(({op == "close"} and {file: *f}) implies (pre (once ({op == "open"} and {file: *f}))))')
    b = 'for f = "b.txt": '
    assert explained(["--spec", "forall[f]. ({op: close, file: *f} -> pre(once{op: open, file: *f}))"], ops) == [
        {"time": 0, "property": "p1", "value": True},
        {"time": 2, "property": "p1", "value": False, "explain": [
            "(forall[f]. " + body + ") is false: " + body + ' is false for f = "b.txt"',
            b + '{op == "close"} is true at step 2',
            b + "{file: *f} is true at step 2",
            b + '(pre (once ({op == "open"} and {file: *f}))) is false: (once ({op == "open"} and {file: *f})) '
                "was false at step 1"]},
    ]

    # Dense: "a" opened on [0, 0.5), closed at 1: once[0:1] of its opening ends at 1.5.
    files = write(tmp_path, "files.jsonl", [
        '{"time":0,"open":"a"}', '{"time":0.5,"open":"b"}', '{"time":1,"close":"a"}', '{"time":3}'])
    a = 'for f = "a": '
    assert explained(["--dense", "--spec", "forall[f]. ({close: *f} -> once[0:1]{open: *f})"], files) == [
        {"time": 0, "property": "p1", "value": True},
        {"time": 1.5, "property": "p1", "value": False, "explain": [
            "(forall[f]. ({close: *f} implies (once[:1] {open: *f}))) is false: ({close: *f} implies "
            '(once[:1] {open: *f})) is false for f = "a"',
            a + "{close: *f} is true throughout [1, 3)",
            a + "(once[:1] {open: *f}) is false: {open: *f} never held in [0.5, 1.5]",
            a + "{open: *f} is false throughout [1, 3)"]},
    ]

    r = run(rvc, "check", "--robustness", "--explain", "--spec", "{x > 1}", trace)
    assert r.returncode == 2 and "not --robustness values" in r.stderr, r.stderr


def test_data_references_values_limits_and_refusals(rvc, tmp_path):
    """exists/forall from the command line: bound values keep their JSON type (3 and "3" differ,
    3 and 3.0 do not); a field that cannot be bound keeps the last value with a warning (strict:
    rejected); --max-data-values stops the run with an error naming property and variable; specs
    with unbound variables point at them; robustness and synchronized inputs refuse references."""
    trace = tmp_path / "ids.jsonl"
    trace.write_text("".join(json.dumps(e) + "\n" for e in
                             [{"id": 3}, {"id": "3"}, {"id": "3"}, {"id": 3.0}, {"id": 3}, {"id": [1]}, {"id": True}]))
    spec = "exists[x]. ({id: *x} and pre{id: *x})"  # the same id twice in a row
    r = subprocess.run([rvc, "check", "--all", "--spec", spec, str(trace)], capture_output=True, text=True)
    values = [json.loads(line)["value"] for line in r.stdout.splitlines()]
    assert values == [False, False, True, False, True, True, False], r.stdout
    assert 'line 6: field "id" is an array, but {id: *x} needs a string, number or Boolean to bind' in r.stderr
    r = subprocess.run([rvc, "check", "--strict", "--spec", spec, str(trace)], capture_output=True, text=True)
    assert r.returncode == 1 and "rejected" in r.stderr
    r = subprocess.run([rvc, "check", "--max-data-values", "1", "--spec", "exists[x]. {id: *x}", str(trace)],
                       capture_output=True, text=True)
    assert r.returncode == 5 and r.stdout.count("\n") == 1, r.stderr  # held at step 0, stopped at the 2nd value
    assert "line 2: property 'p1': variable 'x' would take more than 1 distinct values (--max-data-values)" in r.stderr
    r = subprocess.run([rvc, "check", "--spec", "exists[x]. {id: *y}", str(trace)], capture_output=True, text=True)
    assert r.returncode == 2 and "column 13" in r.stderr and "variable 'y' is not bound" in r.stderr, r.stderr
    r = subprocess.run([rvc, "check", "--robustness", "--spec", spec, str(trace)], capture_output=True, text=True)
    assert r.returncode == 2 and "no meaning for data references" in r.stderr, r.stderr
