#!/usr/bin/env python3
"""What exact nanosecond time costs (issue 36): `rvc check` before and after, side by side in one run,
on the 30 Timescales files (10 families x bounds 10/100/1000), in discrete time (the files as
generated) and in dense time (the same files with an epoch stamp 25 ms apart on every line, written as
decimal seconds: the path that now reads times exactly).

  python3 bench/exact_time_bench.py --before OLD_RVC [--after build/release/rvc] [--steps 200000] [--reps 3]

OLD_RVC is an rvc built from a commit before exact time (e.g. fdbae9f: `git worktree add /tmp/old
fdbae9f && cd /tmp/old && bash scripts/build.sh`). The two binaries run interleaved on each file (best
of --reps, wall clock), so machine load hits both alike. Writes bench/results/exact-time.md and .csv and,
unless --no-docs, the table into docs/performance.md between the exact-time markers.

This is a benchmark, not a test: it asserts nothing; it reports ratios.
"""
import argparse
import csv
import math
import os
import platform
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FAMILIES = ["AbsentAQ", "AbsentBQR", "AbsentBR", "AlwaysAQ", "AlwaysBQR",
            "AlwaysBR", "RecurBQR", "RecurGLB", "RespondBQR", "RespondGLB"]
BOUNDS = [10, 100, 1000]
EPOCH_NS = 1746721937599626818
STEP_NS = 25_000_000


def sec_text(ns):
    whole, frac = divmod(ns, 10**9)
    return str(whole) if frac == 0 else f"{whole}.{frac:09d}".rstrip("0")


def run_time(cmd):
    t0 = time.perf_counter()
    p = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    dt = time.perf_counter() - t0
    if p.returncode not in (0, 1):
        raise SystemExit(f"{' '.join(cmd)}: exit {p.returncode}: {p.stderr[-400:]}")
    return dt


def dense_copy(src, dst):
    """Each line with "time" first: an epoch stamp 25 ms after the previous one, as decimal seconds."""
    with open(src) as f, open(dst, "w") as out:
        for k, line in enumerate(f):
            body = line.strip()[1:]
            sep = "" if body == "}" else ", "
            out.write('{"time": ' + sec_text(EPOCH_NS + k * STEP_NS) + sep + body + "\n")


def dense_spec(spec, step_s=STEP_NS / 1e9):
    """The discrete formula's step bounds as seconds of the 25 ms grid ([a:b] steps -> [a*0.025:b*0.025])."""
    out, i = [], 0
    while i < len(spec):
        if spec[i] == "[":
            j = spec.index("]", i)
            lo, hi = spec[i + 1:j].split(":")
            f = lambda x: "" if x == "" else sec_text(int(x) * STEP_NS)  # noqa: E731
            out.append(f"[{f(lo)}:{f(hi)}]")
            i = j + 1
        else:
            out.append(spec[i])
            i += 1
    return "".join(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--before", required=True, help="rvc built before exact time")
    ap.add_argument("--after", default=os.path.join(ROOT, "build", "release", "rvc"))
    ap.add_argument("--steps", type=int, default=200_000)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--no-docs", action="store_true")
    args = ap.parse_args()
    outdir = os.path.join(ROOT, "bench", "results")
    data = os.path.join(outdir, f"exact-time-{args.steps}")
    os.makedirs(data, exist_ok=True)
    rows = []
    started = time.time()
    for n, (family, bound) in enumerate([(f, b) for f in FAMILIES for b in BOUNDS], 1):
        name = f"{family}-{bound}"
        disc = os.path.join(data, name + ".jsonl")
        dense = os.path.join(data, name + "-dense.jsonl")
        if not os.path.exists(disc):
            subprocess.run([args.after, "timescales", family, "--ubound", str(bound), "--duration", str(args.steps),
                            "-o", disc], check=True)
        if not os.path.exists(dense):
            dense_copy(disc, dense)
        spec = subprocess.run([args.after, "timescales", family, "--ubound", str(bound), "--formula"],
                              capture_output=True, text=True, check=True).stdout.strip()
        cases = {"discrete": ([disc, "--spec", spec], []), "dense": ([dense, "--spec", dense_spec(spec)], ["--dense"])}
        for mode, (rest, flags) in cases.items():
            before_cmd = [args.before, "check", *flags, *rest]
            after_cmd = [args.after, "check", *flags, *rest]
            b, a = math.inf, math.inf
            for _ in range(args.reps):  # interleaved: load hits both alike
                b = min(b, run_time(before_cmd))
                a = min(a, run_time(after_cmd))
            rows.append({"file": name, "mode": mode, "before_s": b, "after_s": a, "ratio": a / b})
        print(f"[{n}/30] {name}: discrete {rows[-2]['ratio']:.3f}x, dense {rows[-1]['ratio']:.3f}x "
              f"({time.time() - started:.0f} s)", file=sys.stderr, flush=True)
    with open(os.path.join(outdir, "exact-time.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)

    def geo(mode):
        r = [x["ratio"] for x in rows if x["mode"] == mode]
        return math.exp(sum(math.log(v) for v in r) / len(r)), min(r), max(r)

    load = os.getloadavg()[0]
    md = [f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores; load average {load:.1f} "
          f"at the end; {args.steps:,} lines per file, best of {args.reps}, before and after interleaved. Run time "
          f"{(time.time() - started) / 60:.1f} min. Command: `python3 bench/exact_time_bench.py --before OLD_RVC "
          f"--steps {args.steps}`.", "",
          "| mode | after / before, geometric mean | min | max |", "|---|---|---|---|"]
    for mode in ("discrete", "dense"):
        g, lo, hi = geo(mode)
        md.append(f"| {mode} | {g:.3f}x | {lo:.3f}x | {hi:.3f}x |")
    md += ["", "| file | discrete before (s) | after (s) | ratio | dense before (s) | after (s) | ratio |",
           "|---|---|---|---|---|---|---|"]
    for k in range(0, len(rows), 2):
        d, e = rows[k], rows[k + 1]
        md.append(f"| {d['file']} | {d['before_s']:.3f} | {d['after_s']:.3f} | {d['ratio']:.3f} | "
                  f"{e['before_s']:.3f} | {e['after_s']:.3f} | {e['ratio']:.3f} |")
    text = "\n".join(md) + "\n"
    with open(os.path.join(outdir, "exact-time.md"), "w") as f:
        f.write(text)
    print(text)
    if not args.no_docs:
        path = os.path.join(ROOT, "docs", "performance.md")
        doc = open(path).read()
        begin, end = "<!-- exact-time:begin -->", "<!-- exact-time:end -->"
        if begin in doc:
            doc = doc[:doc.index(begin) + len(begin)] + "\n" + text + doc[doc.index(end):]
            open(path, "w").write(doc)


if __name__ == "__main__":
    main()
