#!/usr/bin/env python3
"""Many properties over one stream (the paper's conclusion: a container should carry tens to
hundreds of properties). One trace, 1 / 10 / 100 / 1,000 / 10,000 properties, side by side in one
run, each with rvc's default evaluation and with the hidden `--plain-eval` (every field test and
every operator at every message, the path before issue 27):

  shared    every property reads the same 3 atoms ({p}, {q}, {r}) with its own time bounds
            (Timescales AlwaysBQR shapes, bounds 10..1000): one parse and one atom evaluation per
            message serve them all;
  distinct  each property is also `|| {v > k}` with its own k (k spread over v's range), so
            atoms grow with the properties. The AlwaysBQR part falls false for good at the
            trace's first {r} that lacks its {q}, as these traces soon have: from then on each
            property is its threshold alone;
  live      `((r && !q && once q) -> (p since[a:b] q)) || {v > k}`: no outer historically, so
            nothing falls for good and every property's since is stepped while its window is in
            flight (the case change-driven stepping helps least).

v is a random walk (+1, 0 or -1 per message over 0..2000), as a measured quantity moves; with
--v-jumps it is drawn afresh each message, so about a third of all thresholds flip (and as many
verdicts are written) per message: output then grows with the properties, whatever the evaluator.

Cost is CPU time (user + sys of the rvc process, from wait4), not wall time: the machine is shared.
Per message: (CPU of the whole trace - CPU of a run on its first message) / (messages - 1), so
start-up (parsing 10,000 properties) is reported apart. Best of --reps.
Writes bench/results/many_properties.{json,md,png} and the table into docs/performance.md.
A benchmark, not a test: nothing is asserted.
"""
import argparse
import json
import os
import random
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from timescales_bench import write_marked  # noqa: E402

V_MAX = 2000


def properties(n, kind):
    lines = ["properties:"]
    for i in range(n):
        bound = 10 + (i * 37) % 991
        body = f"({{r}} && !{{q}} && once{{q}}) -> ({{p}} since[{bound // 3}:{bound}] {{q}})"
        k = round(i * V_MAX / n, 3)  # thresholds spread over v's range
        spec = {"shared": f"historically({body})",
                "distinct": f"(historically({body})) || {{v > {k}}}",
                "live": f"({body}) || {{v > {k}}}"}[kind]
        lines.append(f"  - name: p{i}\n    spec: \"{spec}\"")
    return "\n".join(lines) + "\n"


def cpu_run(args):
    """CPU seconds (user + sys) and peak RSS (KiB) of one rvc run."""
    p = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(p.pid, 0)
    err = p.stderr.read().decode(errors="replace")
    p.stderr.close()
    code = os.waitstatus_to_exitcode(status)
    if code not in (0, 1):
        raise RuntimeError(f"{' '.join(args)}: exit {code}: {err[-400:]}")
    return usage.ru_utime + usage.ru_stime, usage.ru_maxrss


def best(args, reps):
    runs = [cpu_run(args) for _ in range(reps)]
    return min(r[0] for r in runs), max(r[1] for r in runs)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rvc", default=os.path.join(ROOT, "build", "release", "rvc"))
    ap.add_argument("--messages", type=int, default=200_000)
    ap.add_argument("--counts", default="1,10,100,1000,10000")
    ap.add_argument("--kinds", default="shared,distinct,live")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--plain-budget", type=float, default=4e8,
                    help="--plain-eval runs get at most this many property-messages (fewer messages at 10,000)")
    ap.add_argument("--v-jumps", action="store_true", help="v drawn afresh each message (a third of thresholds flip)")
    ap.add_argument("--no-docs", action="store_true")
    a = ap.parse_args()
    counts = [int(c) for c in a.counts.split(",")]
    load = os.getloadavg()
    results = []
    with tempfile.TemporaryDirectory(prefix="rvc-many-") as tmp:
        trace = os.path.join(tmp, "trace.jsonl")
        first = os.path.join(tmp, "first.jsonl")
        rng = random.Random(7)
        v = V_MAX // 2
        lines = []
        for t in range(a.messages):
            v = rng.randint(0, V_MAX) if a.v_jumps else min(V_MAX, max(0, v + rng.choice((-1, 0, 1))))
            lines.append(json.dumps({"time": t, "p": rng.random() < 0.9, "q": rng.random() < 0.05,
                                     "r": rng.random() < 0.02, "v": v}) + "\n")
        with open(trace, "w") as f:
            f.writelines(lines)
        with open(first, "w") as f:
            f.write(lines[0])
        for kind in a.kinds.split(","):
            for n in counts:
                props = os.path.join(tmp, f"{kind}-{n}.yaml")
                with open(props, "w") as f:
                    f.write(properties(n, kind))
                row = {"kind": kind, "properties": n}
                for mode, extra in (("default", []), ("plain", ["--plain-eval"])):
                    msgs = a.messages if mode == "default" else max(2, min(a.messages, int(a.plain_budget / n)))
                    src = trace
                    if msgs < a.messages:
                        src = os.path.join(tmp, f"trace-{msgs}.jsonl")
                        with open(src, "w") as f:
                            f.writelines(lines[:msgs])
                    base = ["check", "--properties", props, "-o", "/dev/null"] + extra
                    cpu, rss = best([a.rvc] + base + [src], a.reps)
                    start, _ = best([a.rvc] + base + [first], a.reps)
                    ns = max(cpu - start, 0) / (msgs - 1) * 1e9
                    row[mode] = {"messages": msgs, "cpu_s": cpu, "startup_s": start, "ns_per_msg": ns,
                                 "msgs_per_s": 1e9 / ns if ns else float("inf"), "ns_per_property_msg": ns / n,
                                 "rss_kib": rss}
                results.append(row)
                d, p = row["default"], row["plain"]
                print(f"  {kind:8s} {n:6d}: {d['msgs_per_s'] / 1e6:7.2f} M msg/s {d['ns_per_msg']:9.0f} ns/msg "
                      f"{d['ns_per_property_msg']:8.2f} ns/prop-msg | plain {p['msgs_per_s'] / 1e6:7.3f} M msg/s "
                      f"{p['ns_per_property_msg']:8.2f} ns/prop-msg | speed-up {p['ns_per_msg'] / d['ns_per_msg']:.1f}x "
                      f"| start-up {d['startup_s'] * 1e3:.0f} ms, RSS {d['rss_kib'] / 1024:.1f} MiB", flush=True)
    load_after = os.getloadavg()
    md = ["| atoms | properties | messages/s | ns / message | ns / (property × message) | `--plain-eval` messages/s "
          "| `--plain-eval` ns / (property × message) | speed-up | start-up CPU | peak RSS |",
          "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in results:
        d, p = r["default"], r["plain"]
        md.append(f"| {r['kind']} | {r['properties']:,} | {d['msgs_per_s'] / 1e6:.2f} M | {d['ns_per_msg']:.0f} | "
                  f"{d['ns_per_property_msg']:.2f} | {p['msgs_per_s'] / 1e6:.3f} M | {p['ns_per_property_msg']:.1f} | "
                  f"{p['ns_per_msg'] / d['ns_per_msg']:.1f}x | {d['startup_s'] * 1e3:.0f} ms | "
                  f"{d['rss_kib'] / 1024:.1f} MiB |")
    trace_text = "v drawn afresh each message" if a.v_jumps else "v a random walk over 0..2000"
    text = "\n".join(md) + (
        f"\n\n{a.messages:,} messages (p, q, r Booleans; {trace_text}), `rvc check -o /dev/null`, CPU time (user + sys) "
        f"per message with the start-up (a run on the first message) taken off, best of {a.reps}; `--plain-eval` on "
        f"at most {a.plain_budget:,.0f} property-messages. Load average {load[0]:.1f} before, {load_after[0]:.1f} after "
        "(2 cores, shared). Reproduce: `python3 bench/many_properties_bench.py"
        + "".join(" " + x for x in sys.argv[1:] if x != "--no-docs") + "`.\n")
    print(text)
    out_dir = os.path.join(ROOT, "bench", "results")
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "many_properties.json"), "w") as f:
        json.dump({"load": [load, load_after], "v_jumps": a.v_jumps, "results": results}, f, indent=1)
    with open(os.path.join(out_dir, "many_properties.md"), "w") as f:
        f.write(text)
    plot(results, os.path.join(out_dir, "many_properties.png"))
    if not a.no_docs:
        write_marked(os.path.join(ROOT, "docs", "performance.md"), "many-properties", text)
        plot(results, os.path.join(ROOT, "docs", "img", "many-properties.png"))


def plot(results, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plot")
        return
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for kind in dict.fromkeys(r["kind"] for r in results):
        rows = [r for r in results if r["kind"] == kind]
        ns = [r["properties"] for r in rows]
        ax.plot(ns, [r["default"]["ns_per_msg"] / 1e3 for r in rows], "o-", label=f"{kind}")
        ax.plot(ns, [r["plain"]["ns_per_msg"] / 1e3 for r in rows], "x--", label=f"{kind}, --plain-eval")
    lo = min(r["properties"] for r in results)
    hi = max(r["properties"] for r in results)
    ax.plot([lo, hi], [0.25, 0.25 * hi / lo], ":", color="grey", label="linear growth")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("properties")
    ax.set_ylabel("CPU µs per message")
    ax.set_title("Many properties over one stream (rvc check)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
