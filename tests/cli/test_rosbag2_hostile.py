"""Hostile rosbag2 sqlite3 bags: not a bag, tables or columns missing, values of the wrong SQLite
type, a topic id that names no topic, a CDR blob cut short, a database cut in half, a broken
metadata.yaml. Each gives one clear line naming the problem (and the message, by index and row id),
the exit status of docs/cli.md, never a crash; the valid messages around a bad row are still
checked, with verdicts equal to `rvc check` on the same valid values as JSON lines.

Bags are written here with Python's sqlite3 in rosbag2's schema, samples serialized by rosbags.
"""
import json
import os
import sqlite3
import subprocess

import pytest

SCHEMA = """
CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);
CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL, metadata TEXT NOT NULL);
CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
                    serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL,
                    type_description_hash TEXT NOT NULL);
CREATE TABLE message_definitions(id INTEGER PRIMARY KEY, topic_type TEXT NOT NULL, encoding TEXT NOT NULL,
                                 encoded_message_definition TEXT NOT NULL, type_description_hash TEXT NOT NULL);
CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, data BLOB NOT NULL);
"""
SPEC = "historically({data < 30})"


def run(args, **kw):
    # errors="replace": a damaged bag's names may hold any bytes, and rvc prints them as the bag has them
    return subprocess.run(args, capture_output=True, text=True, errors="replace", timeout=120, **kw)


def float64(v):
    """std_msgs/msg/Float64 as CDR, serialized by rosbags."""
    from rosbags.typesys import Stores, get_typestore
    ts = get_typestore(Stores.ROS2_HUMBLE)
    t = ts.types["std_msgs/msg/Float64"]
    return bytes(ts.serialize_cdr(t(data=v), t.__msgtype__))


def make_db3(path, rows, schema=SCHEMA, definitions=True):
    con = sqlite3.connect(path)
    con.executescript(schema)
    if "CREATE TABLE topics" in schema:
        con.execute("INSERT INTO topics VALUES (1, '/speed', 'std_msgs/msg/Float64', 'cdr', '', '')")
    if definitions and "message_definitions" in schema:
        con.execute("INSERT INTO message_definitions VALUES (1, 'std_msgs/msg/Float64', 'ros2msg', 'float64 data', '')")
    for row in rows:
        con.execute("INSERT INTO messages(topic_id, timestamp, data) VALUES (?, ?, ?)", row)
    con.commit()
    con.close()
    return str(path)


def good_rows(values):
    return [(1, 1000 + i, float64(v)) for i, v in enumerate(values)]


def check(rvc, bag, *extra):
    return run([rvc, "check", bag, "--spec", SPEC, "--stats", *extra])


def test_valid_db3_checks_like_json(rvc, tmp_path):
    values = [1.0, 2.0, 31.0, 4.0]
    bag = make_db3(tmp_path / "ok.db3", good_rows(values))
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(json.dumps({"time": i, "data": v}) + "\n" for i, v in enumerate(values)))
    r, want = check(rvc, bag), run([rvc, "check", "--spec", SPEC, str(trace)])
    assert r.returncode == want.returncode == 1, r.stderr
    assert [json.loads(x)["value"] for x in r.stdout.splitlines()] == [json.loads(x)["value"] for x in want.stdout.splitlines()]


@pytest.mark.parametrize("what,schema,needle", [
    ("no tables", "CREATE TABLE notes(id INTEGER, text TEXT);", "not a rosbag2 bag: it has no table 'topics'"),
    ("no messages", SCHEMA.split("CREATE TABLE messages")[0], "not a rosbag2 bag: it has no table 'messages'"),
    ("no data column", SCHEMA.replace(", data BLOB NOT NULL", ""), "table 'messages' has no column 'data'"),
])
def test_sqlite_that_is_no_bag_is_refused(rvc, tmp_path, what, schema, needle):
    con = sqlite3.connect(tmp_path / "x.db3")
    con.executescript(schema)
    con.commit()
    con.close()
    bag = str(tmp_path / "x.db3")
    for args in (["check", bag, "--spec", SPEC], ["echo", bag], ["bag", "info", bag],
                 ["monitor", "--input", "bag:" + bag, "--spec", SPEC]):
        r = run([rvc, *args])
        assert r.returncode == 2, (what, args, r.stderr)
        assert needle in r.stderr and "invalid JSON" not in r.stderr, (what, args, r.stderr)
        assert len(r.stderr.strip().splitlines()) <= 2, r.stderr  # monitor may print its header line first


@pytest.mark.parametrize("bad_row,reason", [
    ((1, 1002, 7), "data is an integer, not a blob"),
    ((1, "soon", float64(5.0)), "timestamp is text, not nanoseconds since the epoch"),
    ((9, 1002, float64(5.0)), "topic_id 9 is no row of table 'topics'"),
])
def test_rows_of_the_wrong_type_are_skipped_and_counted(rvc, tmp_path, bad_row, reason):
    values = [1.0, 2.0, 31.0, 4.0]
    rows = good_rows(values)
    rows.insert(2, bad_row)
    bag = make_db3(tmp_path / "bad.db3", rows)
    r = check(rvc, bag)
    assert r.returncode == 1, r.stderr  # the violation among the valid rows still counts first
    assert reason in r.stderr and "(row id 3 of table 'messages')" in r.stderr, r.stderr
    counters = json.loads(r.stderr.strip().splitlines()[-1])
    assert counters["checked"] == len(values) and counters["rejected"] == 1
    assert counters["received"] == counters["checked"] + counters["rejected"]  # the bad row was received too
    ok = run([rvc, "check", bag, "--spec", "historically({data < 100})", "--stats"])
    assert ok.returncode == 3, ok.stderr  # nothing violated: the skipped row is rejected input
    e = run([rvc, "echo", bag])
    assert e.returncode == 3 and len(e.stdout.splitlines()) == len(values), e.stderr


def test_blob_cut_short_is_rejected_with_its_position(rvc, tmp_path):
    rows = good_rows([1.0, 2.0, 3.0])
    rows[1] = (1, 1001, float64(2.0)[:10])
    bag = make_db3(tmp_path / "cut.db3", rows)
    r = check(rvc, bag)
    assert r.returncode == 3, r.stderr
    assert "message 2" in r.stderr, r.stderr
    counters = json.loads(r.stderr.strip().splitlines()[-1])
    assert counters["received"] == 3 and counters["checked"] == 2 and counters["rejected"] == 1
    e = run([rvc, "echo", bag])
    assert e.returncode == 3 and len(e.stdout.splitlines()) == 2 and "message 2: not a std_msgs/msg/Float64" in e.stderr


def test_database_cut_in_half_is_no_crash(rvc, tmp_path):
    bag = make_db3(tmp_path / "big.db3", good_rows([float(i % 20) for i in range(3000)]))
    data = open(bag, "rb").read()
    half = tmp_path / "half.db3"
    half.write_bytes(data[: len(data) // 2])
    for args in (["check", str(half), "--spec", SPEC, "--stats"], ["echo", str(half)], ["bag", "info", str(half)]):
        r = run([rvc, *args])
        assert r.returncode in (2, 3), (args, r.returncode, r.stderr)  # refused, or read as far as it goes
        assert r.stderr.strip() and "Traceback" not in r.stderr and len(r.stderr.splitlines()) < 10, r.stderr


def test_garbage_after_sqlite_magic(rvc, tmp_path):
    bad = tmp_path / "fake.db3"
    bad.write_bytes(b"SQLite format 3\x00" + os.urandom(64))
    r = run([rvc, "check", str(bad), "--spec", SPEC])
    assert r.returncode == 2 and "bag '" in r.stderr and len(r.stderr.splitlines()) == 1, r.stderr


def test_broken_metadata_yaml_names_its_line(rvc, tmp_path):
    folder = tmp_path / "bag"
    folder.mkdir()
    make_db3(folder / "bag_0.db3", good_rows([1.0]))
    (folder / "metadata.yaml").write_text("rosbag2_bagfile_information:\n  version: 8\n  files: [\n")
    r = run([rvc, "check", str(folder), "--spec", SPEC])
    assert r.returncode == 2 and "metadata.yaml:" in r.stderr and len(r.stderr.splitlines()) == 1, r.stderr
    (folder / "metadata.yaml").write_text("rosbag2_bagfile_information:\n  relative_file_paths: [gone.db3]\n")
    r = run([rvc, "echo", str(folder)])
    assert r.returncode == 2 and "'gone.db3', which is not in the folder" in r.stderr, r.stderr


def test_db3_without_definitions_uses_bundled_types(rvc, tmp_path):
    """A Humble bag (no message_definitions table): std_msgs/Float64 from the bundled definitions."""
    schema = SCHEMA.replace(SCHEMA[SCHEMA.index("CREATE TABLE message_definitions"):SCHEMA.index("CREATE TABLE messages")], "")
    bag = make_db3(tmp_path / "humble.db3", good_rows([1.0, 2.0]), schema=schema)
    r = run([rvc, "echo", bag])
    assert r.returncode == 0, r.stderr
    assert [json.loads(x) for x in r.stdout.splitlines()] == [{"data": 1.0}, {"data": 2.0}]


def test_corrupted_db3_never_crashes(rvc, tmp_path):
    """Seeded random damage (bytes overwritten, the file cut) to a valid db3 bag, 150 variants:
    every run ends with an exit status of docs/cli.md, never a signal, and says why on stderr."""
    import random
    rng = random.Random(28)
    good = open(make_db3(tmp_path / "good.db3", good_rows([float(i % 40) for i in range(200)])), "rb").read()
    bad = tmp_path / "bad.db3"
    seen = set()
    for k in range(150):
        data = bytearray(good)
        for _ in range(rng.randint(1, 40)):
            pos = rng.randrange(100, len(data))  # past the header's magic: still a SQLite file
            data[pos] = rng.randrange(256)
        if k % 5 == 0:
            data = data[: rng.randrange(100, len(data))]
        bad.write_bytes(bytes(data))
        for args in (["check", str(bad), "--spec", SPEC, "--stats"], ["bag", "info", str(bad)]):
            r = run([rvc, *args])
            assert r.returncode in (0, 1, 2, 3, 6), (k, args, r.returncode, r.stderr[-500:])
            seen.add(r.returncode)
            assert "invalid JSON" not in r.stderr, (k, args, r.stderr[-500:])  # read as a bag, never as text
            if r.returncode not in (0, 1):
                assert r.stderr.strip(), (k, args)
    assert 2 in seen or 3 in seen  # the damage was noticed at least once


# --- compression bombs: per-message zstd is streamed under the size cap ------------------------------

def zstd_bomb(size, declare):
    """A zstd frame of zeros that decompresses to `size` bytes: a few tens of KB. `declare`: the frame
    header says its size (zstd's one-shot API writes it; a streaming writer may not)."""
    import zstandard
    c = zstandard.ZstdCompressor(level=3, write_content_size=declare)
    obj = c.compressobj(size=size if declare else -1)
    block, out = bytes(16 << 20), []
    for _ in range(size // len(block)):
        out.append(obj.compress(block))
    out.append(obj.flush())
    return b"".join(out)


def run_capped(args, mib=1024):
    """rvc under a memory cap (rvc_testlib.memory_capped): an allocation of the decompressed size fails the run."""
    from rvc_testlib import memory_capped
    return subprocess.run(args, capture_output=True, text=True, errors="replace", timeout=300, **memory_capped(mib))


BOMB = 1536 << 20  # 1.5 GiB of zeros, as in the issue


def compressed_bag(folder, storage, datas):
    """A bag folder (compression_mode: message) of /speed messages whose data are `datas` as given."""
    folder.mkdir()
    if storage == "sqlite3":
        make_db3(folder / "bag_0.db3", [(1, 1000 + i, d) for i, d in enumerate(datas)])
    else:
        from mcap.writer import CompressionType, Writer
        with open(folder / "bag_0.mcap", "wb") as f:
            w = Writer(f, compression=CompressionType.NONE)
            w.start(profile="ros2", library="rvc tests")
            sid = w.register_schema(name="std_msgs/msg/Float64", encoding="ros2msg", data=b"float64 data")
            ch = w.register_channel(topic="/speed", message_encoding="cdr", schema_id=sid)
            for i, d in enumerate(datas):
                w.add_message(channel_id=ch, log_time=1000 + i, publish_time=1000 + i, sequence=i, data=d)
            w.finish()
    (folder / "metadata.yaml").write_text(
        f"rosbag2_bagfile_information:\n  version: 8\n  storage_identifier: {storage}\n"
        f"  relative_file_paths: [bag_0.{'db3' if storage == 'sqlite3' else 'mcap'}]\n"
        "  compression_format: zstd\n  compression_mode: message\n")
    return str(folder)


@pytest.mark.parametrize("storage", ["sqlite3", pytest.param("mcap", marks=pytest.mark.needs_rust)])
@pytest.mark.parametrize("declare", [True, False])
def test_a_zstd_bomb_message_is_rejected_and_the_next_one_checked(rvc, tmp_path, declare, storage):
    """compression_mode: message, message 2 a 1.5 GiB zstd bomb: it was decompressed whole before the
    size check (2.1 GB resident, std::bad_alloc exit 5 under a limit) and the valid message after it was
    never read. Now decompression stops at the cap, under a 1 GiB address-space limit: the bomb is named
    with its index, counted as rejected, the messages around it checked (the violation after it: exit 1)."""
    import zstandard
    bomb = zstd_bomb(BOMB, declare)
    assert len(bomb) < 200_000
    z = zstandard.ZstdCompressor()
    folder = compressed_bag(tmp_path / "bag", storage, [z.compress(float64(1.0)), bomb, z.compress(float64(31.0)),
                                                         z.compress(float64(2.0))])
    def said(limit):
        return "message 2 on /speed: zstd: " + (
            f"its frame declares {BOMB} bytes decompressed, over the limit of {limit} (--max-message-size)" if declare
            else f"it decompresses to more than the limit of {limit} bytes (decompression stopped there) "
                 "(--max-message-size)")
    for args in (["check", folder, "--spec", SPEC, "--stats"], ["monitor", "--input", f"bag:{folder}", "--spec", SPEC]):
        r = run_capped([rvc, *args])
        assert r.returncode == 1, (args, r.returncode, r.stderr)
        assert said(268435456) in r.stderr, r.stderr
        counters = json.loads(r.stderr.strip().splitlines()[-1])
        assert (counters["received"], counters["checked"], counters["rejected"]) == (4, 3, 1), counters
    r = run_capped([rvc, "check", folder, "--spec", SPEC, "--max-message-size", "1000"])
    assert r.returncode == 1 and said(1000) in r.stderr, r.stderr
    e = run_capped([rvc, "echo", folder])
    assert e.returncode == 3 and [json.loads(x)["data"] for x in e.stdout.splitlines()] == [1.0, 31.0, 2.0], e.stderr


# --- a damaged page: everything readable is read, the damage named and counted ----------------------

N_DAMAGED = 2130


def damaged_bag(tmp_path, where, index=False, values=None):
    """A bag of N_DAMAGED Float64 messages (data = i % 20, or `values`), one leaf page of table
    'messages' overwritten with 0xff: the middle one, or the last. SQLite's dbstat names the pages."""
    values = values or [float(i % 20) for i in range(N_DAMAGED)]
    bag = make_db3(tmp_path / "good.db3", good_rows(values))
    con = sqlite3.connect(bag)
    if index:  # rosbag2's own schema has it: ORDER BY timestamp then streams through the index
        con.execute("CREATE INDEX timestamp_idx ON messages (timestamp ASC)")
        con.commit()
    leaves = [p for (p,) in con.execute("SELECT pageno FROM dbstat WHERE name = 'messages' AND pagetype = 'leaf' "
                                        "ORDER BY pageno")]
    page_size = con.execute("PRAGMA page_size").fetchone()[0]
    con.close()
    page = leaves[len(leaves) // 2] if where == "middle" else leaves[-1]
    data = bytearray(open(bag, "rb").read())
    data[(page - 1) * page_size: page * page_size] = b"\xff" * page_size
    bad = tmp_path / f"damaged_{where}.db3"
    bad.write_bytes(bytes(data))
    return str(bad), values


def sqlite_oracle(path):
    """Python's sqlite3 on the damaged file: the rows a scan returns before the error, and the rows
    a lookup by row id reads (every row not on the bad page)."""
    con = sqlite3.connect(f"file:{path}?immutable=1", uri=True)
    scanned = 0
    with pytest.raises(sqlite3.DatabaseError, match="malformed"):
        for _ in con.execute("SELECT id, topic_id, timestamp, data FROM messages"):
            scanned += 1
    readable = []
    for i in range(1, N_DAMAGED + 1):
        try:
            if con.execute("SELECT id FROM messages WHERE id = ?", (i,)).fetchone():
                readable.append(i)
        except sqlite3.DatabaseError:
            pass
    con.close()
    return scanned, readable


@pytest.mark.parametrize("index", [False, True])
def test_a_damaged_page_costs_only_its_rows(rvc, tmp_path, index):
    """One damaged leaf page in the middle of table 'messages': the bag was refused whole ("database
    disk image is malformed", exit 2, nothing checked; `bag info` 0 messages). Now every row SQLite can
    read is checked (the oracle: Python's sqlite3, by row id), the lost row ids are named once and
    counted as one rejected record (received = checked + rejected), the violation after the damage is
    found (exit 1), a property that holds exits 3; `bag info` counts the readable rows and says why."""
    values = [1.0] * N_DAMAGED
    values[-5] = 31.0  # after the damaged page: found only if reading goes on past it
    bag, values = damaged_bag(tmp_path, "middle", index, values)
    scanned, readable = sqlite_oracle(bag)
    lost = [i for i in range(1, N_DAMAGED + 1) if i not in set(readable)]
    assert 0 < scanned < len(readable) < N_DAMAGED and lost == list(range(lost[0], lost[-1] + 1))
    r = check(rvc, bag)
    assert r.returncode == 1, r.stderr
    assert f"row ids {lost[0]}-{lost[-1]} of table 'messages' cannot be read (SQLite: database disk image is " \
           f"malformed), after message {lost[0] - 1}: skipped; reading goes on at row id {lost[-1] + 1}" in r.stderr
    counters = json.loads(r.stderr.strip().splitlines()[-1])
    assert (counters["received"], counters["checked"], counters["rejected"]) == (len(readable) + 1, len(readable), 1)
    ok = run([rvc, "check", bag, "--spec", "historically({data < 100})", "--stats"])
    assert ok.returncode == 3, ok.stderr
    e = run([rvc, "echo", bag])
    assert e.returncode == 3, e.stderr
    assert [json.loads(x)["data"] for x in e.stdout.splitlines()] == [values[i - 1] for i in readable]
    info = run([rvc, "bag", "info", bag, "--json"])
    assert info.returncode == 3, info.stderr
    s = json.loads(info.stdout)
    assert s["messages"] == len(readable) and f"row ids {lost[0]}-{lost[-1]}" in s["skipped"], s


def test_a_damaged_last_page_keeps_the_rows_before_it(rvc, tmp_path):
    """The last leaf damaged: every row before it is checked (as many as SQLite reads by row id; a
    scan gives one fewer), then the rest is named as unreadable: exit 3, `bag info` the same counts."""
    bag, values = damaged_bag(tmp_path, "last")
    scanned, readable = sqlite_oracle(bag)
    assert readable == list(range(1, len(readable) + 1)) and scanned <= len(readable) < N_DAMAGED
    r = check(rvc, bag)
    assert r.returncode == 3, r.stderr
    assert f"SQLite cannot read on after message {len(readable)}: the rows from row id {len(readable) + 1} on of " \
           "table 'messages' cannot be read (database disk image is malformed)" in r.stderr, r.stderr
    counters = json.loads(r.stderr.strip().splitlines()[-1])
    assert (counters["received"], counters["checked"]) == (len(readable), len(readable))
    info = run([rvc, "bag", "info", bag, "--json"])
    assert info.returncode == 3 and json.loads(info.stdout)["messages"] == len(readable), info.stderr


# --- bag folders whose entries are no files -----------------------------------------------------------

@pytest.mark.parametrize("case", ["metadata loop", "metadata folder", "storage loop", "storage folder",
                                  "storage dangling"])
def test_a_bag_folder_entry_that_is_no_file_is_named(rvc, tmp_path, case):
    """metadata.yaml or a storage file that is a symlink loop, a folder or a dangling link ended
    check/echo/bag info with an uncaught C++ exception ("rvc: error: filesystem error: ...",
    "basic_filebuf::underflow error ..."), exit 5. Now: one line naming the path and the problem, exit 2."""
    folder = tmp_path / "bag"
    folder.mkdir()
    make_db3(folder / "bag_0.db3", good_rows([1.0]))
    md = "rosbag2_bagfile_information:\n  relative_file_paths: [{}]\n"
    if case.startswith("metadata"):
        target, why = folder / "metadata.yaml", ("Too many levels of symbolic links" if "loop" in case
                                                  else "it is a folder, not a file")
        if "loop" in case:
            os.symlink("metadata.yaml", target)
        else:
            target.mkdir()
        needle = f"cannot read {target}: {why}"
    else:
        (folder / "metadata.yaml").write_text(md.format("x.db3"))
        target = folder / "x.db3"
        if "loop" in case:
            os.symlink("y.db3", target)
            os.symlink("x.db3", folder / "y.db3")
            why = "Too many levels of symbolic links"
        elif "folder" in case:
            target.mkdir()
            why = "it is a folder, not a file"
        else:
            os.symlink("gone.db3", target)
            why = "No such file or directory"
        needle = f"metadata.yaml lists 'x.db3', which cannot be read: {target}: {why}"
    for args in (["check", str(folder), "--spec", SPEC], ["echo", str(folder)], ["bag", "info", str(folder)],
                 ["monitor", "--input", f"bag:{folder}", "--spec", SPEC]):
        r = run([rvc, *args])
        assert r.returncode == 2, (case, args, r.returncode, r.stderr)
        assert needle in r.stderr and "error:" not in r.stderr, (case, args, r.stderr)
