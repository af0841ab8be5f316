"""Every numeric option of every subcommand goes through one rule (docs/cli.md, "Numeric options";
src/cli/option_rules.hpp): a value outside the option's documented range, NaN, an infinity, an empty
string or a non-number is refused when the command line is parsed, exit 2, naming the option and the range
(`--queue: '0' is out of range (allowed: 1 to 16777216)`) -- never accepted out of range, never CLI11's
internal "Value 0 not in range 0.000000 to 1.79e308". The options are not written down here: they come
from rvc itself (the hidden `rvc --list-numeric`), so an option added later is covered too. Whether a value
was accepted, and as what, comes from the hidden `rvc --print-parsed SUB ...`, which parses and runs
nothing (issue 36: `--service-timeout nan` made every call unanswered, `--max-instances 0` printed
CLI11's message)."""
import json
import math
import re
import subprocess

import pytest

BAD = ["nan", "NaN", "inf", "-inf", "0", "-1", "-0.5", "1e400", "-1e400", "", "abc", "1.5", "1e3", "0x10"]


def run(args):
    return subprocess.run(args, capture_output=True, text=True, timeout=60)


def listing(rvc):
    out = run([rvc, "--list-numeric"])
    assert out.returncode == 0, out.stderr
    return [json.loads(l) for l in out.stdout.splitlines()]


def as_number(text):
    return float(int(text, 16)) if text.startswith("0x") else float(text)  # (strtod reads hex too)


def limit(v):
    return math.inf if v == "infinity" else -math.inf if v == "-infinity" else float(v)


def base(entry):
    """A command line that parses without the option: required options and positionals with dummy values."""
    args = []
    for r in entry["required"]:
        args += [r, "sqlite:unused.db" if r == "--db" else "file:unused.jsonl" if r == "--input" else "x"]
    for p in entry["positionals"]:
        if p == "family":
            args.append("p")
        elif p == "routes":
            args += ["file:a.jsonl", "file:b.jsonl"]
        else:
            args.append("unused.jsonl")
    return args


def parsed(rvc, entry, value):
    cmd = entry["command"].split()
    return run([rvc, "--print-parsed", *cmd, *base(entry), entry["option"], value])


def test_every_subcommand_with_numbers_is_listed(rvc):
    by = {(e["command"], e["option"]) for e in listing(rvc)}
    for expected in [("monitor", "--queue"), ("check", "--max-instances"), ("check", "--instance-expiry"),
                     ("check", "--service-timeout"), ("calls", "--service-timeout"), ("hz", "--period"),
                     ("replay", "--batch"), ("dashboard", "--poll"), ("timescales", "--seed")]:
        assert expected in by, expected


def test_every_numeric_option_declares_a_range(rvc):
    missing = [(e["command"], e["option"]) for e in listing(rvc) if e["range"] is None]
    assert not missing, f"numeric options without in_range() (src/cli/option_ranges.hpp): {missing}"


def test_the_default_parses(rvc):
    for e in listing(rvc):
        r = run([rvc, "--print-parsed", *e["command"].split(), *base(e)])
        assert r.returncode == 0, (e["command"], r.stderr)


def allowed(e, v):
    lo, hi = (limit(x) for x in e["range"])
    return (v > lo if e["above"] else v >= lo) and v <= hi and (not e["integer"] or (math.isfinite(v) and
                                                                                     v == math.floor(v)))


def test_each_value_is_taken_in_range_or_refused_naming_option_and_range(rvc):
    checked = 0
    for e in listing(rvc):
        lo, hi = e["range"]
        edge = [str(lo) if not e["above"] else None, str(hi) if hi != "infinity" else "1e300"]
        for value in BAD + [x for x in edge if x]:
            r = parsed(rvc, e, value)
            where = (e["command"], e["option"], value, r.stderr)
            try:
                number = as_number(value)
            except ValueError:
                number = None
            if number is not None and not math.isnan(number) and allowed(e, number):  # (inf: if the range holds it)
                assert r.returncode == 0, where
                got = json.loads(r.stdout)["options"][e["option"]]
                assert len(got) == 1 and as_number(got[0]) == number, where  # "1e3" may read as "1000"
            else:
                assert r.returncode == 2, where
                first = r.stderr.splitlines()[0]
                assert first.startswith(e["option"] + ": '" + value + "' is "), where
                assert re.search(r"\(allowed: (more than )?[-0-9.]+,? (up )?to ([0-9.]+|inf)", first), where
                assert "not in range" not in r.stderr and "0.000000" not in r.stderr, where
            checked += 1
    assert checked > 500


@pytest.mark.parametrize("args", [["check", "--instances-by", "", "t.jsonl"], ["check", "--time-field", "", "t.jsonl"],
                                  ["echo", "--field", "", "x.mcap"], ["hz", "--stamp-field", "", "file:x"],
                                  ["sync", "--time-field", "", "--input", "a=file:x"]])
def test_an_empty_field_name_is_refused(rvc, args):
    r = run([rvc, "--print-parsed", *args])
    assert r.returncode == 2, r.stdout
    assert "an empty field name" in r.stderr and args[1] in r.stderr, r.stderr


def test_a_nan_service_timeout_no_longer_makes_calls_unanswered(rvc, tmp_path):
    r = run([rvc, "calls", "--service-timeout", "nan", str(tmp_path / "none.jsonl")])
    assert r.returncode == 2 and "--service-timeout: 'nan' is out of range (allowed: more than 0, up to " \
                                 "604800 seconds)" in r.stderr, r.stderr
