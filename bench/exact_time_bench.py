#!/usr/bin/env python3
"""What exact nanosecond time costs (issue 36): `rvc check` before and after, side by side in one run,
on the 30 Timescales files (10 families x bounds 10/100/1000), in discrete time (the files as
generated) and in dense time (the same files with an epoch stamp 25 ms apart on every line, written as
decimal seconds: the path that now reads times exactly).

  python3 bench/exact_time_bench.py --before OLD_RVC [--after build/release/rvc] [--steps 1000000] [--reps 5]

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
import re
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


def instructions(cmd):
    err = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null"] + cmd,
                         capture_output=True, text=True).stderr
    return int(re.search(r"Collected : (\d+)", err).group(1))


def head(src, dst, n):
    with open(src) as f, open(dst, "w") as out:
        for k, line in enumerate(f):
            if k == n:
                break
            out.write(line)


def per_line(binary, flags, path, spec, a, b, tmp):
    """Instructions per line (callgrind: the same count however busy the machine), from the first a and
    b lines of `path`: the difference cancels start-up."""
    counts = []
    for n in (a, b):
        head(path, tmp, n)
        counts.append(instructions([binary, "check", *flags, tmp, "--spec", spec]))
    return (counts[1] - counts[0]) / (b - a)


def run_time(cmd):
    t0 = time.perf_counter()
    p = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    dt = time.perf_counter() - t0
    if p.returncode not in (0, 1):
        raise SystemExit(f"{' '.join(cmd)}: exit {p.returncode}: {p.stderr[-400:]}")
    return dt


def dense_copy(src, dst):
    """Each line's "time" (its step) replaced by an epoch stamp 25 ms after the previous line's, as
    decimal seconds (the files carry {"time": step, ...} first)."""
    with open(src) as f, open(dst, "w") as out:
        for k, line in enumerate(f):
            line = line.strip()
            m = re.match(r'\{"time":\s*\d+\s*,?', line)
            body = line[m.end():] if m else line[1:]
            sep = "" if body.startswith("}") else ","
            out.write('{"time":' + sec_text(EPOCH_NS + k * STEP_NS) + sep + body + "\n")


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
    ap.add_argument("--steps", type=int, default=1_000_000)
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--no-docs", action="store_true")
    ap.add_argument("--instr-lines", default="20000,60000",
                    help="A,B: instructions per line from the first A and B lines (callgrind); 0: no count")
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
            row = {"file": name, "mode": mode, "before_s": b, "after_s": a, "ratio": a / b}
            if args.instr_lines != "0":
                n1, n2 = (int(x) for x in args.instr_lines.split(","))
                tmp = os.path.join(data, "head.jsonl")
                ib = per_line(args.before, flags, rest[0], rest[2], n1, n2, tmp)
                ia = per_line(args.after, flags, rest[0], rest[2], n1, n2, tmp)
                row.update({"before_instr": ib, "after_instr": ia, "instr_ratio": ia / ib})
            rows.append(row)
        print(f"[{n}/30] {name}: discrete {rows[-2]['ratio']:.3f}x, dense {rows[-1]['ratio']:.3f}x "
              f"({time.time() - started:.0f} s)", file=sys.stderr, flush=True)
    with open(os.path.join(outdir, "exact-time.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)

    def geo(mode, key="ratio"):
        r = [x[key] for x in rows if x["mode"] == mode]
        return math.exp(sum(math.log(v) for v in r) / len(r)), min(r), max(r)

    load = os.getloadavg()[0]
    md = [f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores; load average {load:.1f} "
          f"at the end; {args.steps:,} lines per file, best of {args.reps}, before and after interleaved. Run time "
          f"{(time.time() - started) / 60:.1f} min. Command: `python3 bench/exact_time_bench.py --before OLD_RVC "
          f"--steps {args.steps}`.", "",
          "| mode | wall clock, after / before (geometric mean) | min | max |"
          + (" instructions per line, after / before (geometric mean) | min | max |" if "instr_ratio" in rows[0] else ""),
          "|---|---|---|---|" + ("---|---|---|" if "instr_ratio" in rows[0] else "")]
    for mode in ("discrete", "dense"):
        g, lo, hi = geo(mode)
        line = f"| {mode} | {g:.3f}x | {lo:.3f}x | {hi:.3f}x |"
        if "instr_ratio" in rows[0]:
            gi, loi, hii = geo(mode, "instr_ratio")
            line += f" {gi:.3f}x | {loi:.3f}x | {hii:.3f}x |"
        md.append(line)
    if "instr_ratio" in rows[0]:
        md += ["", f"Instructions per line are counted by callgrind between the first {args.instr_lines.replace(',', ' and ')} "
               "lines (start-up cancels); wall clock is best of --reps on the whole file and moves by +-30 % between "
               "runs on this virtual machine, so the instruction ratio is the figure to read."]
    instr = "instr_ratio" in rows[0]
    md += ["", "| file | discrete before (s) | after (s) | ratio |" + (" instr/line before | after | ratio |" if instr else "")
           + " dense before (s) | after (s) | ratio |" + (" instr/line before | after | ratio |" if instr else ""),
           "|---|---|---|---|" + ("---|---|---|" if instr else "") + "---|---|---|" + ("---|---|---|" if instr else "")]
    for k in range(0, len(rows), 2):
        line = f"| {rows[k]['file']} |"
        for r in (rows[k], rows[k + 1]):
            line += f" {r['before_s']:.3f} | {r['after_s']:.3f} | {r['ratio']:.3f} |"
            if instr:
                line += f" {r['before_instr']:.0f} | {r['after_instr']:.0f} | {r['instr_ratio']:.3f} |"
        md.append(line)
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
