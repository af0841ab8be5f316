"""A repeatable option takes one value per flag, so a positional may follow it (issue 25).

`rvc check --topic /t bag.mcap` once read bag.mcap as a second topic ('trace is required'), and
`rvc msg decode --msg-path DIR samples.hex` read the samples file as a second folder. The options
covered here are not written down: every subcommand's repeatable options come from rvc itself (the
hidden `rvc --list-repeatable`, cross-checked against the `...` that `rvc SUB --help` prints after a
repeatable option), so an option added later is covered too. How a command line was read comes from
the hidden `rvc --print-parsed SUB ...`, which parses and runs nothing.
"""
import json
import os
import re
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, timeout=60, **kw)


def listing(rvc):
    out = run([rvc, "--list-repeatable"])
    assert out.returncode == 0, out.stderr
    return [json.loads(line) for line in out.stdout.splitlines()]


def help_repeatable(rvc, command):
    """Options whose `--help` line shows `...` (CLI11's mark of an option that takes many values)."""
    text = run([rvc, *command.split(), "--help"]).stdout
    found = set()
    for line in text.splitlines():
        m = re.match(r"^\s+(-[\w-]+(?:,\s*-[\w-]+)*)\s+(\S.*)$", line)
        if m and re.match(r"^[A-Z]\S*(=\S+)?\s\.\.\.(\s|$)", m.group(2)):
            names = [n.strip() for n in m.group(1).split(",")]
            found.add(next((n for n in names if n.startswith("--")), names[0]))
    return found


def parsed(rvc, command, args):
    out = run([rvc, "--print-parsed", *command.split(), *args])
    return out, (json.loads(out.stdout) if out.returncode == 0 else None)


def test_every_subcommand_is_listed(rvc):
    commands = {c["command"] for c in listing(rvc)}
    for expected in ("check", "monitor", "replay", "echo", "sync", "bridge", "msg decode", "msg encode",
                     "msg list", "perf pub", "timescales", "dashboard"):
        assert expected in commands
    # the two of the issue are repeatable
    by_name = {c["command"]: c for c in listing(rvc)}
    assert "--topic" in by_name["check"]["repeatable"]
    assert "--msg-path" in by_name["msg decode"]["repeatable"]


def test_listing_matches_help(rvc):
    for c in listing(rvc):
        assert set(c["repeatable"]) == help_repeatable(rvc, c["command"]), c["command"]


def cases(rvc_path):
    out = []
    for c in listing(rvc_path):
        for opt in c["repeatable"]:
            out.append((c, opt))
    return out


def test_a_positional_after_each_repeatable_option(rvc):
    checked = 0
    for c, opt in cases(rvc):
        cmd = c["command"]
        required = [a for r in c["required"] if r != opt for a in (r, "req")]
        if c["positionals"]:
            # the option once, then the positional(s): the option keeps one value
            first = c["positionals"][0]
            pos = ["pos-a", "pos-b"] if cmd == "bridge" else ["pos-a"]
            out, p = parsed(rvc, cmd, required + [opt, "value-1", *pos])
            assert out.returncode == 0, (cmd, opt, out.stderr)
            assert p["command"] == cmd
            assert p["options"][opt] == ["value-1"], (cmd, opt, p)
            assert p["options"][first] == pos, (cmd, opt, p)
        else:
            # nothing may take the extra word: refused, not swallowed as a second value
            out = run([rvc, "--print-parsed", *cmd.split(), *required, opt, "value-1", "stray-word"])
            assert out.returncode == 2, (cmd, opt, out.stdout)
            assert "stray-word" in out.stderr, (cmd, opt, out.stderr)
        # repeated, it collects one value per flag, in order
        out, p = parsed(rvc, cmd, required + [opt, "value-1", opt, "value-2"]
                        + (["pos-a", "pos-b"] if cmd == "bridge" else ["pos-a"] if c["positionals"] else []))
        assert out.returncode == 0, (cmd, opt, out.stderr)
        assert p["options"][opt] == ["value-1", "value-2"], (cmd, opt, p)
        checked += 1
    assert checked >= 20  # every subcommand's --connect/--listen/--dds-peer/... at least


def write_hex_sample(path):
    # rvc_test_pkg/msg/Pair {int32 a, float64 b} with a=7, b=0.5, little-endian CDR:
    # encapsulation 00 01 00 00, int32 at 0, padding to 8, float64 at 8.
    path.write_text("00010000" + "07000000" + "00000000" + "000000000000e03f" + "\n")


def test_msg_decode_msg_path_then_samples_file(rvc, tmp_path):
    defs = tmp_path / "defs" / "rvc_test_pkg" / "msg"
    defs.mkdir(parents=True)
    (defs / "Pair.msg").write_text("int32 a\nfloat64 b\n")
    samples = tmp_path / "samples.hex"
    write_hex_sample(samples)
    out = run([rvc, "msg", "decode", "--type", "rvc_test_pkg/msg/Pair", "--msg-path", str(tmp_path / "defs"),
               str(samples)])
    assert out.returncode == 0, out.stderr
    assert [json.loads(line) for line in out.stdout.splitlines()] == [{"a": 7, "b": 0.5}]
