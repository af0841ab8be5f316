#!/usr/bin/env python3
"""Timescales "large" suite: rvc check vs parse-only floors and Reelay 25's
C++ monitors, side by side in one run.

  python3 bench/timescales_bench.py [--steps 1000000] [--reps 3] [--no-reelay-cpp]

Generates the 30 files (10 families x bounds 10/100/1000, 1M steps each,
seed 1) under bench/results/timescales/, times each program on each file
(best of --reps runs, wall clock; peak RSS from /usr/bin/time), and writes
bench/results/timescales.csv, bench/results/timescales.md, a PNG plot, and
the table into docs/performance.md between the timescales markers.

Reelay C++: bench/reelay_cpp/fetch.py fetches the reelay==25.0.0 sdist from
PyPI (into the git-ignored bench/results/reelay-src/) and builds our
bench/reelay_cpp/reelay_check.cpp against its headers: Reelay's
discrete_timed_monitor fed by a simdjson reader, a stand-in for Reelay's
ryjson (not in the sdist); --reelay-input picks what it feeds the monitor. Before timing a file, its first --check-lines
lines go through both rvc check and reelay_check; a file whose verdict
changes differ is reported and left out of the Reelay C++ column. If the
fetch or build fails, the run says so and goes on without that column.

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


def reelay_cpp_binary():
    """Fetches Reelay's sdist and builds reelay_check; returns (path, None) or (None, why it failed)."""
    sys.path.insert(0, os.path.join(ROOT, "bench", "reelay_cpp"))
    try:
        import fetch
        return fetch.build(), None
    except Exception as e:  # fetch.FetchError, or anything unexpected: the bench goes on without it
        return None, f"{type(e).__name__}: {e}"
    finally:
        sys.path.pop(0)


def verdict_changes(cmd):
    """Runs cmd (prints JSON verdict lines, maybe a summary line); returns ([(time, value)], exit code,
    stderr)."""
    proc = subprocess.run(cmd, capture_output=True, text=True)
    out = []
    for line in proc.stdout.splitlines():
        d = json.loads(line)
        if "value" in d:
            out.append((d["time"], d["value"]))
    return out, proc.returncode, proc.stderr.strip()


def body_of(spec):
    """The operand of an outermost `historically(...)`, else None."""
    head = "historically("
    if not spec.startswith(head):
        return None
    depth = 0
    for i in range(len(head) - 1, len(spec)):
        depth += {"(": 1, ")": -1}.get(spec[i], 0)
        if depth == 0:
            return spec[len(head):i] if i == len(spec) - 1 else None
    return None


def write_prefixes(path, lines, scratch, seed):
    """Writes the first `lines` lines of path, and a copy where one in 100 lines has one Boolean field
    flipped (seeded): the Timescales traces satisfy their formulas, so on the file itself a verdict
    hardly changes; the flips make the formulas' bodies change often."""
    import random
    rng = random.Random(seed)
    plain, flipped = os.path.join(scratch, "prefix.jsonl"), os.path.join(scratch, "prefix-flipped.jsonl")
    with open(path) as src, open(plain, "w") as p, open(flipped, "w") as f:
        for i, line in enumerate(src):
            if i >= lines:
                break
            p.write(line)
            if rng.random() < 0.01:
                obj = json.loads(line)
                keys = [k for k, v in obj.items() if isinstance(v, bool)]
                if keys:
                    k = rng.choice(keys)
                    obj[k] = not obj[k]
                    line = json.dumps(obj, separators=(",", ":")) + "\n"
            f.write(line)
    return [plain, flipped]


def same_verdicts(rvc, reelay_check, spec, path, lines, scratch):
    """Compares rvc check's verdict changes with reelay_check's (a command: binary and options) on the
    first `lines` lines of path, as is and with a few fields flipped, for the formula and for the body of
    its outermost `historically`.
    Returns (None when all agree, else a one-line description of the first difference; the number of
    verdict changes compared)."""
    compared = 0
    for trace in write_prefixes(path, lines, scratch, os.path.basename(path)):
        for formula in filter(None, [spec, body_of(spec)]):
            ours, rc_ours, err_ours = verdict_changes([rvc, "check", "--spec", formula, trace])
            theirs, rc_theirs, err_theirs = verdict_changes(reelay_check + ["--print", "--spec", formula, trace])
            if rc_ours not in (0, 1):
                return (f"could not compare: rvc check exited {rc_ours} ({err_ours[-200:] or 'no message'})",
                        compared)
            if rc_theirs != 0:
                return (f"could not compare: reelay_check exited {rc_theirs} "
                        f"({err_theirs[-200:] or 'no message'})", compared)
            if ours != theirs:
                where = next((f"change #{i}: rvc {a}, Reelay C++ {b}"
                              for i, (a, b) in enumerate(zip(ours, theirs)) if a != b),
                             f"the first {min(len(ours), len(theirs))} changes agree")
                return (f"{os.path.basename(trace)}, {formula}: {where} ({len(ours)} vs {len(theirs)} changes)",
                        compared)
            compared += len(ours)
    return None, compared


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
    ap.add_argument("--reelay-events", type=int, default=0,
                    help="events per file for a Reelay Python binding sample (default 0: skip; the Reelay C++ "
                         "column replaces it)")
    ap.add_argument("--no-reelay-cpp", action="store_true", help="leave out the Reelay C++ column")
    ap.add_argument("--reelay-input", choices=["dom", "json"], default="dom",
                    help="what the Reelay C++ harness feeds its monitor: each line's simdjson DOM element "
                         "(default; as Reelay's ryjson does) or the line converted to reelay::json (nlohmann)")
    ap.add_argument("--check-lines", type=int, default=20_000,
                    help="lines per file compared between rvc and Reelay C++ before timing (0: no check)")
    ap.add_argument("--build", default=os.path.join(ROOT, "build", "release"))
    ap.add_argument("--no-docs", action="store_true",
                    help="do not update docs/performance.md nor docs/img (the plot goes to bench/results/)")
    args = ap.parse_args()

    rvc = os.path.join(args.build, "rvc")
    floor = os.path.join(args.build, "rvc_parse_floor")
    outdir = os.path.join(ROOT, "bench", "results")
    # Files of another length than the default go elsewhere, so that a short trial run does not leave
    # files that a full run would take for its own.
    data = os.path.join(outdir, "timescales" if args.steps == 1_000_000 else f"timescales-{args.steps}")
    os.makedirs(data, exist_ok=True)

    reelay_check, why = (None, "--no-reelay-cpp") if args.no_reelay_cpp else reelay_cpp_binary()
    if reelay_check:
        print(f"Reelay C++: {reelay_check} --input {args.reelay_input}", flush=True)
    elif not args.no_reelay_cpp:
        print(f"Reelay C++ column LEFT OUT: fetching/building Reelay 25 failed: {why}", flush=True)
    scratch = os.path.join(outdir, "reelay_cpp")
    os.makedirs(scratch, exist_ok=True)
    mismatches = []
    changes_compared = 0

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
        t_vfloor, _, _ = best_of([floor, "--validate", path], args.reps)
        r_rate = reelay_rate(path, spec, args.reelay_events) if args.reelay_events else float("nan")
        t_cpp = rss_cpp = float("nan")
        cpp_note = ""
        if reelay_check:
            harness = [reelay_check, "--input", args.reelay_input]
            diff, n_changes = (same_verdicts(rvc, harness, spec, path, args.check_lines, scratch)
                               if args.check_lines else (None, 0))
            changes_compared += n_changes
            if diff:
                mismatches.append((name, diff))
                cpp_note = "  Reelay C++ EXCLUDED"
                what = "check failed" if diff.startswith("could not compare") else "verdict changes differ"
                print(f"MISMATCH {name}: first {args.check_lines:,} lines, {what}: {diff}; "
                      f"left out of the Reelay C++ column", flush=True)
            else:
                t_cpp, rss_cpp, rc_cpp = best_of(harness + ["--spec", spec, path], args.reps)
                if rc_cpp != 0:
                    t_cpp = rss_cpp = float("nan")
                    mismatches.append((name, f"reelay_check exited {rc_cpp}"))
                    cpp_note = f"  Reelay C++ FAILED (exit {rc_cpp})"
                else:
                    cpp_note = f"  Reelay C++ {t_cpp*1e3:7.1f} ms ({t_cpp/t_rvc:4.2f}x)"
        rows.append(dict(property=name, family=family, bound=bound, rvc_ms=t_rvc * 1e3, rvc_rss_mb=rss_rvc,
                         decode_ms=t_dec * 1e3, floor_ms=t_floor * 1e3, floor_rss_mb=rss_floor,
                         vfloor_ms=t_vfloor * 1e3,
                         rvc_mev_s=args.steps / t_rvc / 1e6, reelay_cpp_ms=t_cpp * 1e3, reelay_cpp_rss_mb=rss_cpp,
                         reelay_py_mev_s=r_rate / 1e6, verdict_rc=rc))
        py_note = f"  reelay-py {r_rate/1e6:6.3f} Mev/s" if args.reelay_events else ""
        print(f"[{n:2d}/{total}] {name:14s} rvc {t_rvc*1e3:7.1f} ms  decode-only {t_dec*1e3:7.1f} ms  "
              f"simdjson floor {t_floor*1e3:7.1f} ms (validating {t_vfloor*1e3:7.1f})  rss {rss_rvc:5.1f} MB{cpp_note}{py_note}", flush=True)

    with open(os.path.join(outdir, "timescales.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)

    if reelay_check and mismatches:
        print(f"Reelay C++: {len(mismatches)} file(s) left out: " + "; ".join(f"{n}: {d}" for n, d in mismatches),
              flush=True)
    md = render(rows, args, reelay_cpp=bool(reelay_check), reelay_cpp_why=why, mismatches=mismatches,
                changes_compared=changes_compared)
    with open(os.path.join(outdir, "timescales.md"), "w") as f:
        f.write(md)
    plot(rows, os.path.join(outdir, "timescales.png") if args.no_docs
         else os.path.join(ROOT, "docs", "img", "timescales.png"))
    if not args.no_docs:
        update_docs(md)
    print(md)


def render(rows, args, reelay_cpp=False, reelay_cpp_why=None, mismatches=(), changes_compared=0):
    def geo(xs):
        p = 1.0
        for x in xs:
            p *= x
        return p ** (1 / len(xs))

    def have(x):
        return x == x  # not NaN

    over_floor = [r["rvc_ms"] / r["floor_ms"] for r in rows]
    over_vfloor = [r["rvc_ms"] / r["vfloor_ms"] for r in rows]
    over_decode = [r["rvc_ms"] / r["decode_ms"] for r in rows]
    by = {(r["family"], r["bound"]): r for r in rows}
    b1000_vs_10 = [by[(f, 1000)]["rvc_ms"] / by[(f, 10)]["rvc_ms"] for f in FAMILIES]
    py = bool(args.reelay_events)
    out = []
    note = ""
    if reelay_cpp:
        note = (" Reelay C++: Reelay 25's discrete_timed_monitor fed "
                + ("each line's simdjson DOM element" if args.reelay_input == "dom"
                   else "each line converted to reelay::json") + " by bench/reelay_cpp/reelay_check.")
    out.append(f"Machine: {machine()}. {args.steps:,} events per file, best of {args.reps} runs, wall clock.{note}\n")
    head = ("| property | rvc check ms | M events/s | peak RSS MB | rvc decode-only ms | simdjson floor ms "
            "| validating floor ms | rvc / floor | rvc / validating floor | rvc / decode-only |")
    rule = "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    if reelay_cpp:
        head += " Reelay C++ ms | Reelay C++ RSS MB | rvc speed-up over Reelay C++ |"
        rule += "---:|---:|---:|"
    if py:
        head += " Reelay py M ev/s | rvc / Reelay-py |"
        rule += "---:|---:|"
    out += [head, rule]
    for r in rows:
        line = (f"| {r['property']} | {r['rvc_ms']:.1f} | {r['rvc_mev_s']:.2f} | {r['rvc_rss_mb']:.1f} | "
                f"{r['decode_ms']:.1f} | {r['floor_ms']:.1f} | {r['vfloor_ms']:.1f} | {r['rvc_ms']/r['floor_ms']:.2f} | "
                f"{r['rvc_ms']/r['vfloor_ms']:.2f} | {r['rvc_ms']/r['decode_ms']:.2f} |")
        if reelay_cpp:
            if have(r["reelay_cpp_ms"]):
                line += (f" {r['reelay_cpp_ms']:.1f} | {r['reelay_cpp_rss_mb']:.1f} | "
                         f"{r['reelay_cpp_ms']/r['rvc_ms']:.2f}x |")
            else:
                line += " excluded | | |"
        if py:
            line += f" {r['reelay_py_mev_s']:.3f} | {r['rvc_mev_s']/r['reelay_py_mev_s']:.0f}x |"
        out.append(line)
    out.append("")
    if reelay_cpp:
        speedups = [r["reelay_cpp_ms"] / r["rvc_ms"] for r in rows if have(r["reelay_cpp_ms"])]
        if speedups:
            g = geo(speedups)
            out.append(f"- rvc speed-up over Reelay C++ (Reelay C++ ms / rvc ms, geometric mean over "
                       f"{len(speedups)} files): **{g:.2f}x** (min {min(speedups):.2f}x, "
                       f"max {max(speedups):.2f}x); issue 15's target >= 3x: {'met' if g >= 3 else 'not met'}")
            rss = max(r["reelay_cpp_rss_mb"] for r in rows if have(r["reelay_cpp_rss_mb"]))
            out.append(f"- Reelay C++ peak RSS: max **{rss:.1f} MB**")
        if args.check_lines:
            checked = len(rows) - len(mismatches)
            out.append(f"- before timing, rvc's and Reelay C++'s verdict changes compared on the first "
                       f"{args.check_lines:,} lines of each file (as is, and with 1% of lines given a flipped "
                       f"field), for the formula and for the body of its outer `historically` "
                       f"({changes_compared:,} changes): "
                       f"equal on {checked} of {len(rows)} files"
                       + ("" if not mismatches else "; left out: " + ", ".join(n for n, _ in mismatches)))
    elif reelay_cpp_why and reelay_cpp_why != "--no-reelay-cpp":
        out.append(f"- Reelay C++: not measured in this run (fetch/build failed: {reelay_cpp_why.splitlines()[0]})")
    out.append(f"- rvc / simdjson floor (geometric mean): **{geo(over_floor):.2f}** (min {min(over_floor):.2f}, "
               f"max {max(over_floor):.2f})")
    out.append(f"- rvc / validating floor (every scalar read by type, as a reader that rejects malformed values "
               f"must; geometric mean): **{geo(over_vfloor):.2f}** (min {min(over_vfloor):.2f}, "
               f"max {max(over_vfloor):.2f})")
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
    cpp = [r["reelay_cpp_ms"] for r in rows]
    with_cpp = any(v == v for v in cpp)
    fig, ax = plt.subplots(figsize=(14, 4.5))
    w = 0.21 if with_cpp else 0.28
    off = -1.5 * w if with_cpp else -w
    ax.bar([i + off for i in x], [r["floor_ms"] for r in rows], w, label="simdjson floor (parse, no monitor)")
    ax.bar([i + off + w for i in x], [r["decode_ms"] for r in rows], w, label="rvc decode-only (--parse-only)")
    ax.bar([i + off + 2 * w for i in x], [r["rvc_ms"] for r in rows], w, label="rvc check")
    if with_cpp:
        ax.bar([i + off + 3 * w for i in x], [v if v == v else 0 for v in cpp], w,
               label="Reelay 25 C++ (discrete_timed_monitor + simdjson)")
    ax.set_xticks(list(x))
    ax.set_xticklabels(names, rotation=70, fontsize=8)
    ax.set_ylabel("ms per 1M-event file")
    ax.set_title("Timescales large suite: rvc check vs parse-only floors"
                 + (" and Reelay C++" if with_cpp else ""))
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
