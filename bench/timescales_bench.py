#!/usr/bin/env python3
"""Timescales "large" suite: rvc check vs parse-only floors (and Reelay's
Python binding on a sample), side by side in one run.

  python3 bench/timescales_bench.py [--steps 1000000] [--reps 3]

Generates the 30 files (10 families x bounds 10/100/1000, 1M steps each,
seed 1) under bench/results/timescales/, times each program on each file
(best of --reps runs, wall clock; peak RSS from /usr/bin/time), and writes
bench/results/timescales.csv, bench/results/timescales.md, a PNG plot, and
the table into docs/performance.md between the timescales markers.

This is a benchmark, not a test: it asserts nothing; it reports ratios.
"""
import argparse
import csv
import json
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


def timed(cmd):
    """Runs cmd; returns (seconds, peak RSS in MB, exit code)."""
    t0 = time.perf_counter()
    proc = subprocess.run(["/usr/bin/time", "-f", "%M"] + cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                          text=True)
    elapsed = time.perf_counter() - t0
    rss_kb = int(proc.stderr.strip().splitlines()[-1])
    return elapsed, rss_kb / 1024, proc.returncode


def best_of(cmd, reps):
    runs = [timed(cmd) for _ in range(reps)]
    return min(r[0] for r in runs), max(r[1] for r in runs), runs[0][2]


def reelay_rate(path, spec, events):
    """Events/s of Reelay 25's Python binding (json.loads + update per line)."""
    import reelay
    m = reelay.discrete_timed_monitor(pattern=spec, condense=True)
    loads = json.loads
    with open(path) as f:
        lines = [next(f) for _ in range(events)]
    t0 = time.perf_counter()
    for line in lines:
        m.update(loads(line))
    return events / (time.perf_counter() - t0)


def machine():
    cpu = "?"
    with open("/proc/cpuinfo") as f:
        for line in f:
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    return f"{cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=1_000_000)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--reelay-events", type=int, default=100_000,
                    help="events per file for the Reelay Python sample (0: skip)")
    ap.add_argument("--build", default=os.path.join(ROOT, "build", "release"))
    ap.add_argument("--no-docs", action="store_true", help="do not update docs/performance.md")
    args = ap.parse_args()

    rvc = os.path.join(args.build, "rvc")
    floor = os.path.join(args.build, "rvc_parse_floor")
    outdir = os.path.join(ROOT, "bench", "results")
    data = os.path.join(outdir, "timescales")
    os.makedirs(data, exist_ok=True)

    rows = []
    total = len(FAMILIES) * len(BOUNDS)
    for n, (family, bound) in enumerate(((f, b) for f in FAMILIES for b in BOUNDS), 1):
        name = f"{family}{bound}"
        path = os.path.join(data, f"{name}.jsonl")
        if not os.path.exists(path) or os.path.getsize(path) == 0:
            subprocess.run([rvc, "timescales", family, "--ubound", str(bound), "--duration", str(args.steps),
                            "--seed", "1", "-o", path], check=True)
        spec = subprocess.run([rvc, "timescales", family, "--ubound", str(bound), "--formula"],
                              capture_output=True, text=True, check=True).stdout.strip()
        t_rvc, rss_rvc, rc = best_of([rvc, "check", "--spec", spec, path], args.reps)
        t_dec, rss_dec, _ = best_of([rvc, "check", "--parse-only", "--spec", spec, path], args.reps)
        t_floor, rss_floor, _ = best_of([floor, path], args.reps)
        r_rate = reelay_rate(path, spec, args.reelay_events) if args.reelay_events else float("nan")
        rows.append(dict(property=name, family=family, bound=bound, rvc_ms=t_rvc * 1e3, rvc_rss_mb=rss_rvc,
                         decode_ms=t_dec * 1e3, floor_ms=t_floor * 1e3, floor_rss_mb=rss_floor,
                         rvc_mev_s=args.steps / t_rvc / 1e6, reelay_py_mev_s=r_rate / 1e6, verdict_rc=rc))
        print(f"[{n:2d}/{total}] {name:14s} rvc {t_rvc*1e3:7.1f} ms  decode-only {t_dec*1e3:7.1f} ms  "
              f"simdjson floor {t_floor*1e3:7.1f} ms  rss {rss_rvc:5.1f} MB  reelay-py {r_rate/1e6:6.3f} Mev/s",
              flush=True)

    with open(os.path.join(outdir, "timescales.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)

    md = render(rows, args)
    with open(os.path.join(outdir, "timescales.md"), "w") as f:
        f.write(md)
    plot(rows, os.path.join(ROOT, "docs", "img", "timescales.png"))
    if not args.no_docs:
        update_docs(md)
    print(md)


def render(rows, args):
    def geo(xs):
        p = 1.0
        for x in xs:
            p *= x
        return p ** (1 / len(xs))
    over_floor = [r["rvc_ms"] / r["floor_ms"] for r in rows]
    over_decode = [r["rvc_ms"] / r["decode_ms"] for r in rows]
    by = {(r["family"], r["bound"]): r for r in rows}
    b1000_vs_10 = [by[(f, 1000)]["rvc_ms"] / by[(f, 10)]["rvc_ms"] for f in FAMILIES]
    out = []
    out.append(f"Machine: {machine()}. {args.steps:,} events per file, best of {args.reps} runs, wall clock.\n")
    out.append("| property | rvc check ms | M events/s | peak RSS MB | rvc decode-only ms | simdjson floor ms "
               "| rvc / floor | rvc / decode-only | Reelay py M ev/s | rvc / Reelay-py |")
    out.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        out.append(f"| {r['property']} | {r['rvc_ms']:.1f} | {r['rvc_mev_s']:.2f} | {r['rvc_rss_mb']:.1f} | "
                   f"{r['decode_ms']:.1f} | {r['floor_ms']:.1f} | {r['rvc_ms']/r['floor_ms']:.2f} | "
                   f"{r['rvc_ms']/r['decode_ms']:.2f} | {r['reelay_py_mev_s']:.3f} | "
                   f"{r['rvc_mev_s']/r['reelay_py_mev_s']:.0f}x |")
    out.append("")
    out.append(f"- rvc / simdjson floor (geometric mean): **{geo(over_floor):.2f}** (min {min(over_floor):.2f}, "
               f"max {max(over_floor):.2f})")
    out.append(f"- rvc / rvc decode-only (monitoring cost alone, geometric mean): **{geo(over_decode):.2f}** "
               f"(min {min(over_decode):.2f}, max {max(over_decode):.2f})")
    out.append(f"- bound 1000 / bound 10, per family: **{', '.join(f'{x:.2f}' for x in b1000_vs_10)}** "
               f"(max {max(b1000_vs_10):.2f})")
    out.append(f"- peak RSS: max **{max(r['rvc_rss_mb'] for r in rows):.1f} MB**")
    out.append(f"- ms per file: min {min(r['rvc_ms'] for r in rows):.0f}, max {max(r['rvc_ms'] for r in rows):.0f}")
    return "\n".join(out) + "\n"


def plot(rows, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plot", file=sys.stderr)
        return
    os.makedirs(os.path.dirname(path), exist_ok=True)
    names = [r["property"] for r in rows]
    x = range(len(rows))
    fig, ax = plt.subplots(figsize=(14, 4.5))
    w = 0.28
    ax.bar([i - w for i in x], [r["floor_ms"] for r in rows], w, label="simdjson floor (parse, no monitor)")
    ax.bar(list(x), [r["decode_ms"] for r in rows], w, label="rvc decode-only (--parse-only)")
    ax.bar([i + w for i in x], [r["rvc_ms"] for r in rows], w, label="rvc check")
    ax.set_xticks(list(x))
    ax.set_xticklabels(names, rotation=70, fontsize=8)
    ax.set_ylabel("ms per 1M-event file")
    ax.set_title("Timescales large suite: rvc check vs parse-only floors")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def write_marked(path, tag, md):
    """Puts `md` between the <!-- TAG:begin --> and <!-- TAG:end --> markers of a doc (appended with
    the markers if it has none): the benchmarks' tables live in docs written by hand around them."""
    text = open(path).read() if os.path.exists(path) else ""
    block = f"<!-- {tag}:begin -->\n" + md + f"<!-- {tag}:end -->"
    if f"<!-- {tag}:begin -->" in text:
        text = re.sub(rf"<!-- {tag}:begin -->.*?<!-- {tag}:end -->", lambda _: block, text, flags=re.S)
    else:
        text += "\n" + block + "\n"
    with open(path, "w") as f:
        f.write(text)


def update_docs(md):
    write_marked(os.path.join(ROOT, "docs", "performance.md"), "timescales", md)


if __name__ == "__main__":
    main()
