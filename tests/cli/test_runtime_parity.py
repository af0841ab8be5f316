"""`rvc check FILE` and `rvc monitor --input file:FILE` run on one runtime
(src/runtime): the same hostile file must give the same verdicts, the same
counts and the same exit status on both. Expected verdicts are hand-computed."""
import json
import subprocess


def run(rvc, *args, timeout=60):
    return subprocess.run([rvc, *args], capture_output=True, text=True, timeout=timeout)


def verdicts(text):
    return [(v["time"], v["property"], v["value"]) for v in map(json.loads, text.splitlines())]


def final_stats(stderr):
    return json.loads([l for l in stderr.splitlines() if l.startswith("{")][-1])


HOSTILE = [
    '{"p":true,"n":1}',             # 1 ok
    '{"p":tru}',                    # 2 malformed
    '',                             # 3 blank: not a message
    '{"p":false,"n":2}\r',          # 4 ok (CRLF)
    '{"p":true} {"p":false}',       # 5 two objects on one line: rejected
    '{"p":true,"pad":"' + "x" * 200 + '"}',  # 6 longer than --max-message-size 100
    '{"p":"yes","n":3}',            # 7 wrong type for p: warning, p keeps false
    '[1,2]',                        # 8 not an object
    '{"p":true,"n":4}',             # 9 ok
]


def test_check_and_monitor_agree_on_a_hostile_file(rvc, tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text("\n".join(HOSTILE) + "\n")
    args = ["--all", "--spec", "{p}", "--spec", "{n > 1}", "--max-message-size", "100"]
    c = run(rvc, "check", *args, "--summary", str(trace))
    out = tmp_path / "v.jsonl"
    m = run(rvc, "monitor", *args, "--input", f"file:{trace}", "--output", f"file:{out}")
    # Accepted: lines 1, 4, 7 (p keeps false), 9 -> steps 0..3.
    expected = [(0, "p1", True), (0, "p2", False), (1, "p1", False), (1, "p2", True),
                (2, "p1", False), (2, "p2", True), (3, "p1", True), (3, "p2", True)]
    assert verdicts(c.stdout) == expected, c.stderr
    assert verdicts(out.read_text()) == expected, m.stderr
    assert "4 messages checked, 4 rejected, 1 warnings" in c.stderr
    s = final_stats(m.stderr)
    assert (s["checked"], s["rejected"], s["warnings"]) == (4, 4, 1)
    assert c.returncode == m.returncode == 1  # p was violated


def test_monitor_applies_max_message_size_to_single_messages(rvc, tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"p":true}\n{"p":true,"pad":"' + "x" * 100 + '"}\n')
    m = run(rvc, "monitor", "--spec", "{p}", "--max-message-size", "50", "--input", f"file:{trace}",
            "--output", f"file:{tmp_path / 'v.jsonl'}")
    assert "longer than 50 bytes" in m.stderr
    assert final_stats(m.stderr)["rejected"] == 1
    assert m.returncode == 3


def test_dense_time_order_error_names_the_message(rvc, tmp_path):
    # The time-order error is raised at commit(), after the reader's position
    # object is gone: it must still name the right message.
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"time":0,"p":true}\n{"time":2,"p":true}\n{"time":1,"p":true}\n{"time":3,"p":true}\n')
    c = run(rvc, "check", "--dense", "--spec", "{p}", str(trace))
    assert "line 3: time 1 is not after the previous message's time 2" in c.stderr, c.stderr
    m = run(rvc, "monitor", "--dense", "--spec", "{p}", "--input", f"file:{trace}",
            "--output", f"file:{tmp_path / 'v.jsonl'}")
    assert "seq 3: time 1 is not after the previous message's time 2" in m.stderr, m.stderr
    assert c.returncode == m.returncode == 3


def test_output_naming_the_input_is_refused(rvc, tmp_path):
    trace = tmp_path / "t.jsonl"
    content = '{"p":true}\n{"p":false}\n'
    trace.write_text(content)
    link = tmp_path / "same.jsonl"
    link.symlink_to(trace)
    for out in (str(trace), f"file:{trace}", str(link)):
        c = run(rvc, "check", "--spec", "{p}", str(trace), "-o", out)
        assert c.returncode == 2 and "refusing to overwrite" in c.stderr, c.stderr
        m = run(rvc, "monitor", "--spec", "{p}", "--input", f"file:{trace}", "--output", out)
        assert m.returncode == 2 and "refusing to monitor its own output" in m.stderr, m.stderr
    assert trace.read_text() == content


def test_empty_input_is_not_a_pass_for_monitor(rvc, tmp_path):
    # An empty file still ends with an end-of-stream marker: nothing was lost,
    # but nothing was checked either: incomplete (issue 25).
    trace = tmp_path / "empty.jsonl"
    trace.write_text("")
    m = run(rvc, "monitor", "--spec", "{p}", "--input", f"file:{trace}", "--output", f"file:{tmp_path / 'v'}")
    s = final_stats(m.stderr)
    assert s["received"] == 0 and s["eos"] is True
    assert m.returncode == 6 and "nothing was received" in m.stderr, m.stderr


def test_blank_lines_in_a_file_are_not_lost_messages(rvc, tmp_path):
    # A file's frames are numbered by line: a blank line is a skipped number,
    # not a message lost in transit (exit 4).
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"p":true}\n\n\n{"p":true}\n')
    m = run(rvc, "monitor", "--spec", "{p}", "--input", f"file:{trace}", "--output", f"file:{tmp_path / 'v'}")
    s = final_stats(m.stderr)
    assert (s["received"], s["checked"], s["gaps"], s["duplicates"]) == (2, 2, 0, 0)
    assert m.returncode == 0, m.stderr
