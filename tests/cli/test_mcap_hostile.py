"""Hostile ROS 2 bags (MCAP): lengths that claim more than the file holds, chunks altered after
they were written, messages on channels never defined, channels redefined, many channels, and
samples rvc cannot read (zstd-compressed by rosbag2, a string cut short).

Bags are written by the `mcap` package from PyPI (Foxglove's reference writer), then patched at
offsets found by the small record walker below (independent of rvc's). Each test asserts the
one-line error (naming the record's offset), the exit status, and that the valid messages around
the bad record are still checked: the verdicts equal `rvc check` on the same valid messages
written as JSON lines. Python's own mcap reader is the oracle for "this chunk was altered".
"""
import json
import os
import struct
import subprocess
import sys

import pytest

from conftest import transports_built

pytestmark = pytest.mark.needs_rust  # every test here reads a bag

MAGIC = b"\x89MCAP0\r\n"
OP_CHANNEL, OP_MESSAGE, OP_CHUNK, OP_DATA_END = 0x04, 0x05, 0x06, 0x0F


@pytest.fixture
def mcap_rvc(rvc):
    if "zenoh" not in transports_built(rvc):  # the MCAP reader lives in the Rust library
        pytest.fail("this rvc was built without its Rust library (RVC_WITH_ZENOH=OFF): no MCAP")
    return rvc


def run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, timeout=300, **kw)


def run_measured(args):
    """Runs rvc in a child of a fresh Python, which reports the child's peak RSS (KiB)."""
    code = ("import resource, subprocess, sys, json\n"
            "r = subprocess.run(sys.argv[1:], capture_output=True, text=True)\n"
            "print(json.dumps([r.returncode, r.stdout, r.stderr, "
            "resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss]))\n")
    out = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=300)
    return json.loads(out.stdout)


def records(data, start=len(MAGIC)):
    """(offset, opcode, body offset, body length) of each record up to the data end record."""
    pos = start
    while pos + 9 <= len(data):
        op, n = data[pos], struct.unpack_from("<Q", data, pos + 1)[0]
        yield pos, op, pos + 9, n
        if op == OP_DATA_END:
            return
        pos += 9 + n


def chunk_records(data, chunk_body):
    """The records inside an uncompressed chunk: (offset in the file, opcode, body offset, length)."""
    compression_len = struct.unpack_from("<I", data, chunk_body + 28)[0]
    start = chunk_body + 32 + compression_len + 8
    n = struct.unpack_from("<Q", data, start - 8)[0]
    return [r for r in records(data[: start + n], start)]


def json_bag(path, rows, chunked=True, compression="none", chunk_size=256, data_crcs=False):
    """One JSON topic (/status), message i holding rows[i]."""
    from mcap.writer import CompressionType, Writer
    with open(path, "wb") as f:
        w = Writer(f, chunk_size=chunk_size, use_chunking=chunked,
                   compression=getattr(CompressionType, compression.upper()), enable_data_crcs=data_crcs)
        w.start(profile="", library="rvc tests")
        ch = w.register_channel(topic="/status", message_encoding="json", schema_id=0)
        for i, row in enumerate(rows):
            t = (i + 1) * 10**8
            w.add_message(channel_id=ch, log_time=t, publish_time=t, sequence=i, data=json.dumps(row).encode())
        w.finish()
    return path


def json_trace(tmp_path, rows):
    p = tmp_path / "same.jsonl"
    p.write_text("".join(json.dumps(r) + "\n" for r in rows))
    return str(p)


def message_offsets(data):
    """Offsets of every message record (also inside uncompressed chunks), in file order."""
    out = []
    for pos, op, body, n in records(data):
        if op == OP_MESSAGE:
            out.append(pos)
        elif op == OP_CHUNK:
            out += [p for p, o, _, _ in chunk_records(data, body) if o == OP_MESSAGE]
    return out


def record(op, body):
    return bytes([op]) + struct.pack("<Q", len(body)) + body


def string(b):
    return struct.pack("<I", len(b)) + b


def zstd_chunk(inner):
    """A chunk record holding `inner` (records) compressed with zstd, its sizes and CRC honest."""
    import zlib
    import zstandard
    comp = zstandard.ZstdCompressor().compress(inner)
    return record(OP_CHUNK, struct.pack("<QQQI", 0, 0, len(inner), zlib.crc32(inner)) + string(b"zstd")
                  + struct.pack("<Q", len(comp)) + comp)


def message_claiming(n):
    """A message record (channel 1) whose length claims n bytes, followed by 16 bytes."""
    return bytes([OP_MESSAGE]) + struct.pack("<Q", n) + struct.pack("<HIQQ", 1, 0, 0, 0) + b"x" * 16


def test_a_record_claiming_64_gib_is_an_error_not_an_abort(mcap_rvc, tmp_path):
    """The issue's file of a few hundred bytes: a zstd chunk whose message record claims 64 GiB. The
    mcap crate allocated the claimed length and aborted (SIGABRT); rvc names the record instead."""
    header = record(0x01, string(b"ros2") + string(b"rvc tests"))
    inner = message_claiming(64 << 30)
    tiny = MAGIC + header + zstd_chunk(inner) + record(OP_DATA_END, struct.pack("<I", 0)) + MAGIC
    assert len(tiny) < 248
    bag = tmp_path / "tiny.mcap"
    bag.write_bytes(tiny)
    r = run([mcap_rvc, "check", "--spec", "{p}", str(bag)])
    assert r.returncode == 2, (r.returncode, r.stderr)  # nothing to check: a usage error, not a crash
    assert f"the chunk at offset {len(MAGIC) + len(header)}: the message record at offset 0 of its records " \
           f"claims 68719476736 bytes, the chunk holds {len(inner)} uncompressed; its records are skipped" \
           in r.stderr, r.stderr


def test_a_record_claiming_1_gib_costs_no_memory(mcap_rvc, tmp_path):
    """A zstd chunk whose message record claims 1 GiB, among valid chunks: it cost 1 GiB of memory,
    then stopped the bag. Now the chunk is skipped, the later chunks are checked (the violation in
    one of them: exit 1), and rvc's peak RSS stays far below the claim."""
    rows = [{"p": i != 150} for i in range(200)]
    data = open(json_bag(tmp_path / "z.mcap", rows, compression="zstd"), "rb").read()
    chunks = [(pos, body, n) for pos, op, body, n in records(data) if op == OP_CHUNK]
    pos, body, n = chunks[1]
    bag = tmp_path / "claim.mcap"
    bag.write_bytes(data[:pos] + zstd_chunk(message_claiming(1 << 30)) + data[body + n:])
    rc, out, err, rss_kib = run_measured([mcap_rvc, "check", "--all", "--spec", "{p}", str(bag)])
    assert rc == 1, err
    assert f"the chunk at offset {pos}: the message record at offset 0 of its records claims 1073741824 bytes" \
        in err, err
    assert rss_kib < 200 * 1024, rss_kib
    got = [json.loads(l)["value"] for l in out.splitlines()]
    assert got.count(False) == 1 and len(got) > 150, err


def test_a_message_record_past_the_end_of_the_file(mcap_rvc, tmp_path):
    """An unchunked bag whose 11th message record claims 1 GiB: the ten before it are checked and
    the record is named by its offset (the records after it cannot be found)."""
    rows = [{"p": i != 4} for i in range(20)]
    data = bytearray(open(json_bag(tmp_path / "b.mcap", rows, chunked=False), "rb").read())
    at = message_offsets(data)[10]
    struct.pack_into("<Q", data, at + 1, 1 << 30)
    bag = tmp_path / "claim.mcap"
    bag.write_bytes(bytes(data))
    r = run([mcap_rvc, "check", "--all", "--spec", "{p}", str(bag)])
    assert r.returncode == 1, r.stderr  # message 5 violates, and is checked
    assert f"the message record at offset {at} claims 1073741824 bytes, the file has {len(data) - at - 9} left" \
        in r.stderr, r.stderr
    assert "the messages before it were checked" in r.stderr
    want = run([mcap_rvc, "check", "--all", "--spec", "{p}", json_trace(tmp_path, rows[:10])])
    assert r.stdout == want.stdout


def test_a_compressed_chunk_claiming_1_gib_is_skipped(mcap_rvc, tmp_path):
    """A zstd chunk whose uncompressed size is patched to 1 GiB: skipped (its zstd data holds far
    less), reported at its offset; the chunks after it are checked and find the violation."""
    rows = [{"p": i != 150} for i in range(200)]
    data = bytearray(open(json_bag(tmp_path / "z.mcap", rows, compression="zstd"), "rb").read())
    chunks = [(pos, body) for pos, op, body, _ in records(data) if op == OP_CHUNK]
    assert len(chunks) > 5
    pos, body = chunks[1]
    struct.pack_into("<Q", data, body + 16, 1 << 30)  # uncompressed_size
    bag = tmp_path / "zclaim.mcap"
    bag.write_bytes(bytes(data))
    rc, out, err, rss_kib = run_measured([mcap_rvc, "check", "--all", "--spec", "{p}", str(bag)])
    assert rc == 1, err
    assert f"the chunk at offset {pos}: it claims 1073741824 bytes uncompressed, its zstd data" in err, err
    assert rss_kib < 200 * 1024, rss_kib
    # Every message outside that chunk is checked, in order.
    got = [json.loads(l) for l in out.splitlines()]
    assert len(got) < 200 and got[-1]["value"] is True and any(v["value"] is False for v in got)


def test_an_altered_chunk_is_refused_and_the_rest_checked(mcap_rvc, tmp_path):
    """The violating sample altered inside its (uncompressed) chunk: it read as valid (exit 0).
    Now the chunk's CRC refuses it (as Python's mcap reader does), its messages are skipped and
    named, every other chunk is checked: exit 3."""
    rows = [{"p": i != 37} for i in range(80)]
    clean = json_bag(tmp_path / "c.mcap", rows)
    data = bytearray(open(clean, "rb").read())
    i = data.index(b'{"p": false}')
    data[i:i + 12] = b'{"p": true }'
    bag = tmp_path / "altered.mcap"
    bag.write_bytes(bytes(data))

    from mcap.reader import make_reader
    from mcap.stream_reader import CRCValidationError
    with open(bag, "rb") as f, pytest.raises(CRCValidationError):
        list(make_reader(f, validate_crcs=True).iter_messages())

    chunk = [(pos, body) for pos, op, body, n in records(data) if op == OP_CHUNK and body < i < body + n][0]
    inside = {p for p, op, _, _ in chunk_records(data, chunk[1]) if op == OP_MESSAGE}
    in_chunk = [k for k, p in enumerate(message_offsets(data)) if p in inside]
    first, last = in_chunk[0] + 1, in_chunk[-1] + 1
    assert last > first  # the chunk holds several messages
    r = run([mcap_rvc, "check", "--all", "--spec", "{p}", str(bag)])
    assert r.returncode == 3, r.stderr
    assert f"the chunk at offset {chunk[0]}: the CRC of its records is " in r.stderr, r.stderr
    assert f"(the chunk was altered); its messages {first}-{last} ({last - first + 1}) are skipped" in r.stderr
    kept = [row for k, row in enumerate(rows) if not first <= k + 1 <= last]
    want = run([mcap_rvc, "check", "--all", "--spec", "{p}", json_trace(tmp_path, kept)])
    assert r.stdout == want.stdout and want.returncode == 0
    mon = run([mcap_rvc, "monitor", "--spec", "{p}", "--input", f"mcap:{bag}"])
    stats = json.loads(mon.stderr.strip().splitlines()[-1])
    assert (mon.returncode, stats["checked"], stats["rejected"]) == (3, len(kept), 1), mon.stderr


def test_an_altered_unchunked_record_fails_the_data_section_crc(mcap_rvc, tmp_path):
    rows = [{"p": i != 12} for i in range(30)]
    data = bytearray(open(json_bag(tmp_path / "u.mcap", rows, chunked=False, data_crcs=True), "rb").read())
    i = data.index(b'{"p": false}')
    data[i:i + 12] = b'{"p": true }'
    bag = tmp_path / "u-altered.mcap"
    bag.write_bytes(bytes(data))
    end = [pos for pos, op, _, _ in records(data) if op == OP_DATA_END][0]
    r = run([mcap_rvc, "check", "--spec", "{p}", str(bag)])
    assert r.returncode == 3, r.stderr
    assert f"the CRC of the data section is " in r.stderr and f"the data end record at offset {end} records " \
        in r.stderr, r.stderr


def test_a_message_on_an_undefined_channel_is_skipped(mcap_rvc, tmp_path):
    """Message 10 names channel 9, which no record defines: it used to stop the bag (exit 3, the
    violation at message 20 never checked). Now it is skipped and counted, and the run goes on."""
    rows = [{"p": i != 19} for i in range(30)]
    data = bytearray(open(json_bag(tmp_path / "d.mcap", rows, chunked=False), "rb").read())
    at = message_offsets(data)[9]
    struct.pack_into("<H", data, at + 9, 9)  # channel id
    bag = tmp_path / "undefined.mcap"
    bag.write_bytes(bytes(data))
    r = run([mcap_rvc, "check", "--all", "--spec", "{p}", str(bag)])
    assert r.returncode == 1, r.stderr
    assert f"message 10 (the message record at offset {at}): its channel 9 is not defined (message skipped)" \
        in r.stderr, r.stderr
    want = run([mcap_rvc, "check", "--all", "--spec", "{p}", json_trace(tmp_path, rows[:9] + rows[10:])])
    assert r.stdout == want.stdout
    mon = run([mcap_rvc, "monitor", "--spec", "{p}", "--input", f"mcap:{bag}"])
    stats = json.loads(mon.stderr.strip().splitlines()[-1])
    assert (mon.returncode, stats["checked"], stats["rejected"]) == (1, 29, 1), mon.stderr


def test_a_channel_redefined_differently_keeps_its_first_definition(mcap_rvc, tmp_path):
    rows = [{"p": i != 19} for i in range(30)]
    data = open(json_bag(tmp_path / "r.mcap", rows, chunked=False), "rb").read()
    at = message_offsets(data)[5]
    body = struct.pack("<HH", 1, 0)
    for s in (b"/other", b"json"):
        body += struct.pack("<I", len(s)) + s
    body += struct.pack("<I", 0)  # no metadata
    bag = tmp_path / "redefined.mcap"
    bag.write_bytes(data[:at] + bytes([OP_CHANNEL]) + struct.pack("<Q", len(body)) + body + data[at:])
    r = run([mcap_rvc, "check", "--all", "--spec", "{p}", str(bag)])
    assert r.returncode == 1, r.stderr
    assert f"the channel record at offset {at}: channel 1 is redefined differently ('/other', first '/status'): " \
           "the first definition stays (record skipped)" in r.stderr, r.stderr
    want = run([mcap_rvc, "check", "--all", "--spec", "{p}", json_trace(tmp_path, rows)])
    assert r.stdout == want.stdout


def test_a_bag_of_65535_channels(mcap_rvc, tmp_path):
    """Each of 65,535 channels with its own topic and two messages; the checked topic's messages
    are found among all the others (the channel of each message is looked up by id, not searched)."""
    from mcap.writer import CompressionType, Writer
    path = tmp_path / "many.mcap"
    n = 65535
    with open(path, "wb") as f:
        w = Writer(f, compression=CompressionType.NONE, chunk_size=1 << 20)
        w.start(profile="", library="rvc tests")
        ids = [w.register_channel(topic=f"/c{k}", message_encoding="json", schema_id=0) for k in range(n)]
        for rnd in range(2):
            for k, ch in enumerate(ids):
                t = (rnd * n + k + 1) * 1000
                w.add_message(channel_id=ch, log_time=t, publish_time=t, sequence=rnd,
                              data=b'{"p": %s}' % (b"false" if (k, rnd) == (n - 1, 1) else b"true"))
        w.finish()
    r = run([mcap_rvc, "check", "--all", "--spec", "{p}", str(path), "--topic", f"/c{n - 1}"])
    assert r.returncode == 1, r.stderr[-2000:]
    assert [json.loads(l)["value"] for l in r.stdout.splitlines()] == [True, False]


NESTED_SCHEMA = ("test_msgs/Inner inner\nuint8 level\n"
                 "================================================================================\n"
                 "MSG: test_msgs/Inner\nstring label\n")


def nested_sample(label, level):
    """CDR (little endian) of test_msgs/msg/Outer {inner: {label}, level}, by hand."""
    s = label.encode() + b"\0"
    return b"\x00\x01\x00\x00" + struct.pack("<I", len(s)) + s + bytes([level])


def test_samples_rvc_cannot_read_say_what_they_are(mcap_rvc, tmp_path):
    """A string cut short is refused with what it is, the others are checked; a sample compressed by
    rosbag2's per-message compression (a zstd frame) is decompressed and checked (issue 28)."""
    import zstandard
    from mcap.writer import CompressionType, Writer
    good = [nested_sample("abc", 1), nested_sample("abcdef", 2), nested_sample("x", 7)]
    cut = nested_sample("abcdef", 2)[:4 + 4 + 3]  # the string claims 7 bytes, 3 are there
    samples = [good[0], zstandard.ZstdCompressor().compress(good[1]), cut, good[2]]
    path = tmp_path / "samples.mcap"
    with open(path, "wb") as f:
        w = Writer(f, compression=CompressionType.NONE)
        w.start(profile="ros2", library="rvc tests")
        sid = w.register_schema(name="test_msgs/msg/Outer", encoding="ros2msg", data=NESTED_SCHEMA.encode())
        ch = w.register_channel(topic="/outer", message_encoding="cdr", schema_id=sid)
        for i, s in enumerate(samples):
            w.add_message(channel_id=ch, log_time=i + 1, publish_time=i + 1, sequence=i, data=s)
        w.finish()
    r = run([mcap_rvc, "check", "--all", "--spec", "{level < 5}", str(path)])
    assert r.returncode == 1, r.stderr
    assert [json.loads(l)["value"] for l in r.stdout.splitlines()] == [True, True, False]
    assert "message 2" not in r.stderr, r.stderr
    assert "message 3: bad test_msgs/msg/Outer sample: string field 'inner.label' claims 7 bytes, the sample has " \
           "3 left at byte 4" in r.stderr, r.stderr


def test_a_chunk_over_the_limit_is_skipped_before_it_is_decompressed(mcap_rvc, tmp_path):
    """A zstd chunk of 300 MiB of zeros (about 10 KiB compressed: its frames can hold it) is over
    rvc's limit for one chunk (256 MiB, docs/ros2-types.md): skipped, named, nothing allocated for it;
    the chunks after it are checked."""
    import zlib
    import zstandard
    size = 300 << 20
    payload_len = size - 9 - 22
    head = bytes([OP_MESSAGE]) + struct.pack("<Q", 22 + payload_len) + struct.pack("<HIQQ", 1, 0, 0, 0)
    crc, comp = zlib.crc32(head), zstandard.ZstdCompressor().compressobj(size=size)
    parts = [comp.compress(head)]
    zeros = bytes(1 << 20)
    for k in range(0, payload_len, len(zeros)):
        block = zeros[: min(len(zeros), payload_len - k)]
        crc = zlib.crc32(block, crc)
        parts.append(comp.compress(block))
    parts.append(comp.flush())
    data_z = b"".join(parts)
    chunk = record(OP_CHUNK, struct.pack("<QQQI", 0, 0, size, crc) + string(b"zstd")
                   + struct.pack("<Q", len(data_z)) + data_z)
    rows = [{"p": i != 150} for i in range(200)]
    data = open(json_bag(tmp_path / "z.mcap", rows, compression="zstd"), "rb").read()
    chunks = [(pos, body, n) for pos, op, body, n in records(data) if op == OP_CHUNK]
    pos, body, n = chunks[1]
    bag = tmp_path / "big.mcap"
    bag.write_bytes(data[:pos] + chunk + data[body + n:])
    rc, out, err, rss_kib = run_measured([mcap_rvc, "check", "--all", "--spec", "{p}", str(bag)])
    assert rc == 1, err
    assert f"the chunk at offset {pos}: it claims {size} bytes uncompressed, over rvc's limit of 256 MiB for " \
           "one chunk; its records are skipped" in err, err
    assert rss_kib < 200 * 1024, rss_kib


@pytest.mark.parametrize("compression", ["none", "zstd"])
def test_a_record_with_a_bad_length_keeps_the_records_before_it(mcap_rvc, tmp_path, compression):
    """A message record in the middle of a chunk whose length is patched to 1 TiB: the valid records
    before it in the same chunk were lost with the chunk (its CRC refused it whole, or its zstd data
    was refused at the bad record). Now they are checked, the chunk's rest is skipped naming the
    record's offset, every other chunk is checked. Oracle: the `mcap` package's reader (it gives the
    damaged record's bytes up to the chunk's end as one more message, which no JSON parser reads)."""
    rows = [{"p": i != 70, "i": i} for i in range(80)]
    data = bytearray(open(json_bag(tmp_path / "c.mcap", rows, chunk_size=1024), "rb").read())
    chunks = [(pos, body, n) for pos, op, body, n in records(data) if op == OP_CHUNK]
    assert len(chunks) >= 3
    pos, body, n = chunks[1]
    inner = [r for r in chunk_records(data, body) if r[1] == OP_MESSAGE]
    bad_at = inner[len(inner) // 2][0]
    start = chunk_records(data, body)[0][0]  # the chunk's records begin here
    struct.pack_into("<Q", data, bad_at + 1, 1 << 40)
    if compression == "zstd":  # the same records, zstd-compressed, the chunk's sizes and CRC honest
        end = body + n
        data = data[:pos] + zstd_chunk(bytes(data[start:end])) + data[end:]
    bag = tmp_path / "badlen.mcap"
    bag.write_bytes(bytes(data))

    from mcap.stream_reader import StreamReader
    from mcap.records import Message
    want = []
    with open(bag, "rb") as f:
        for r in StreamReader(f).records:
            if isinstance(r, Message):
                try:
                    want.append(json.loads(r.data))
                except ValueError:
                    pass  # the damaged record
    assert len(want) > len(rows) - len(inner)  # some of that chunk's records are valid

    r = run([mcap_rvc, "echo", str(bag)])
    assert r.returncode == 3, r.stderr
    assert [json.loads(l) for l in r.stdout.splitlines()] == want
    said = f"the chunk at offset {pos}: " + (
        "the CRC of its records is " if compression == "none" else "")
    assert said in r.stderr and f"the message record at offset {bad_at - start} " in r.stderr and \
        "claims 1099511627776 bytes" in r.stderr and "its records before that one are read, the rest skipped" \
        in r.stderr, r.stderr
    c = run([mcap_rvc, "check", "--all", "--stats", "--spec", "{p}", str(bag)])
    assert c.returncode == 1, c.stderr  # message 70, in the last chunk
    counters = json.loads(c.stderr.strip().splitlines()[-1])
    assert (counters["received"], counters["checked"], counters["rejected"]) == (len(want) + 1, len(want), 1)
    same = run([mcap_rvc, "check", "--all", "--spec", "{p}", json_trace(tmp_path, want)])
    assert c.stdout == same.stdout


@pytest.mark.parametrize("name,content,said", [
    ("rec.mcap", b"", "is an empty file (0 bytes), not an MCAP file: a recording cut short before its first byte?"),
    ("rec.mcap", MAGIC[:5], "is a truncated MCAP file: 5 bytes, its 8-byte magic cut short"),
    ("rec.db3", b"", "is an empty file (0 bytes), not a rosbag2 sqlite3 file"),
])
def test_an_empty_or_cut_bag_file_is_named_so(mcap_rvc, tmp_path, name, content, said):
    """An empty .mcap with --topic was "a JSON-lines trace" (and without --topic "nothing was
    checked", exit 6): now every command says it is an empty or truncated bag file, exit 2."""
    bag = tmp_path / name
    bag.write_bytes(content)
    for args in (["check", str(bag), "--topic", "/x", "--spec", "{p}"], ["check", str(bag), "--spec", "{p}"],
                 ["echo", str(bag), "--topic", "/x"], ["bag", "info", str(bag)],
                 ["monitor", "--input", f"bag:{bag}", "--spec", "{p}"]):
        r = run([mcap_rvc, *args])
        assert r.returncode == 2, (args, r.stderr)
        assert f"bag '{bag}' {said}" in r.stderr and "JSON-lines" not in r.stderr, (args, r.stderr)
