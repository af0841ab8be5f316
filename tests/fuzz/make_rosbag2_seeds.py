"""Writes the seeds of fuzz_db3, fuzz_bag_folder and fuzz_zstd (tests/fuzz/corpus/<name>): small
rosbag2 sqlite3 files written with Python's sqlite3 in rosbag2's schema (512-byte pages, so a few
pages each: with and without the timestamp index and message_definitions, per-message zstd, a
damaged page, a file cut short), metadata.yaml texts (single and split bags, compression modes,
old-style paths, entries that are no files), and zstd frames (declared size or not, several frames,
skippable frames, a bomb of 64 MiB of zeros, a frame cut short).

    python3 tests/fuzz/make_rosbag2_seeds.py
"""
import os
import sqlite3
import struct

import zstandard

HERE = os.path.dirname(os.path.abspath(__file__))
CORPUS = os.path.join(HERE, "corpus")
SCHEMA = """
PRAGMA page_size = 512;
CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);
CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
                    serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
CREATE TABLE message_definitions(id INTEGER PRIMARY KEY, topic_type TEXT NOT NULL, encoding TEXT NOT NULL,
                                 encoded_message_definition TEXT NOT NULL);
CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, data BLOB NOT NULL);
"""


def float64(v):
    return b"\x00\x01\x00\x00" + struct.pack("<d", v)


def db3(path, n=40, index=False, compress=False, rows=None):
    if os.path.exists(path):
        os.remove(path)
    con = sqlite3.connect(path)
    con.executescript(SCHEMA)
    con.execute("INSERT INTO topics VALUES (1, '/speed', 'std_msgs/msg/Float64', 'cdr', '')")
    con.execute("INSERT INTO topics VALUES (2, '/status', 'std_msgs/msg/String', 'json', '')")
    con.execute("INSERT INTO message_definitions VALUES (1, 'std_msgs/msg/Float64', 'ros2msg', 'float64 data')")
    z = zstandard.ZstdCompressor()
    for i in range(n):
        data = float64(i % 7)
        con.execute("INSERT INTO messages(topic_id, timestamp, data) VALUES (?, ?, ?)",
                    (1 + i % 2, 1000 + i, z.compress(data) if compress else data))
    for row in rows or []:
        con.execute("INSERT INTO messages(topic_id, timestamp, data) VALUES (?, ?, ?)", row)
    if index:
        con.execute("CREATE INDEX timestamp_idx ON messages (timestamp ASC)")
    con.commit()
    con.close()
    return open(path, "rb").read()


def write(name, files):
    out = os.path.join(CORPUS, name)
    os.makedirs(out, exist_ok=True)
    for f, data in files.items():
        with open(os.path.join(out, f), "wb") as fh:
            fh.write(data)


def main():
    tmp = os.path.join(CORPUS, "..", "seed.tmp.db3")
    plain = db3(tmp)
    damaged = bytearray(db3(tmp, n=120))
    damaged[512 * 5: 512 * 6] = b"\xff" * 512  # one page of table 'messages'
    write("db3", {
        "plain.db3": plain,
        "index.db3": db3(tmp, index=True),
        "zstd_messages.db3": db3(tmp, compress=True),
        "bad_rows.db3": db3(tmp, n=10, rows=[(9, 5, float64(1)), (1, "soon", float64(2)), (1, 7, 3), (1, -4, b"")]),
        "damaged_page.db3": bytes(damaged),
        "cut_short.db3": plain[: len(plain) // 2],
    })
    os.remove(tmp)
    md = ("rosbag2_bagfile_information:\n  version: 8\n  storage_identifier: sqlite3\n"
          "  relative_file_paths:\n{files}  compression_format: '{fmt}'\n  compression_mode: '{mode}'\n"
          "  topics_with_message_count:\n    - topic_metadata:\n        name: /speed\n"
          "        type: std_msgs/msg/Float64\n        serialization_format: cdr\n      message_count: 20\n")
    def files(*names):
        return "".join(f"    - {n}\n" for n in names)
    write("bag_folder", {
        "single.yaml": md.format(files=files("bag_0.db3"), fmt="", mode="").encode(),
        "split.yaml": md.format(files=files("bag_0.db3", "bag_1.db3"), fmt="", mode="").encode(),
        "old_style.yaml": md.format(files=files("bag/bag_0.db3"), fmt="", mode="").encode(),
        "message_zstd.yaml": md.format(files=files("bag_0.db3"), fmt="zstd", mode="message").encode(),
        "not_files.yaml": md.format(files=files("sub", "loop_a", "dangling.db3", "metadata.yaml"), fmt="",
                                    mode="").encode(),
        "flow.yaml": b"rosbag2_bagfile_information: {relative_file_paths: [bag_0.db3, bag_1.db3], version: 5}\n",
        "anchors.yaml": b"rosbag2_bagfile_information:\n  relative_file_paths: &f [bag_0.db3]\n"
                        b"  topics_with_message_count: [{topic_metadata: {name: /a}}, *f]\n",
    })
    z = zstandard.ZstdCompressor()
    sample = float64(1.5)
    bomb = zstandard.ZstdCompressor(level=19).compress(bytes(64 << 20))
    undeclared = zstandard.ZstdCompressor(write_content_size=False).compressobj()
    streamed = undeclared.compress(sample * 100) + undeclared.flush()
    skippable = struct.pack("<II", 0x184D2A50, 4) + b"skip"
    # The first byte of each seed picks the harness's cap (64 B << (byte % 18)).
    write("zstd", {
        "sample": b"\x05" + z.compress(sample),
        "two_frames": b"\x05" + z.compress(sample) + z.compress(sample * 3),
        "undeclared": b"\x07" + streamed,
        "then_skippable": b"\x05" + z.compress(sample) + skippable + z.compress(sample),
        "bomb_64mib": b"\x11" + bomb,
        "cut_short": b"\x05" + z.compress(sample * 50)[:-3],
        "checksum": b"\x05" + zstandard.ZstdCompressor(write_checksum=True).compress(sample * 20),
    })


if __name__ == "__main__":
    main()
