#!/usr/bin/env python3
"""What one `rvc` run costs before it reads anything: start-up, side by side with the floor.

  python3 bench/startup_bench.py [--build build/release] [--runs 30]

For `rvc --version`, `rvc check` on a one-line file and the parse-only floor
(`rvc_parse_floor`, which links only simdjson) on the same file, it reports:
  - instructions, counted by callgrind (the same on a busy machine),
  - CPU time per run (user + system, mean of --runs runs, from getrusage), and
  - the shared libraries the dynamic loader mapped (LD_DEBUG=files).
Writes bench/results/startup.md and prints it. A benchmark, not a test: it asserts nothing.
"""
import argparse
import os
import re
import resource
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def instructions(cmd):
    out = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null"] + cmd,
                         capture_output=True, text=True).stderr
    m = re.search(r"Collected : (\d+)", out)
    return int(m.group(1)) if m else float("nan")


def cpu_ms(cmd, runs):
    """Mean CPU time (user + system) of the children, in ms."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    for _ in range(runs):
        subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    used = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return used / runs * 1e3


def libraries(cmd):
    err = subprocess.run(cmd, capture_output=True, text=True, env={"LD_DEBUG": "files", "PATH": "/usr/bin:/bin"}).stderr
    return sorted({m.group(1) for m in re.finditer(r"file=(\S+)\s+\[0\];\s+needed by", err)})


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build", "release"))
    ap.add_argument("--runs", type=int, default=30)
    args = ap.parse_args()
    rvc = os.path.join(args.build, "rvc")
    floor = os.path.join(args.build, "rvc_parse_floor")
    with tempfile.TemporaryDirectory() as tmp:
        one = os.path.join(tmp, "one.jsonl")
        with open(one, "w") as f:
            f.write('{"time":0,"p":true}\n')
        programs = [
            ("rvc --version", [rvc, "--version"]),
            ("rvc check (one line)", [rvc, "check", "--spec", "{p}", one, "-o", "/dev/null"]),
            ("simdjson floor (one line)", [floor, one]),
        ]
        rows = []
        for name, cmd in programs:
            rows.append((name, instructions(cmd), cpu_ms(cmd, args.runs), libraries(cmd)))
            print(f"{name:28s} {rows[-1][1] / 1e6:7.2f} M instructions  {rows[-1][2]:6.2f} ms CPU  "
                  f"{len(rows[-1][3])} libraries", flush=True)
    floor_row = rows[-1]
    lines = ["| program | instructions | CPU ms per run | vs floor (CPU) | shared libraries mapped |",
             "|---|---:|---:|---:|---:|"]
    for name, ins, ms, libs in rows:
        lines.append(f"| {name} | {ins / 1e6:.2f} M | {ms:.2f} | {ms / floor_row[2]:.1f}x | {len(libs)} |")
    lines.append("")
    lines.append(f"Libraries `rvc check` maps at start: {', '.join(rows[1][3])}.")
    md = "\n".join(lines) + "\n"
    os.makedirs(os.path.join(ROOT, "bench", "results"), exist_ok=True)
    with open(os.path.join(ROOT, "bench", "results", "startup.md"), "w") as f:
        f.write(md)
    print(md)


if __name__ == "__main__":
    sys.exit(main())
