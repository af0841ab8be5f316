#!/usr/bin/env python3
"""Many properties over one stream (the paper's conclusion: a container should carry tens to
hundreds of properties). One trace, 1 / 10 / 100 / 1000 properties, side by side in one run:

  shared   every property reads the same 3 atoms ({p}, {q}, {r}) with its own time bounds
           (Timescales AlwaysBQR shapes, bounds 10..1000): one parse and one atom evaluation per
           message serve them all, so the cost per message should grow with the monitors only;
  distinct each property also tests a numeric field against its own threshold ({v > k}), so
           atoms grow with the properties.

Reports messages/s, ns per message and per property-message, and peak RSS (GNU time), best of
--reps; writes bench/results/many_properties.json and the table into docs/performance.md.
A benchmark, not a test: nothing is asserted.
"""
import argparse
import json
import os
import random
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from timescales_bench import write_marked  # noqa: E402


def properties(n, distinct):
    lines = ["properties:"]
    for i in range(n):
        bound = 10 + (i * 37) % 991
        spec = f"historically(({{r}} && !{{q}} && once{{q}}) -> ({{p}} since[{bound // 3}:{bound}] {{q}}))"
        if distinct:
            spec = f"({spec}) || {{v > {i}}}"
        lines.append(f"  - name: p{i}\n    spec: \"{spec}\"")
    return "\n".join(lines) + "\n"


def run(rvc, props, trace):
    t0 = time.perf_counter()
    p = subprocess.run(["/usr/bin/time", "-f", "RSS %M", rvc, "check", "--properties", props, trace, "-o", "/dev/null"],
                       capture_output=True, text=True)
    elapsed = time.perf_counter() - t0
    if p.returncode not in (0, 1):
        raise RuntimeError(p.stderr[-400:])
    rss = int([l for l in p.stderr.splitlines() if l.startswith("RSS ")][-1].split()[1])
    return elapsed, rss


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rvc", default=os.path.join(ROOT, "build", "release", "rvc"))
    ap.add_argument("--messages", type=int, default=200_000)
    ap.add_argument("--counts", default="1,10,100,1000")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--no-docs", action="store_true")
    a = ap.parse_args()
    counts = [int(c) for c in a.counts.split(",")]
    with tempfile.TemporaryDirectory(prefix="rvc-many-") as tmp:
        trace = os.path.join(tmp, "trace.jsonl")
        rng = random.Random(7)
        with open(trace, "w") as f:
            for t in range(a.messages):
                f.write(json.dumps({"time": t, "p": rng.random() < 0.9, "q": rng.random() < 0.05,
                                    "r": rng.random() < 0.02, "v": rng.randint(0, 2000)}) + "\n")
        empty = os.path.join(tmp, "none.yaml")
        results = []
        for kind in ("shared", "distinct"):
            for n in counts:
                props = os.path.join(tmp, f"{kind}-{n}.yaml")
                with open(props, "w") as f:
                    f.write(properties(n, kind == "distinct"))
                best, rss = None, 0
                for rep in range(a.reps):
                    t, r = run(a.rvc, props, trace)
                    if best is None or t < best:
                        best, rss = t, r
                ns = best / a.messages * 1e9
                row = {"atoms": kind, "properties": n, "seconds": best, "msgs_per_s": a.messages / best,
                       "ns_per_msg": ns, "ns_per_property_msg": ns / n, "rss_kib": rss}
                results.append(row)
                print(f"  {kind:8s} {n:5d} properties: {a.messages / best / 1e6:6.2f} M msg/s, {ns:8.0f} ns/msg, "
                      f"{ns / n:7.1f} ns per property-message, RSS {rss / 1024:.1f} MiB", flush=True)
    md = ["| atoms | properties | messages/s | ns / message | ns / (property × message) | peak RSS |",
          "|---|---:|---:|---:|---:|---:|"]
    for r in results:
        md.append(f"| {r['atoms']} | {r['properties']:,} | {r['msgs_per_s'] / 1e6:.2f} M | {r['ns_per_msg']:.0f} | "
                  f"{r['ns_per_property_msg']:.1f} | {r['rss_kib'] / 1024:.1f} MiB |")
    text = "\n".join(md) + (f"\n\n{a.messages:,} messages (p, q, r Booleans and an integer v), `rvc check -o /dev/null`, "
                            f"best of {a.reps}, whole process (start, parse of the properties file, exit). "
                            "Reproduce: `python3 bench/many_properties_bench.py`.\n")
    print(text)
    os.makedirs(os.path.join(ROOT, "bench", "results"), exist_ok=True)
    with open(os.path.join(ROOT, "bench", "results", "many_properties.json"), "w") as f:
        json.dump(results, f, indent=1)
    if not a.no_docs:
        write_marked(os.path.join(ROOT, "docs", "performance.md"), "many-properties", text)


if __name__ == "__main__":
    main()
