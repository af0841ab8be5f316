"""rvc-batch (tools/rvc-batch): `rvc check` over many bags on a Dask cluster, one run per bag.

Oracles: sequential `rvc check` on every bag (exit status, verdict lines, and what it stores: the
same rows per bag in its own SQLite store), and the hand-computed answer of the generated bags
(tools/rvc-batch/example_bags.py: every fifth bag violated at a known step, the rest held). Bags
are written by rosbags (PyPI), half MCAP, half SQLite. Two broken bags must be reported, counted
and must not stop the others. Needs dask[distributed] (PyPI; under CI=true a missing one fails).
"""
import importlib.util
import json
import os
import sqlite3
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
TOOL = os.path.join(ROOT, "tools", "rvc-batch", "rvc_batch.py")
_spec = importlib.util.spec_from_file_location("example_bags", os.path.join(ROOT, "tools", "rvc-batch",
                                                                           "example_bags.py"))
eb = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(eb)
_tool_spec = importlib.util.spec_from_file_location("rvc_batch", TOOL)
rb = importlib.util.module_from_spec(_tool_spec)
_tool_spec.loader.exec_module(rb)

COUNT, MESSAGES = 200, 20


def batch(rvc, *args, timeout=600):
    return subprocess.run([sys.executable, TOOL, "--rvc", rvc, *args], capture_output=True, text=True,
                          timeout=timeout)


def runs_by_bag(db):
    """{bag: (exit_status, verdict rows, violation rows, final counters)} of a results store."""
    con = sqlite3.connect(db)
    out = {}
    for run, inputs, status, counters in con.execute("SELECT run, inputs, exit_status, counters FROM runs"):
        bag = json.loads(inputs)[0]
        assert bag not in out, "two runs for %s" % bag
        verdicts = con.execute("SELECT property, time, value FROM verdicts WHERE run = ? ORDER BY id",
                               (run,)).fetchall()
        violations = con.execute("SELECT property, time, witness FROM violations WHERE run = ? ORDER BY id",
                                 (run,)).fetchall()
        out[bag] = (status, verdicts, violations, json.loads(counters) if counters else None)
    con.close()
    return out


@pytest.fixture(scope="module")
def bags(tmp_path_factory):
    pytest.importorskip("dask.distributed", reason="dask[distributed] (PyPI) not installed")
    d = tmp_path_factory.mktemp("batch-bags")
    paths = eb.write_bags(str(d / "bags"), COUNT, MESSAGES)
    broken = d / "bags" / "broken"
    broken.mkdir()
    (broken / "empty.mcap").write_bytes(b"")
    with open(os.path.join(paths[0], "bag-0000.mcap"), "rb") as f:
        (broken / "cut.mcap").write_bytes(f.read()[:60])  # the magic and part of the header record
    return d, paths, [str(broken / "cut.mcap"), str(broken / "empty.mcap")]


def test_batch_equals_sequential_check_and_the_hand_computed_answer(rvc, bags, tmp_path):
    d, paths, broken = bags
    r = batch(rvc, str(d / "bags"), "--store", "sqlite:%s" % (tmp_path / "batch.db"), "--workers", "2",
              "--out-dir", str(tmp_path / "verdicts"), "--summary", str(tmp_path / "summary.jsonl"),
              "--no-progress", "--", "--spec", eb.SPEC, "--topic", eb.TOPIC)
    assert r.returncode == 5, r.stderr[-3000:]  # two bags failed
    total = json.loads(r.stdout.strip().splitlines()[-1])
    violated = [i for i in range(COUNT) if eb.expected(i, MESSAGES)[0]]
    assert total["bags"] == COUNT + 2 and total["workers"] == 2
    assert (total["violated"], total["held"], total["failed"]) == (len(violated), COUNT - len(violated), 2)
    assert total["held"] + total["violated"] + total["failed"] == total["bags"]
    for b in broken:  # each failed bag is named on stderr with rvc's own reason
        assert "bag %s failed (exit " % b in r.stderr, r.stderr[-3000:]
    summary = {rec["bag"]: rec for rec in map(json.loads, open(tmp_path / "summary.jsonl"))}
    assert sorted(summary) == sorted(paths + broken)

    # Oracle 1: sequential rvc check, bag by bag, into its own store.
    seq_db = tmp_path / "seq.db"
    for bag in paths + broken:
        s = subprocess.run([rvc, "check", bag, "--spec", eb.SPEC, "--topic", eb.TOPIC, "--stats",
                            "-o", "sqlite:%s" % seq_db], capture_output=True, text=True, timeout=60)
        rec = summary[bag]
        assert rec["exit"] == s.returncode, (bag, rec, s.stderr)
        if bag in broken:
            assert s.returncode not in (0, 1) and rec["error"], (bag, rec)
            continue
        assert open(rec["verdicts"]).read() == s.stdout, bag
        stats = [ln for ln in s.stderr.splitlines() if ln.startswith("{")]
        assert rec["stats"] == json.loads(stats[-1]), bag
    got, want = runs_by_bag(tmp_path / "batch.db"), runs_by_bag(seq_db)
    assert sorted(got) == sorted(want) and set(paths) <= set(got)
    for bag in got:
        g, w = got[bag], want[bag]
        # exit status, every verdict change, every violation with its witness, the run's counters
        assert g == w, bag

    # Oracle 2: the answer written into the bags.
    for i, bag in enumerate(paths):
        bad, step = eb.expected(i, MESSAGES)
        status, verdicts, violations, counters = got[bag]
        assert status == (1 if bad else 0), bag
        assert counters["checked"] == MESSAGES and counters["rejected"] == 0, bag
        assert summary[bag]["stats"]["received"] == MESSAGES, bag
        assert [v[1] for v in violations] == ([float(step)] if bad else []), bag


def test_existing_cluster_by_address(rvc, bags, tmp_path):
    from dask.distributed import LocalCluster
    d, paths, _ = bags
    listed = tmp_path / "list.txt"
    listed.write_text("# ten bags\n" + "\n".join(paths[:10]) + "\n")
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp://",
                      host="127.0.0.1", dashboard_address=None) as cluster:
        r = batch(rvc, "@%s" % listed, "--store", "sqlite:%s" % (tmp_path / "r.db"), "--scheduler",
                  cluster.scheduler_address, "--no-progress", "--", "--spec", eb.SPEC)
    assert r.returncode == 1, r.stderr[-3000:]  # bags 0 and 5 are violated
    total = json.loads(r.stdout.strip().splitlines()[-1])
    assert (total["bags"], total["violated"], total["held"], total["failed"], total["workers"]) == (10, 2, 8, 0, 1)
    assert sorted(runs_by_bag(tmp_path / "r.db")) == sorted(paths[:10])


def test_nothing_to_check_and_bad_paths(rvc, tmp_path):
    pytest.importorskip("dask.distributed", reason="dask[distributed] (PyPI) not installed")
    (tmp_path / "empty").mkdir()
    r = batch(rvc, str(tmp_path / "empty"), "--store", "sqlite:%s" % (tmp_path / "x.db"), "--", "--spec", "{p}")
    assert r.returncode == 6 and "no bag found" in r.stderr
    assert json.loads(r.stdout)["bags"] == 0
    r = batch(rvc, str(tmp_path / "missing"), "--store", "sqlite:%s" % (tmp_path / "x.db"), "--", "--spec", "{p}")
    assert r.returncode == 2 and "missing" in r.stderr
    r = batch(rvc, str(tmp_path / "empty"), "--store", "results.db", "--", "--spec", "{p}")
    assert r.returncode == 2 and "--store" in r.stderr
    assert not (tmp_path / "x.db").exists()


def test_files_it_did_not_create_are_never_written_over(rvc, bags, tmp_path):
    """--summary and --out-dir files: a foreign file keeps its bytes (exit 2, nothing run); the tool's
    own earlier output and an empty file are written as before."""
    d, paths, _ = bags
    one = os.path.join(paths[0], "bag-0000.mcap")
    foreign = tmp_path / "summary.jsonl"
    foreign.write_text("precious\n")
    store = tmp_path / "s.db"
    r = batch(rvc, one, "--store", "sqlite:%s" % store, "--summary", str(foreign), "--no-progress",
              "--", "--spec", "{data < 1000}")
    assert r.returncode == 2 and "rvc did not write it" in r.stderr, r.stderr
    assert foreign.read_text() == "precious\n" and not store.exists()
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    target = Path(rb.verdicts_path(str(out_dir), one))
    target.write_text("precious\n")
    r = batch(rvc, one, "--store", "sqlite:%s" % store, "--out-dir", str(out_dir), "--no-progress",
              "--", "--spec", "{data < 1000}")
    assert r.returncode == 2 and str(target) in r.stderr, r.stderr
    assert target.read_text() == "precious\n"
    target.unlink()
    mine = tmp_path / "mine.jsonl"
    mine.write_text("")
    for _ in range(2):  # an empty file, then the tool's own output: written both times
        r = batch(rvc, one, "--store", "sqlite:%s" % store, "--summary", str(mine), "--out-dir", str(out_dir),
                  "--no-progress", "--", "--spec", "{data < 1000}")
        assert r.returncode in (0, 1), r.stderr
        assert json.loads(mine.read_text().splitlines()[0])["bag"] == one
        assert target.read_text() != ""


def test_a_bag_past_its_timeout_is_stopped_and_counted(rvc, bags, tmp_path):
    d, paths, _ = bags
    # 1 microsecond: no rvc can start, read a bag and end in that time, so every bag is stopped
    r = batch(rvc, paths[0], paths[1], "--store", "sqlite:%s" % (tmp_path / "t.db"), "--timeout", "0.000001",
              "--no-progress", "--", "--spec", eb.SPEC)
    assert r.returncode == 5, r.stderr[-2000:]
    total = json.loads(r.stdout.strip().splitlines()[-1])
    assert (total["bags"], total["failed"], total["held"], total["violated"]) == (2, 2, 0, 0)
    assert r.stderr.count("(--timeout): stopped") == 2


@pytest.fixture
def postgres():
    """A throwaway PostgreSQL server (scripts/postgres-test.sh: unix socket only) and a psql runner."""
    import shutil
    import tempfile
    pg_bin = os.environ.get("PG_BIN", "/usr/lib/postgresql/15/bin")
    if not os.access(os.path.join(pg_bin, "postgres"), os.X_OK):
        pytest.skip("PostgreSQL 15 server not installed (apt-get install postgresql-15)")
    script = os.path.join(ROOT, "scripts", "postgres-test.sh")
    d = tempfile.mkdtemp(prefix="rvc-pg-batch-", dir="/tmp")  # the server user must enter it
    try:
        r = subprocess.run([script, "start", d], capture_output=True, text=True, timeout=120)
        assert r.returncode == 0, r.stderr
        uri = r.stdout.strip()

        def sql(query):
            p = subprocess.run([os.path.join(pg_bin, "psql"), "-X", "-At", "-v", "ON_ERROR_STOP=1", "-d", uri, "-c",
                                "SELECT coalesce(json_agg(q), '[]') FROM (%s) q" % query],
                               capture_output=True, text=True, timeout=30)
            assert p.returncode == 0, p.stderr
            return json.loads(p.stdout)
        yield uri, sql
    finally:
        subprocess.run([script, "stop", d], capture_output=True, timeout=120)
        shutil.rmtree(d, ignore_errors=True)


def test_postgresql_store_one_run_per_bag(rvc, bags, postgres, tmp_path):
    uri, sql = postgres
    d, paths, _ = bags
    few = paths[:20]
    r = batch(rvc, *few, "--store", uri, "--workers", "2", "--no-progress", "--", "--spec", eb.SPEC)
    assert r.returncode == 1, r.stderr[-3000:]  # bags 0, 5, 10, 15 are violated
    total = json.loads(r.stdout.strip().splitlines()[-1])
    assert (total["bags"], total["violated"], total["held"], total["failed"]) == (20, 4, 16, 0)
    seq_db = tmp_path / "seq.db"
    for bag in few:
        subprocess.run([rvc, "check", bag, "--spec", eb.SPEC, "-o", "sqlite:%s" % seq_db], capture_output=True,
                       timeout=60)
    want = runs_by_bag(seq_db)
    runs = sql("SELECT run, inputs, exit_status FROM runs")
    assert sorted(json.loads(x["inputs"])[0] for x in runs) == sorted(few)
    for x in runs:
        bag = json.loads(x["inputs"])[0]
        verdicts = sql("SELECT property, time, value FROM verdicts WHERE run = '%s' ORDER BY id" % x["run"])
        got = [(v["property"], float(v["time"]), int(v["value"])) for v in verdicts]
        assert (x["exit_status"], got) == (want[bag][0], [(p, float(t), int(v)) for p, t, v in want[bag][1]]), bag


def test_one_verdict_file_per_bag_whatever_the_names(rvc, tmp_path):
    """Issue 36: `a b.mcap`, `a_b.mcap` and `sub/a b.mcap` shared one --out-dir file, each overwriting the
    last. Oracle: `rvc check` of each bag alone."""
    pytest.importorskip("dask.distributed", reason="dask[distributed] (PyPI) not installed")
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore
    ts = get_typestore(Stores.ROS2_HUMBLE)
    F = ts.types["std_msgs/msg/Float64"]
    top = tmp_path / "bags"
    (top / "sub").mkdir(parents=True)
    names = ["a b.mcap", "a_b.mcap", "sub/a b.mcap"]
    for k, name in enumerate(names):
        folder = tmp_path / f"w{k}"
        with Writer(folder, version=8, storage_plugin=StoragePlugin.MCAP) as w:
            c = w.add_connection("/speed", F.__msgtype__, typestore=ts)
            for j in range(5):  # bag k exceeds 10 at step k+1: each bag's verdicts differ
                w.write(c, 1_000 + j, ts.serialize_cdr(F(data=20.0 if j == k + 1 else 1.0), F.__msgtype__))
        os.rename(next(folder.glob("*.mcap")), top / name)
    spec = ["--", "--spec", "{data < 10}", "--all"]
    out = tmp_path / "out"
    r = batch(rvc, str(top), "--store", "sqlite:%s" % (tmp_path / "s.db"), "--out-dir", str(out), "--no-progress",
              "--workers", "1", *spec)
    assert r.returncode == 1, r.stderr
    files = sorted(os.listdir(out))
    assert len(files) == 3, files
    for name in names:
        bag = str(top / name)
        want = subprocess.run([rvc, "check", bag, *spec[1:]], capture_output=True, text=True).stdout
        assert want and open(rb.verdicts_path(str(out), bag)).read() == want, name
