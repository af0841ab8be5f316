"""Writes the seed bags of fuzz_mcap (tests/fuzz/corpus/mcap): small MCAP files from the `mcap`
package (each chunk compression, unchunked, JSON and CDR with a ros2msg schema, several channels),
plus the MCAP bags of ROS 2's own rosbag2 tests if they are at hand (../shared/data/ros2-bags).

    python3 tests/fuzz/make_mcap_seeds.py
"""
import glob
import os
import shutil
import struct
import zlib

import zstandard

from mcap.writer import CompressionType, Writer

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "corpus", "mcap")
SCHEMA = ("test_msgs/Inner inner\nuint8 level\nfloat64[] values\n"
          "================================================================================\n"
          "MSG: test_msgs/Inner\nstring label\n")


def sample(i):
    label = ("x" * (i % 5)).encode() + b"\0"
    s = b"\x00\x01\x00\x00" + struct.pack("<I", len(label)) + label + bytes([i % 7])
    s += bytes(-len(s) % 4) + struct.pack("<I", i % 3)
    s += bytes(-(len(s) - 4) % 8) + b"".join(struct.pack("<d", k * 0.5) for k in range(i % 3))
    return s


def write(name, compression="none", chunked=True, chunk_size=200, cdr=True, channels=1, data_crcs=False):
    with open(os.path.join(OUT, name), "wb") as f:
        w = Writer(f, chunk_size=chunk_size, use_chunking=chunked, enable_data_crcs=data_crcs,
                   compression=getattr(CompressionType, compression.upper()))
        w.start(profile="ros2" if cdr else "", library="rvc fuzz seeds")
        sid = w.register_schema(name="test_msgs/msg/Outer", encoding="ros2msg", data=SCHEMA.encode()) if cdr else 0
        chans = [w.register_channel(topic=f"/t{k}", message_encoding="cdr" if cdr else "json", schema_id=sid)
                 for k in range(channels)]
        for i in range(12):
            data = sample(i) if cdr else b'{"p": %s, "x": %d}' % (b"true" if i % 3 else b"false", i)
            w.add_message(channel_id=chans[i % channels], log_time=i * 1000, publish_time=i * 1000, sequence=i,
                          data=data)
        w.finish()


def record(op, body):
    return bytes([op]) + struct.pack("<Q", len(body)) + body


def string(b):
    return struct.pack("<I", len(b)) + b


def hostile():
    """Bags that once crashed or misled rvc (tests/cli/test_mcap_hostile.py has each as a test)."""
    header = record(0x01, string(b"ros2") + string(b"rvc fuzz seeds"))
    end = record(0x0F, struct.pack("<I", 0)) + b"\x89MCAP0\r\n"
    # A zstd chunk whose message record claims 64 GiB: the mcap crate allocated it and aborted.
    inner = bytes([0x05]) + struct.pack("<Q", 64 << 30) + struct.pack("<HIQQ", 1, 0, 0, 0) + b"x" * 16
    comp = zstandard.ZstdCompressor().compress(inner)
    chunk = record(0x06, struct.pack("<QQQI", 0, 0, len(inner), zlib.crc32(inner)) + string(b"zstd")
                   + struct.pack("<Q", len(comp)) + comp)
    with open(os.path.join(OUT, "found_inner_record_claims_64gib.mcap"), "wb") as f:
        f.write(b"\x89MCAP0\r\n" + header + chunk + end)
    # A channel, a message on it, a message on channel 9 (never defined), an uncompressed chunk
    # whose CRC does not match its records.
    ch = record(0x04, struct.pack("<HH", 1, 0) + string(b"/s") + string(b"json") + struct.pack("<I", 0))
    msg = lambda c, d: record(0x05, struct.pack("<HIQQ", c, 0, 1, 1) + d)
    inner = msg(1, b'{"p": true}')
    bad = record(0x06, struct.pack("<QQQI", 0, 0, len(inner), zlib.crc32(inner) ^ 1) + string(b"")
                 + struct.pack("<Q", len(inner)) + inner)
    with open(os.path.join(OUT, "found_undefined_channel_bad_crc.mcap"), "wb") as f:
        f.write(b"\x89MCAP0\r\n" + header + ch + msg(1, b'{"p": false}') + msg(9, b"{}") + bad + end)


if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    for c in ("none", "zstd", "lz4"):
        write(f"cdr_{c}.mcap", compression=c)
    write("cdr_unchunked_datacrc.mcap", chunked=False, data_crcs=True)
    write("json_zstd_3channels.mcap", compression="zstd", cdr=False, channels=3)
    hostile()
    root = os.path.join(HERE, "..", "..", "..", "shared", "data", "ros2-bags")
    for bag in sorted(glob.glob(os.path.join(root, "*_mcap", "*.mcap"))):
        if os.path.getsize(bag) < 64 << 10:
            shutil.copy(bag, os.path.join(OUT, "rosbag2_" + os.path.basename(bag)))
    print("\n".join(sorted(os.listdir(OUT))))
