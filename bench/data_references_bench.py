#!/usr/bin/env python3
"""Data references (exists/forall over {file: *f}) as the number of distinct values grows.

One stream of file operations ({"op": "open"|"read"|"close", "file": "f<k>"}, k among N files),
N = 10 / 100 / 1,000 / 10,000, three properties checked side by side in one run:

  unbounded  forall[f]. ({op: close, file: *f} -> pre(once{op: open, file: *f}))
  bounded    forall[f]. ({op: close, file: *f} -> once[1:1000]{op: open, file: *f})
  plain      {op: close} -> pre(once{op: open})         (no reference: the floor)

rvc keeps one entry per file per sub-formula (docs/semantics.md, data references), so its cost
per message grows with N while memory grows with N only, not with the trace. For scale, Reelay 25's
data monitors (PyPI `reelay`, BDD-based, called from Python: its per-message call overhead is the
`plain` row) on the first --reelay-messages messages of the same stream.

Reports µs per message and peak RSS (GNU time) for rvc (whole process, best of --reps), µs per
message for Reelay; writes bench/results/data_references.json and the table into
docs/performance.md. A benchmark, not a test: nothing is asserted.
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

SPECS = {
    "unbounded": "forall[f]. ({op: close, file: *f} -> pre(once{op: open, file: *f}))",
    "bounded": "forall[f]. ({op: close, file: *f} -> once[1:1000]{op: open, file: *f})",
    "plain": "{op: close} -> pre(once{op: open})",
}


def run_rvc(rvc, spec, trace):
    t0 = time.perf_counter()
    p = subprocess.run(["/usr/bin/time", "-f", "RSS %M", rvc, "check", "--spec", spec, trace, "-o", "/dev/null"],
                       capture_output=True, text=True)
    elapsed = time.perf_counter() - t0
    if p.returncode not in (0, 1):
        raise RuntimeError(p.stderr[-400:])
    return elapsed, int([l for l in p.stderr.splitlines() if l.startswith("RSS ")][-1].split()[1])


def run_reelay(spec, events):
    import reelay
    m = reelay.discrete_timed_monitor(pattern=spec, condense=True)
    t0 = time.perf_counter()
    for e in events:
        m.update(e)
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rvc", default=os.path.join(ROOT, "build", "release", "rvc"))
    ap.add_argument("--files", default="10,100,1000,10000")
    ap.add_argument("--messages", type=int, default=100_000)
    ap.add_argument("--reelay-messages", type=int, default=5_000)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--no-docs", action="store_true")
    a = ap.parse_args()
    results = []
    with tempfile.TemporaryDirectory(prefix="rvc-data-") as tmp:
        for n in [int(x) for x in a.files.split(",")]:
            rng = random.Random(n)
            # Fewer messages for many files: the cost per message grows with them.
            count = a.messages if n <= 1000 else a.messages // 5
            events = [{"op": rng.choice(["open", "read", "close"]), "file": f"f{rng.randrange(n)}"} for _ in range(count)]
            trace = os.path.join(tmp, f"ops-{n}.jsonl")
            with open(trace, "w") as f:
                f.writelines(json.dumps(e) + "\n" for e in events)
            for name, spec in SPECS.items():
                best, rss = None, 0
                for _ in range(a.reps):
                    t, r = run_rvc(a.rvc, spec, trace)
                    if best is None or t < best:
                        best, rss = t, r
                rl = run_reelay(spec, events[:a.reelay_messages]) / min(a.reelay_messages, count)
                row = {"files": n, "property": name, "messages": count, "rvc_us_per_msg": best / count * 1e6,
                       "rvc_rss_kib": rss, "reelay_us_per_msg": rl * 1e6}
                results.append(row)
                print(f"  {n:6d} files {name:9s}: rvc {row['rvc_us_per_msg']:8.2f} us/msg RSS {rss / 1024:6.1f} MiB   "
                      f"reelay {row['reelay_us_per_msg']:8.2f} us/msg", flush=True)
    md = ["| files | property | rvc µs / message | rvc peak RSS | Reelay µs / message (Python) |",
          "|---:|---|---:|---:|---:|"]
    for r in results:
        md.append(f"| {r['files']:,} | {r['property']} | {r['rvc_us_per_msg']:.2f} | {r['rvc_rss_kib'] / 1024:.1f} MiB | "
                  f"{r['reelay_us_per_msg']:.2f} |")
    text = "\n".join(md) + (f"\n\n{a.messages:,} messages ({a.messages // 5:,} for more than 1,000 files), `rvc check -o "
                            f"/dev/null`, best of {a.reps}, whole process; Reelay on the first {a.reelay_messages:,} "
                            "messages, one Python call each. Reproduce: `python3 bench/data_references_bench.py`.\n")
    print(text)
    os.makedirs(os.path.join(ROOT, "bench", "results"), exist_ok=True)
    with open(os.path.join(ROOT, "bench", "results", "data_references.json"), "w") as f:
        json.dump(results, f, indent=1)
    if not a.no_docs:
        write_marked(os.path.join(ROOT, "docs", "performance.md"), "data-references", text)


if __name__ == "__main__":
    main()
