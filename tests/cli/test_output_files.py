"""Outputs of one run that name one file, and an output that fails mid-run (issue 36).
`monitor --output mcap:v.mcap --output file:v.mcap` was accepted: the writers overwrote each other (the file
no longer MCAP, verdict lines lost); `monitor --output /dev/full` ended with received 101 but checked 100
and nothing dropped. Oracles: the file's bytes before and after, and the counters' own sum."""
import hashlib
import json
import os
import subprocess

import pytest


def run(rvc, *args, cwd=None):
    return subprocess.run([rvc, *args], capture_output=True, text=True, timeout=60, cwd=cwd)


@pytest.fixture
def trace(tmp_path):
    p = tmp_path / "t.jsonl"
    p.write_text("".join(json.dumps({"p": True}) + "\n" for _ in range(101)))
    return str(p)


def digest(path):
    return hashlib.sha256(open(path, "rb").read()).hexdigest() if os.path.exists(path) else None


CASES = [
    ["--output", "mcap:v.mcap", "--output", "file:v.mcap"],
    ["--output", "mcap:v.mcap", "--output", "./v.mcap"],
    ["--output", "file:v.jsonl", "--output", "sub/../v.jsonl"],
    ["--output", "v.jsonl", "--stats-output", "file:v.jsonl"],
    ["--output", "v.jsonl", "--diagnostics", "file:v.jsonl"],
    ["--stats-output", "v.jsonl", "--diagnostics", "v.jsonl"],
    ["--output", "sqlite:v.db", "--output", "file:v.db"],
    ["--output", "sqlite:v.db", "--spool", "v.db"],
    ["--output", "v.jsonl", "--output", "link.jsonl"],  # a symlink to v.jsonl
]


@pytest.mark.parametrize("existing", [False, True])
@pytest.mark.parametrize("args", CASES)
def test_monitor_refuses_two_outputs_naming_one_file(rvc, tmp_path, trace, args, existing):
    (tmp_path / "sub").mkdir()
    os.symlink("v.jsonl", tmp_path / "link.jsonl")
    names = ["v.mcap", "v.jsonl", "v.db"]
    if existing:
        for n in names:
            (tmp_path / n).write_bytes(b"someone's data\n")
    before = {n: digest(tmp_path / n) for n in names}
    r = run(rvc, "monitor", "--input", f"file:{trace}", "--spec", "{p}", *args, cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    assert "name the same file" in r.stderr, r.stderr
    assert args[1] in r.stderr and args[3] in r.stderr
    assert {n: digest(tmp_path / n) for n in names} == before  # nothing written
    assert not [f for f in os.listdir(tmp_path) if f.endswith(("-wal", "-shm", ".spool"))]


def test_check_refuses_its_output_file_as_the_results_database(rvc, tmp_path, trace):
    r = run(rvc, "check", trace, "--spec", "{p}", "-o", "v.db", "-o", "sqlite:v.db", cwd=tmp_path)
    assert r.returncode == 2 and "name the same file" in r.stderr, r.stderr
    assert not os.path.exists(tmp_path / "v.db")


def test_distinct_outputs_and_devices_are_fine(rvc, tmp_path, trace):
    r = run(rvc, "monitor", "--input", f"file:{trace}", "--spec", "{p}", "--output", "mcap:v.mcap", "--output",
            "v.jsonl", "--output", "/dev/null", "--output", "/dev/null", "--stats-output", "s.jsonl", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert len((tmp_path / "v.jsonl").read_text().splitlines()) == 1
    assert (tmp_path / "v.mcap").read_bytes()[:8] == b"\x89MCAP0\r\n"


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
@pytest.mark.parametrize("spec", ["{p}", "not {p}"])
def test_a_failing_output_leaves_counts_that_add_up(rvc, trace, spec):
    r = run(rvc, "monitor", "--input", f"file:{trace}", "--all", "--spec", spec, "--output", "/dev/full")
    assert "cannot write '/dev/full'" in r.stderr
    assert r.returncode == (5 if spec == "{p}" else 1), r.stderr  # a violation outranks the failure
    c = json.loads(r.stderr.strip().splitlines()[-1])
    assert c["received"] == c["checked"] + c["rejected"] + sum(c["dropped"].values()), c
    # the message whose verdict could not be written is named as such
    assert c["dropped"].get("output_failed") == c["received"] - c["checked"] - c["rejected"] >= 1, c
