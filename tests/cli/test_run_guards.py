"""Guards at start-up and at the end of a run (issue 25, items 2-5): a run that checked nothing is
not a pass (exit 6, with the reason); numeric options out of range are refused when parsed (exit 2,
the option and its range named); a command endpoint or output that is the monitor's own input is
refused before anything is opened; stdin redirected from the output file is caught by device and
inode. Oracles: the exit statuses of docs/cli.md and the files' bytes, which must stay as written."""
import json
import os
import subprocess

import pytest

from conftest import transports_built


def run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, timeout=60, **kw)


def write(path, rows):
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
    return str(path)


# ---- item 2: nothing checked ----

def test_an_empty_file_is_nothing_checked(rvc, tmp_path):
    empty = tmp_path / "empty.jsonl"
    empty.write_text("\n  \n")
    r = run([rvc, "monitor", "--spec", "{ok}", "--input", f"file:{empty}"])
    assert r.returncode == 6 and "nothing was received" in r.stderr, r.stderr
    r = run([rvc, "check", "--spec", "{ok}", str(empty)])
    assert r.returncode == 6 and "nothing was checked: 0 messages received" in r.stderr, r.stderr


def test_every_message_rejected_is_nothing_checked(rvc, tmp_path):
    bad = tmp_path / "bad.jsonl"
    bad.write_text("{\n[1]\n")
    r = run([rvc, "check", "--spec", "{ok}", str(bad)])
    assert r.returncode == 6 and "nothing was checked: 2 messages received, 2 rejected" in r.stderr, r.stderr


@pytest.mark.parametrize("policy", ["approximate", "exact"])
def test_sets_that_never_form_are_nothing_checked(rvc, tmp_path, policy):
    a = write(tmp_path / "a.jsonl", [{"time": 1, "x": 1}, {"time": 3, "x": 1}])
    b = write(tmp_path / "b.jsonl", [{"time": 10, "y": 1}])
    args = ["--input", f"a=file:{a}", "--input", f"b=file:{b}", "--sync", policy]
    if policy == "approximate":
        args += ["--max-interval", "1"]
    r = run([rvc, "monitor", "--spec", "{a.x > 0}", *args])
    assert r.returncode == 6, r.stderr
    assert "nothing was checked: 3 messages received, 0 rejected, dropped {" in r.stderr, r.stderr
    stats = json.loads([l for l in r.stderr.splitlines() if l.startswith('{"input"')][-1])
    assert stats["checked"] == 0 and sum(stats["dropped"].values()) == 3, stats
    r = run([rvc, "sync", *args])
    assert r.returncode == 6 and r.stdout == "", r.stderr


# ---- item 3: numeric options out of range ----

def test_numeric_options_are_bounded_at_parse_time(rvc, tmp_path):
    trace = write(tmp_path / "t.jsonl", [{"ok": True}] * 3)
    mon = [rvc, "monitor", "--spec", "{ok}", "--input", f"file:{trace}"]
    two = [rvc, "monitor", "--spec", "{a.ok}", "--input", f"a=file:{trace}", "--input", f"b=file:{trace}"]
    cases = [
        (mon + ["--queue", "0"], "--queue", "1 to 16777216"),
        (mon + ["--output", f"sqlite:{tmp_path}/r.db", "--witness", "100000000"], "--witness", "0 to 10000"),
        (mon + ["--output", f"sqlite:{tmp_path}/r.db", "--witness", "4294967295"], "--witness", "0 to 10000"),
        (two + ["--max-delay", "1e308"], "--max-delay", "0 to 3600 seconds"),
        (two + ["--max-delay", "nan"], "--max-delay", "0 to 3600 seconds"),
        (two + ["--sync", "approximate", "--sync-queue", "0"], "--sync-queue", "1 to 1048576"),
        (two + ["--sync", "approximate", "--max-interval", "nan"], "--max-interval", "0 to inf seconds"),
        (mon + ["--max-data-values", "0"], "--max-data-values", "1 to 10000000"),
        (mon + ["--max-message-size", "0"], "--max-message-size", "1 to 1073741824 bytes"),
        (mon + ["--stats-interval", "nan"], "--stats-interval", "0 to 604800 seconds"),
        (mon + ["--stats-interval", "-1"], "--stats-interval", "0 to 604800 seconds"),
        (mon + ["--idle-timeout", "nan"], "--idle-timeout", "0 to 604800 seconds"),
        (mon + ["--idle-timeout", "-1"], "--idle-timeout", "0 to 604800 seconds"),
        (mon + ["--dead-after", "inf"], "--dead-after", "0 to 604800 seconds"),
        ([rvc, "sync", "--input", f"a=file:{trace}", "--input", f"b=file:{trace}", "--idle-timeout", "nan"],
         "--idle-timeout", "0 to 604800 seconds"),
    ]
    for args, option, allowed in cases:
        r = run(args)
        assert r.returncode == 2, (args, r.stderr)
        assert option in r.stderr and f"allowed: {allowed}" in r.stderr, (args, r.stderr)
        assert len(r.stderr.strip().splitlines()) <= 2, r.stderr  # one line (CLI11 may add a help hint)
    assert not os.path.exists(tmp_path / "r.db")


# ---- item 4: commands to the monitor's own input ----

def test_on_violation_naming_the_input_file_is_refused_and_the_trace_kept(rvc, tmp_path):
    trace = tmp_path / "t.jsonl"
    text = '{"ok": true}\n{"ok": false}\n'
    trace.write_text(text)
    link = tmp_path / "link.jsonl"
    os.link(trace, link)
    for target in (trace, link):
        r = run([rvc, "monitor", "--spec", "{ok}", "--input", f"file:{trace}",
                 "--on-violation", f'p1=file:{target}:{{"stop":true}}'])
        assert r.returncode == 2, r.stderr
        assert f"--on-violation p1: 'file:{target}' would be read back by the input" in r.stderr, r.stderr
        assert trace.read_text() == text


@pytest.mark.needs_rust  # a zenoh: input
def test_on_violation_on_the_input_key_is_refused(rvc):
    if "zenoh" not in transports_built(rvc):
        pytest.fail("this rvc was built without Zenoh")
    r = run([rvc, "monitor", "--spec", "{ok}", "--input", "zenoh:robot/status",
             "--on-violation", 'p1=zenoh:robot/*:{"stop":true}', "--mode", "peer", "--no-multicast-scouting"])
    assert r.returncode == 2, r.stderr
    assert "'zenoh:robot/*' would be read back by the input 'zenoh:robot/status'" in r.stderr, r.stderr


# ---- item 5: stdin from the output file ----

def test_check_from_stdin_refuses_to_write_over_it(rvc, tmp_path):
    trace = tmp_path / "t.jsonl"
    text = '{"ok": true}\n{"ok": false}\n'
    trace.write_text(text)
    hard = tmp_path / "hard.jsonl"
    os.link(trace, hard)
    soft = tmp_path / "soft.jsonl"
    soft.symlink_to(trace)
    for out in (trace, hard, soft):
        with open(trace) as stdin:
            r = run([rvc, "check", "--spec", "{ok}", "-", "-o", str(out)], stdin=stdin)
        assert r.returncode == 2 and "is the trace being read" in r.stderr, r.stderr
        assert trace.read_text() == text
        with open(trace) as stdin:
            r = run([rvc, "monitor", "--spec", "{ok}", "--input", "-", "--output", f"file:{out}"], stdin=stdin)
        assert r.returncode == 2 and "would be read back" in r.stderr, r.stderr
        assert trace.read_text() == text
    # another file on stdin, into a new output: fine
    with open(trace) as stdin:
        r = run([rvc, "check", "--spec", "{ok}", "-", "-o", str(tmp_path / "verdicts.jsonl")], stdin=stdin)
    assert r.returncode == 1, r.stderr


# ---- file outputs write over only what rvc wrote ----

PRECIOUS = "precious: not rvc's\n"


def _file_output_commands(rvc, tmp_path, out):
    """Every way of naming a file to write, each with the file `out`."""
    trace = write(tmp_path / "in.jsonl", [{"time": 0, "ok": True}, {"time": 1, "ok": False}])
    cmds = [
        [rvc, "check", "--spec", "{ok}", trace, "-o", out],
        [rvc, "monitor", "--spec", "{ok}", "--input", f"file:{trace}", "--output", f"file:{out}"],
        [rvc, "monitor", "--spec", "{ok}", "--input", f"file:{trace}", "--output", "file:/dev/null",
         "--diagnostics", f"file:{out}"],
        [rvc, "monitor", "--spec", "{ok}", "--input", f"file:{trace}", "--output", "file:/dev/null",
         "--stats-output", f"file:{out}"],
        [rvc, "monitor", "--spec", "{ok}", "--input", f"file:{trace}", "--output", "file:/dev/null",
         "--on-violation", f'p1=file:{out}:{{"stop":true}}'],
        [rvc, "hz", f"file:{trace}", "--time-source", "stamps", "--diagnostics", f"file:{out}"],
        [rvc, "replay", trace, "--to", f"file:{out}"],
        [rvc, "timescales", "AlwaysBQR", "--ubound", "3", "--duration", "10", "-o", out],
        [rvc, "timescales", "AlwaysBQR", "--ubound", "3", "--duration", "10", "--properties-out", out],
    ]
    if "dds" in transports_built(rvc):
        cmds.append([rvc, "dds-config", "-o", out])
    return cmds


def test_a_file_rvc_did_not_write_is_never_written_over(rvc, tmp_path):
    precious = tmp_path / "precious.txt"
    for cmd in _file_output_commands(rvc, tmp_path, str(precious)):
        precious.write_text(PRECIOUS)
        r = run(cmd)
        assert r.returncode == 2, (cmd, r.returncode, r.stderr)
        assert f"'{precious}': it exists and rvc did not write it: refusing to write over it" in r.stderr, \
            (cmd, r.stderr)
        assert precious.read_text() == PRECIOUS, cmd
        # a symbolic link to it is the same file
        link = tmp_path / "link.txt"
        link.unlink(missing_ok=True)
        link.symlink_to(precious)
        r = run([c if c != str(precious) else str(link) for c in cmd])
        assert r.returncode == 2 and precious.read_text() == PRECIOUS, (cmd, r.stderr)


def test_rvc_writes_over_its_own_files_new_and_empty_ones_and_devices(rvc, tmp_path):
    for i, cmd_new in enumerate(_file_output_commands(rvc, tmp_path, str(tmp_path / "new.out"))):
        out = tmp_path / f"out{i}.txt"
        cmd = [c.replace(str(tmp_path / "new.out"), str(out)) for c in cmd_new]
        first = run(cmd)
        assert first.returncode in (0, 1), (cmd, first.stderr)
        assert out.exists() and os.getxattr(out, "user.rvc.output") == b"1", cmd
        again = run(cmd)  # the same command again writes over its own output
        assert again.returncode == first.returncode, (cmd, again.stderr)
        empty = tmp_path / f"empty{i}.txt"
        empty.write_text("")  # mktemp's file: nothing to lose
        r = run([c.replace(str(out), str(empty)) for c in cmd])
        assert r.returncode == first.returncode, (cmd, r.stderr)
        r = run([c.replace(str(out), "/dev/null") for c in cmd])
        assert r.returncode == first.returncode, (cmd, r.stderr)


# ---- rvc sync --set-type-dir writes only its own definitions ----

def test_sync_set_type_dir_leaves_a_foreign_definition_alone(rvc, tmp_path):
    if "dds" not in transports_built(rvc):
        pytest.fail("this rvc was built without DDS")
    mine = tmp_path / "defs" / "rvc_sync" / "msg" / "Set.msg"
    mine.parent.mkdir(parents=True)
    mine.write_text("int32 mine\n")  # a definition of the same name that rvc did not write
    r = run([rvc, "sync", "--input", "a=dds:/rvc_guard_a", "--type", "std_msgs/msg/Bool",
             "--input", "b=dds:/rvc_guard_b", "--type", "std_msgs/msg/Bool", "--set-type", "rvc_sync/msg/Set",
             "--set-type-dir", str(tmp_path / "defs"), "--output", "dds:/rvc_guard_out", "--idle-timeout", "1"])
    assert r.returncode == 2, r.stderr
    assert "was not written by rvc sync: refusing to overwrite it" in r.stderr, r.stderr
    assert mine.read_text() == "int32 mine\n"
