"""rvc monitor --diagnostics on files (docs/diagnostics.md): the JSON form of the DiagnosticArray a
file input produces, levels from --level and from the properties file's `level:` key, and the
options refused at start-up with the problem named (exit 2). Oracle: the levels the document gives
for the trace the test writes (p1 is violated by its last message, p2 never)."""
import json
import subprocess


def run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, timeout=60, **kw)


def trace(tmp_path):
    path = tmp_path / "t.jsonl"
    rows = [{"ok": True, "speed": 1}, {"ok": True, "speed": 2}, {"ok": False, "speed": 3}, {"ok": "x", "speed": 4}]
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
    return str(path)


def last_array(path):
    arrays = [json.loads(l) for l in path.read_text().splitlines()]
    assert arrays, "no array written"
    return {s["name"]: s for s in arrays[-1]["status"]}


def values(status):
    return {kv["key"]: kv["value"] for kv in status["values"]}


def test_file_input_final_array(rvc, tmp_path):
    out = tmp_path / "diag.jsonl"
    r = run([rvc, "monitor", "--spec", "{ok}", "--spec", "{speed < 10}", "--input", f"file:{trace(tmp_path)}",
             "--output", f"file:{tmp_path}/v.jsonl", "--diagnostics", f"file:{out}", "--name", "files"])
    assert r.returncode in (1, 3), r.stderr  # violated, and a message rejected ("ok":"x" is no Boolean)
    st = last_array(out)
    assert set(st) == {"rvc: files/monitor", "rvc: files/p1", "rvc: files/p2"}
    p1, p2, mon = st["rvc: files/p1"], st["rvc: files/p2"], st["rvc: files/monitor"]
    assert (p1["level"], p1["message"]) == (2, "violated")
    assert values(p1)["spec"] == "{ok}" and values(p1)["violations"] == "1" and values(p1)["verdict"] == "false"
    assert (p2["level"], p2["message"]) == (0, "holds")
    assert values(mon)["received"] == "4"
    assert int(values(mon)["checked"]) + int(values(mon)["rejected"]) == 4


def test_properties_file_level_and_level_option(rvc, tmp_path):
    props = tmp_path / "props.yaml"
    props.write_text("properties:\n  - name: okay\n    spec: '{ok}'\n    level: warn\n"
                     "  - name: slow\n    spec: '{speed < 3}'\n")
    out = tmp_path / "diag.jsonl"
    r = run([rvc, "monitor", "--properties", str(props), "--input", f"file:{trace(tmp_path)}",
             "--output", f"file:{tmp_path}/v.jsonl", "--diagnostics", f"file:{out}"])
    assert r.returncode in (1, 3), r.stderr
    st = last_array(out)
    assert st["rvc: monitor/okay"]["level"] == 1  # warn, from the file
    assert st["rvc: monitor/slow"]["level"] == 2  # error, the default
    r = run([rvc, "monitor", "--properties", str(props), "--level", "slow=WARN", "--input",
             f"file:{trace(tmp_path)}", "--output", f"file:{tmp_path}/v.jsonl", "--diagnostics", f"file:{out}"])
    assert last_array(out)["rvc: monitor/slow"]["level"] == 1


def test_bad_options_are_named(rvc, tmp_path):
    t = trace(tmp_path)
    base = [rvc, "monitor", "--spec", "{ok}", "--input", f"file:{t}", "--output", f"file:{tmp_path}/v"]
    diag = ["--diagnostics", f"file:{tmp_path}/d"]
    cases = [
        (["--level", "p9=warn", *diag], "--level p9: no property of that name (the properties: p1)"),
        (["--level", "p1=fatal", *diag], "level 'fatal': expected warn or error"),
        (["--level", "warn", *diag], "--level 'warn': expected PROPERTY=warn or PROPERTY=error"),
        (["--level", "p1=warn"], "give --diagnostics URI too"),
        (["--name", "a/b", *diag], "--name 'a/b': use letters, digits"),
        (["--diagnostics", f"file:{t}"], "would be read back by the input"),
    ]
    for extra, message in cases:
        r = run([*base, *extra])
        assert r.returncode == 2 and message in r.stderr, (extra, r.stderr)
    props = tmp_path / "bad.yaml"
    props.write_text("properties:\n  - name: a\n    spec: '{ok}'\n    level: loud\n")
    r = run([rvc, "monitor", "--properties", str(props), "--input", f"file:{t}", *diag])
    assert r.returncode == 2 and "level 'loud': expected warn or error" in r.stderr, r.stderr
