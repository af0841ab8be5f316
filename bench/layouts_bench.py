#!/usr/bin/env python3
"""The layout fast path (docs/performance.md, "Layouts"): what it buys, and what it costs when it cannot help.

  python3 bench/layouts_bench.py [--build build/release] [--steps 1000000] [--reps 5]

Three versions of one Timescales trace (RespondBQR, bound 100, the heaviest formula), the same messages
each time:
  - as generated: every line has the same keys in the same order (what one serializer prints);
  - shuffled keys: each line's keys in a random order (120 orders of 5 keys), so a line rarely repeats the
    layout of one of the 4 kept, and nearly every line goes to simdjson after a failed match: the worst case;
  - two shapes: every other line has the keys in reverse order (a stream with two message shapes).
For each: `rvc check` with layouts, `rvc check --no-layouts` (simdjson reads every line), and the simdjson
floor (`rvc_parse_floor`), timed side by side (best of --reps, wall clock), plus instructions counted by
callgrind on the first 200,000 lines (the same on a busy machine). The verdicts of both rvc runs are
compared on every file. Writes bench/results/layouts.md and the table into docs/performance.md between the
layouts markers. A benchmark, not a test: it asserts nothing.
"""
import argparse
import json
import os
import random
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from timescales_bench import best_of, machine, write_marked  # noqa: E402


def instructions(cmd):
    out = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null"] + cmd,
                         capture_output=True, text=True).stderr
    m = re.search(r"Collected : (\d+)", out)
    return int(m.group(1)) if m else float("nan")


def rewrite(src, dst, order):
    """Writes src's lines to dst with each object's keys in order(i, keys)."""
    with open(src) as f, open(dst, "w") as out:
        for i, line in enumerate(f):
            obj = json.loads(line)
            keys = order(i, list(obj))
            out.write("{" + ",".join(f'"{k}":{json.dumps(obj[k])}' for k in keys) + "}\n")


def head(src, dst, lines):
    with open(src) as f, open(dst, "w") as out:
        for i, line in enumerate(f):
            if i == lines:
                break
            out.write(line)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build", "release"))
    ap.add_argument("--steps", type=int, default=1_000_000)
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--count-lines", type=int, default=200_000, help="lines counted by callgrind")
    ap.add_argument("--no-docs", action="store_true")
    args = ap.parse_args()
    rvc = os.path.join(args.build, "rvc")
    floor = os.path.join(args.build, "rvc_parse_floor")
    rng = random.Random(1)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        base = os.path.join(tmp, "as_generated.jsonl")
        props = os.path.join(tmp, "props.yaml")
        subprocess.run([rvc, "timescales", "RespondBQR", "--ubound", "100", "--duration", str(args.steps), "-o", base,
                        "--properties-out", props], check=True)
        variants = [("as generated", base)]
        shuffled = os.path.join(tmp, "shuffled.jsonl")
        rewrite(base, shuffled, lambda i, keys: rng.sample(keys, len(keys)))
        variants.append(("shuffled keys (worst case)", shuffled))
        two = os.path.join(tmp, "two_shapes.jsonl")
        rewrite(base, two, lambda i, keys: keys if i % 2 == 0 else keys[::-1])
        variants.append(("two shapes, alternating", two))
        def check(path, *extra):
            return [rvc, "check", "--properties", props, path, *extra]

        for name, path in variants:
            # Every verdict (--all) of both paths, compared whole.
            a = subprocess.run(check(path, "--all"), capture_output=True, text=True).stdout
            b = subprocess.run(check(path, "--all", "--no-layouts"), capture_output=True, text=True).stdout
            same = a == b and a.count("\n") == args.steps
            part = os.path.join(tmp, "part.jsonl")
            head(path, part, args.count_lines)
            counts = [instructions(check(part, "-o", "/dev/null")),
                      instructions(check(part, "-o", "/dev/null", "--no-layouts")), instructions([floor, part])]
            times = [best_of(check(path, "-o", "/dev/null"), args.reps)[0],
                     best_of(check(path, "-o", "/dev/null", "--no-layouts"), args.reps)[0],
                     best_of([floor, path], args.reps)[0]]
            rows.append((name, times, counts, same))
            print(f"{name:28s} rvc {times[0]*1e3:7.1f} ms  --no-layouts {times[1]*1e3:7.1f} ms  "
                  f"floor {times[2]*1e3:7.1f} ms   instructions/line {counts[0]/args.count_lines:6.0f} "
                  f"{counts[1]/args.count_lines:6.0f} {counts[2]/args.count_lines:6.0f}  verdicts equal: {same}",
                  flush=True)
    md = (f"Machine: {machine()}. RespondBQR bound 100, {args.steps:,} events per file, best of {args.reps} runs, "
          f"wall clock; instructions per line: callgrind on the first {args.count_lines:,} lines "
          f"(start-up included).\n\n"
          "| trace | rvc check ms | --no-layouts ms | simdjson floor ms | rvc / floor | rvc / --no-layouts | "
          "instructions per line: rvc | --no-layouts | floor | verdicts equal |\n"
          "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|\n")
    for name, t, c, same in rows:
        n = args.count_lines
        md += (f"| {name} | {t[0]*1e3:.1f} | {t[1]*1e3:.1f} | {t[2]*1e3:.1f} | {t[0]/t[2]:.2f} | {t[0]/t[1]:.2f} | "
               f"{c[0]/n:,.0f} | {c[1]/n:,.0f} | {c[2]/n:,.0f} | {'yes' if same else 'NO'} |\n")
    os.makedirs(os.path.join(ROOT, "bench", "results"), exist_ok=True)
    with open(os.path.join(ROOT, "bench", "results", "layouts.md"), "w") as f:
        f.write(md)
    if not args.no_docs:
        write_marked(os.path.join(ROOT, "docs", "performance.md"), "layouts", md)
    print(md)


if __name__ == "__main__":
    main()
