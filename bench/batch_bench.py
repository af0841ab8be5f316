#!/usr/bin/env python3
"""rvc-batch throughput: bags per second with 1 and 2 Dask workers, against plain `rvc check`.

Side by side in one run, on --count bags written by tools/rvc-batch/example_bags.py (rosbags; half
MCAP, half SQLite; --messages each), each best of --reps:
  plain         a shell-less loop: `rvc check BAG --spec S --topic /speed` per bag, one after another
  plain+store   the same with `-o sqlite:DB` (what rvc-batch asks of every bag)
  batch N       tools/rvc-batch/rvc_batch.py --workers N --store sqlite:DB, N = 1, 2: the whole
                command (Python and Dask start-up included) and the tool's own time (its JSON line:
                from the cluster up to the last bag)
Overhead per bag = (batch 1 - plain+store) / count: what fanning out through Dask costs a bag.
Prints a markdown table, writes bench/results/batch.json and the table into docs/performance.md.
This is a benchmark, not a test: it asserts nothing about time. A few minutes on 2 cores.
"""
import argparse
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from timescales_bench import write_marked  # noqa: E402

TOOL = os.path.join(ROOT, "tools", "rvc-batch", "rvc_batch.py")
_spec = importlib.util.spec_from_file_location("example_bags", os.path.join(ROOT, "tools", "rvc-batch",
                                                                           "example_bags.py"))
eb = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(eb)


def plain(rvc, bags, store=None):
    t0 = time.perf_counter()
    for b in bags:
        cmd = [rvc, "check", b, "--spec", eb.SPEC, "--topic", eb.TOPIC] + (["-o", "sqlite:" + store] if store else [])
        p = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if p.returncode not in (0, 1):
            raise RuntimeError("%s: exit %d: %s" % (b, p.returncode, p.stderr[-300:]))
    return time.perf_counter() - t0


def batch(rvc, folder, store, workers):
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, TOOL, folder, "--rvc", rvc, "--store", "sqlite:" + store, "--workers",
                        str(workers), "--no-progress", "--", "--spec", eb.SPEC, "--topic", eb.TOPIC],
                       capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if p.returncode not in (0, 1):
        raise RuntimeError("rvc-batch exit %d: %s" % (p.returncode, p.stderr[-500:]))
    return wall, json.loads(p.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rvc", default=os.environ.get("RVC_BIN", os.path.join(ROOT, "build", "release", "rvc")))
    ap.add_argument("--count", type=int, default=200)
    ap.add_argument("--messages", type=int, default=20)
    ap.add_argument("--reps", type=int, default=2)
    ap.add_argument("--no-docs", action="store_true", help="do not write the table into docs/performance.md")
    a = ap.parse_args()
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="rvc-batch-bench-") as tmp:
        folder = os.path.join(tmp, "bags")
        bags = eb.write_bags(folder, a.count, a.messages)
        res = {"count": a.count, "messages": a.messages, "cores": os.cpu_count(), "load_before": round(load, 2)}
        n = 0

        def store():
            nonlocal n
            n += 1
            return os.path.join(tmp, "s%d.db" % n)
        res["plain"] = min(plain(a.rvc, bags) for _ in range(a.reps))
        res["plain_store"] = min(plain(a.rvc, bags, store()) for _ in range(a.reps))
        for w in (1, 2):
            runs = [batch(a.rvc, folder, store(), w) for _ in range(a.reps)]
            wall, line = min(runs, key=lambda r: r[0])
            res["batch%d" % w] = {"wall": wall, "tool_seconds": line["seconds"], "bags_per_s": a.count / wall,
                                  "tool_bags_per_s": line["bags_per_s"]}
        res["load_after"] = round(os.getloadavg()[0], 2)
    b1, b2 = res["batch1"], res["batch2"]
    rows = [("plain `rvc check`, one after another", res["plain"], None),
            ("plain `rvc check -o sqlite:`", res["plain_store"], None),
            ("rvc-batch, 1 worker", b1["wall"], b1["tool_seconds"]),
            ("rvc-batch, 2 workers", b2["wall"], b2["tool_seconds"])]
    md = ["| %d bags x %d messages | wall s | bags/s | bags/s without start-up |" % (a.count, a.messages),
          "|---|---|---|---|"]
    for name, wall, tool in rows:
        no_start = "%.1f" % (a.count / tool) if tool else "—"
        md.append("| %s | %.2f | %.1f | %s |" % (name, wall, a.count / wall, no_start))
    md.append("")
    md.append("Speed-up 2 workers / 1 worker: %.2fx (whole command), %.2fx (without start-up). "
              "Overhead per bag of rvc-batch (1 worker) over plain `rvc check -o sqlite:`: %+.1f ms "
              "(whole command), %+.1f ms (without start-up). Load average %.1f before, %.1f after; %d cores."
              % (b1["wall"] / b2["wall"], b1["tool_seconds"] / b2["tool_seconds"],
                 1000 * (b1["wall"] - res["plain_store"]) / a.count,
                 1000 * (b1["tool_seconds"] - res["plain_store"]) / a.count,
                 res["load_before"], res["load_after"], res["cores"]))
    text = "\n".join(md) + "\n"
    print(text)
    os.makedirs(os.path.join(ROOT, "bench", "results"), exist_ok=True)
    with open(os.path.join(ROOT, "bench", "results", "batch.json"), "w") as f:
        json.dump(res, f, indent=1)
    if not a.no_docs:
        write_marked(os.path.join(ROOT, "docs", "performance.md"), "batch", text)


if __name__ == "__main__":
    main()
