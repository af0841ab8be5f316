#!/usr/bin/env python3
"""Does a monitor's cost depend on its time bounds? Counted, not timed.

  python3 bench/bounds_instructions.py [--events 50000]

For each Timescales family, counts the instructions (callgrind: the same count on a busy machine,
unlike wall clock) of `rvc check` with the family's formula at bound 10 and at bound 1000, each on the
first --events lines of its own trace (bench/results/timescales/, made by bench/timescales_bench.py or
here), and the parse floor's on the same lines. Prints and writes bench/results/bounds_instructions.md.
A benchmark, not a test: it asserts nothing.
"""
import argparse
import os
import re
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FAMILIES = ["AbsentAQ", "AbsentBQR", "AbsentBR", "AlwaysAQ", "AlwaysBQR",
            "AlwaysBR", "RecurBQR", "RecurGLB", "RespondBQR", "RespondGLB"]


def instructions(cmd):
    err = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null"] + cmd,
                         capture_output=True, text=True).stderr
    return int(re.search(r"Collected : (\d+)", err).group(1))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--events", type=int, default=50_000)
    ap.add_argument("--build", default=os.path.join(ROOT, "build", "release"))
    args = ap.parse_args()
    rvc = os.path.join(args.build, "rvc")
    floor = os.path.join(args.build, "rvc_parse_floor")
    data = os.path.join(ROOT, "bench", "results", "timescales")
    os.makedirs(data, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for family in FAMILIES:
            per_bound = {}
            for bound in (10, 1000):
                full = os.path.join(data, f"{family}{bound}.jsonl")
                if not os.path.exists(full):
                    subprocess.run([rvc, "timescales", family, "--ubound", str(bound), "--duration", "1000000",
                                    "--seed", "1", "-o", full], check=True)
                part = os.path.join(tmp, f"{family}{bound}.jsonl")
                with open(full) as src, open(part, "w") as dst:
                    for _, line in zip(range(args.events), src):
                        dst.write(line)
                spec = subprocess.run([rvc, "timescales", family, "--ubound", str(bound), "--formula"],
                                      capture_output=True, text=True, check=True).stdout.strip()
                per_bound[bound] = (instructions([rvc, "check", "--spec", spec, part, "-o", "/dev/null"]),
                                    instructions([floor, part]))
            (c10, f10), (c1000, f1000) = per_bound[10], per_bound[1000]
            rows.append((family, c10 / args.events, c1000 / args.events, c1000 / c10, f10 / args.events))
            print(f"{family:12s} bound 10: {rows[-1][1]:7.0f} instr/event  bound 1000: {rows[-1][2]:7.0f}  "
                  f"ratio {rows[-1][3]:.3f}  (floor {rows[-1][4]:.0f})", flush=True)
    lines = [f"`rvc check`, instructions per event on the first {args.events:,} events (callgrind; start-up "
             "included, the same for both bounds).", "",
             "| family | bound 10 | bound 1000 | bound 1000 / bound 10 | parse floor |", "|---|---:|---:|---:|---:|"]
    lines += [f"| {f} | {a:.0f} | {b:.0f} | {r:.3f} | {fl:.0f} |" for f, a, b, r, fl in rows]
    lines.append("")
    lines.append(f"max bound 1000 / bound 10: **{max(r[3] for r in rows):.3f}**")
    md = "\n".join(lines) + "\n"
    with open(os.path.join(ROOT, "bench", "results", "bounds_instructions.md"), "w") as f:
        f.write(md)
    print(md)


if __name__ == "__main__":
    main()
