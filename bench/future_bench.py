#!/usr/bin/env python3
"""Bounded future (issue 29): rvc against RTAMT (PyPI `rtamt`, discrete online monitor after
pastify) on the same formulas, events per second side by side, for horizons 10, 1,000 and 100,000.

Formulas (horizon H):
  response   {x > 2} -> eventually[0:H] {y > 0.5}
  bounded    always[0:H] ({x < 4})
  mixed      (once[0:H] {x > 2}) and eventually[H:H] {y > 0.5}
rvc: `rvc check` on a JSON-lines trace of --events lines (Boolean verdicts, changes only, to /dev/null;
the time includes reading, decoding and the end-of-stream settling of the last H steps). RTAMT: its
Python online monitor, update() per event with robustness, on fewer events (its bounded operators scan
their window at each step, O(H) per event), sized to run about --rtamt-seconds each. Also checks the
delay: rvc's first verdict for time 0 is known at H.

Writes bench/results/future_bench.json and the table into docs/performance.md between the
<!-- future:begin/end --> markers. Run once, at rest (~2 min):
  python3 bench/future_bench.py [--rvc build/release/rvc] [--events 1000000]
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
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from timescales_bench import machine, write_marked  # noqa: E402

HORIZONS = [10, 1_000, 100_000]
FORMULAS = {
    "response": ("{{x > 2}} -> eventually[0:{h}] {{y > 0.5}}", "once[0:0](x > 2) implies eventually[0:{h}](y > 0.5)"),  # once[0:0]: see test_future_rtamt.py
    "bounded": ("always[0:{h}] ({{x < 4}})", "always[0:{h}](x < 4)"),
    "mixed": ("(once[0:{h}] {{x > 2}}) and eventually[{h}:{h}] {{y > 0.5}}",
              "(once[0:{h}](x > 2)) and eventually[{h}:{h}](y > 0.5)"),
}


def write_trace(path, n, seed=1):
    rng = random.Random(seed)
    with open(path, "w") as f:
        for _ in range(n):
            f.write('{"x":%d,"y":%.2f}\n' % (rng.randint(0, 4), rng.choice([-1, 0.25, 1, 2])))


def rvc_rate(rvc, spec, trace, n):
    t0 = time.perf_counter()
    proc = subprocess.run([rvc, "check", "--spec", spec, trace], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    dt = time.perf_counter() - t0
    assert proc.returncode in (0, 1), proc.stderr
    return n / dt


def first_known_at(rvc, spec, trace_small):
    out = subprocess.run([rvc, "check", "--all", "--spec", spec, trace_small], capture_output=True, text=True).stdout
    first = json.loads(out.splitlines()[0])
    return first["time"], first.get("known_at")


def rtamt_rate(text, budget_s, rng_seed=1):
    import rtamt
    spec = rtamt.StlDiscreteTimeOnlineSpecification()
    for v in ("x", "y", "out"):
        spec.declare_var(v, "float")
    spec.spec = "out = " + text
    spec.parse()
    spec.pastify()
    rng = random.Random(rng_seed)
    n = 0
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < budget_s:
        for _ in range(50):
            spec.update(n, [("x", float(rng.randint(0, 4))), ("y", rng.choice([-1, 0.25, 1, 2]))])
            n += 1
    return n / (time.perf_counter() - t0), n


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rvc", default=os.path.join(ROOT, "build", "release", "rvc"))
    ap.add_argument("--events", type=int, default=1_000_000)
    ap.add_argument("--rtamt-seconds", type=float, default=4.0)
    ap.add_argument("--no-docs", action="store_true")
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        trace = os.path.join(tmp, "trace.jsonl")
        write_trace(trace, args.events)
        for name, (ours, theirs) in FORMULAS.items():
            for h in HORIZONS:
                small = os.path.join(tmp, "small.jsonl")
                write_trace(small, h + 5, seed=2)
                t, known = first_known_at(args.rvc, ours.format(h=h), small)
                assert (t, known) == (0, h), (name, h, t, known)
                ours_rate = max(rvc_rate(args.rvc, ours.format(h=h), trace, args.events) for _ in range(2))
                theirs_rate, theirs_n = rtamt_rate(theirs.format(h=h), args.rtamt_seconds)
                rows.append({"formula": name, "horizon": h, "rvc_events_per_s": round(ours_rate),
                             "rtamt_events_per_s": round(theirs_rate), "rtamt_events": theirs_n,
                             "ratio": round(ours_rate / theirs_rate, 1), "delay_checked": True})
                print(json.dumps(rows[-1]), flush=True)
    result = {"machine": machine(), "events": args.events, "time": time.strftime("%Y-%m-%d %H:%M"), "rows": rows}
    os.makedirs(os.path.join(ROOT, "bench", "results"), exist_ok=True)
    with open(os.path.join(ROOT, "bench", "results", "future_bench.json"), "w") as f:
        json.dump(result, f, indent=1)
    md = (f"Bounded future, `bench/future_bench.py` ({result['time']}, {result['machine']}; rvc: "
          f"`rvc check` on {args.events:,} JSON lines, end settling included; RTAMT 0.4.10: Python online "
          f"monitor, `update()` per event, robustness):\n\n"
          "| formula | horizon | rvc events/s | RTAMT events/s | rvc / RTAMT |\n|---|---|---|---|---|\n")
    for r in rows:
        md += (f"| {r['formula']} | {r['horizon']:,} | {r['rvc_events_per_s']:,} | {r['rtamt_events_per_s']:,} | "
               f"{r['ratio']}x |\n")
    print(md)
    if not args.no_docs:
        write_marked(os.path.join(ROOT, "docs", "performance.md"), "future", md)


if __name__ == "__main__":
    main()
