#!/usr/bin/env python3
"""Writes N small ROS 2 bags with rosbags (PyPI), for rvc-batch's tests, benchmark and demo.

    tools/rvc-batch/example_bags.py DIR [--count 200] [--messages 20]

Bag i (bag-0000 ...): one topic /speed (std_msgs/msg/Float64), M messages 0.1 s apart; even i an
MCAP bag folder, odd i a SQLite (.db3) one. Speeds stay in 10..16, except in every fifth bag
(i % 5 == 0), where message i % M is 45: `historically({data < 30})` is violated there, first at
step i % M, and holds everywhere else. SPEC below; expected() gives the hand-computed answer.
"""
import argparse
import os

SPEC = "historically({data < 30})"
TOPIC = "/speed"


def speeds(i, messages):
    v = [10.0 + (j % 7) for j in range(messages)]
    if i % 5 == 0:
        v[i % messages] = 45.0
    return v


def expected(i, messages):
    """(violated, step of the first false verdict or None) for bag i."""
    return (True, i % messages) if i % 5 == 0 else (False, None)


def write_bags(folder, count, messages=20):
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore
    ts = get_typestore(Stores.ROS2_HUMBLE)
    Float64 = ts.types["std_msgs/msg/Float64"]
    os.makedirs(folder, exist_ok=True)
    paths = []
    for i in range(count):
        path = os.path.join(folder, "bag-%04d" % i)
        plugin = StoragePlugin.MCAP if i % 2 == 0 else StoragePlugin.SQLITE3
        with Writer(path, version=8, storage_plugin=plugin) as w:
            c = w.add_connection(TOPIC, Float64.__msgtype__, typestore=ts)
            for j, v in enumerate(speeds(i, messages)):
                w.write(c, 1_000_000_000 + j * 100_000_000, ts.serialize_cdr(Float64(data=v), Float64.__msgtype__))
        paths.append(path)
    return paths


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir")
    ap.add_argument("--count", type=int, default=200)
    ap.add_argument("--messages", type=int, default=20)
    a = ap.parse_args()
    print("\n".join(write_bags(a.dir, a.count, a.messages)))
