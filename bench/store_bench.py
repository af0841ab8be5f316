#!/usr/bin/env python3
"""Results store throughput: does `--output sqlite:` / `postgresql://` keep up with the engine?

Side by side in one run, each best of --reps:
  rvc check TRACE -o /dev/null                       (no store: the floor)
  rvc check TRACE -o /dev/null -o sqlite:DB          (embedded default)
  rvc check TRACE -o /dev/null -o postgresql://...   (a throwaway server from scripts/postgres-test.sh,
                                                      unix socket only; skipped with the reason if absent)
on two traces: a Timescales trace (few verdict changes: the usual case) and a worst case where the
verdict changes on every message (a verdict row per message, a violation with its witness window
every other one). The time includes the store draining to the database before rvc exits.
Prints a markdown table, writes bench/results/store.json and the table into docs/performance.md.
This is a benchmark, not a test: it asserts nothing about time.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from timescales_bench import write_marked  # noqa: E402


def run(cmd):
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    elapsed = time.perf_counter() - t0
    if p.returncode not in (0, 1):
        raise RuntimeError(f"{' '.join(cmd)} exited {p.returncode}: {p.stderr[-500:]}")
    return elapsed, p.stderr


def rows_of(stderr):
    for line in stderr.splitlines():
        if line.startswith("rvc: results in "):
            return line.split(": ", 2)[-1]
    return ""


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rvc", default=os.path.join(ROOT, "build", "release", "rvc"))
    ap.add_argument("--messages", type=int, default=2_000_000, help="Timescales trace length")
    ap.add_argument("--toggles", type=int, default=200_000, help="worst-case trace length")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--no-docs", action="store_true")
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="rvc-store-bench-")
    # The server runs as the postgres user: its directory must not sit inside our 0700 temp dir.
    pg_dir, pg_uri = f"/tmp/rvc-store-bench-pg-{os.getpid()}", None
    try:
        ts = os.path.join(tmp, "timescales.jsonl")
        props = os.path.join(tmp, "props.yaml")
        print(f"== generating traces in {tmp}", flush=True)
        subprocess.run([a.rvc, "timescales", "AlwaysBQR", "--ubound", "100", "--duration", str(a.messages),
                        "--seed", "7", "-o", ts, "--properties-out", props], check=True, capture_output=True)
        toggle = os.path.join(tmp, "toggle.jsonl")
        with open(toggle, "w") as f:
            for i in range(a.toggles):
                f.write('{"a":%s,"n":%d}\n' % ("true" if i % 2 == 0 else "false", i))
        script = os.path.join(ROOT, "scripts", "postgres-test.sh")
        why_no_pg = ""
        if os.path.exists(script):
            p = subprocess.run(["bash", script, "start", pg_dir], capture_output=True, text=True)
            if p.returncode == 0:
                pg_uri = p.stdout.strip().splitlines()[-1]
            else:
                why_no_pg = p.stderr.strip().splitlines()[-1] if p.stderr.strip() else "start failed"
        else:
            why_no_pg = "scripts/postgres-test.sh missing"
        cases = [("Timescales AlwaysBQR", ts, ["--properties", props], a.messages),
                 ("verdict change on every message", toggle, ["--spec", "{a}"], a.toggles)]
        results = []
        for name, trace, spec, n in cases:
            stores = [("none", [])]
            stores.append(("sqlite", ["-o", "sqlite:" + os.path.join(tmp, "r.db")]))
            if pg_uri:
                stores.append(("postgresql", ["-o", pg_uri]))
            row = {"trace": name, "messages": n}
            for store, extra in stores:
                best, info = None, ""
                for rep in range(a.reps):
                    if store == "sqlite":
                        for suffix in ("", "-wal", "-shm"):
                            path = os.path.join(tmp, "r.db" + suffix)
                            if os.path.exists(path):
                                os.remove(path)
                    t, err = run([a.rvc, "check", *spec, trace, "-o", "/dev/null", *extra])
                    print(f"  {name}: store {store}, run {rep + 1}: {t:.2f} s ({n / t / 1e6:.2f} M msg/s)", flush=True)
                    if best is None or t < best:
                        best, info = t, rows_of(err)
                row[store] = {"seconds": best, "msgs_per_s": n / best, "stored": info}
            results.append(row)
        md = ["| trace | messages | no store (msg/s) | sqlite (msg/s, × no store) | postgresql (msg/s, × no store) |",
              "|---|---:|---:|---:|---:|"]
        for r in results:
            base = r["none"]["msgs_per_s"]

            def cell(k):
                if k not in r:
                    return "— (" + (why_no_pg or "not run") + ")"
                return f"{r[k]['msgs_per_s'] / 1e6:.2f} M ({r[k]['msgs_per_s'] / base:.2f}×)"
            md.append(f"| {r['trace']} | {r['messages']:,} | {base / 1e6:.2f} M | {cell('sqlite')} | {cell('postgresql')} |")
        stored = [f"- {r['trace']}, {k}: {r[k]['stored']}" for r in results for k in ("sqlite", "postgresql") if k in r]
        text = "\n".join(md) + "\n\nWhat each store run wrote:\n\n" + "\n".join(stored) + "\n"
        text += ("\nReproduce: `python3 bench/store_bench.py` (best of %d; `rvc check` with `-o /dev/null`, "
                 "time to exit, so the store's drain is included).\n" % a.reps)
        print(text)
        os.makedirs(os.path.join(ROOT, "bench", "results"), exist_ok=True)
        with open(os.path.join(ROOT, "bench", "results", "store.json"), "w") as f:
            json.dump(results, f, indent=1)
        if not a.no_docs:
            write_marked(os.path.join(ROOT, "docs", "performance.md"), "results-store", text)
    finally:
        if pg_uri:
            subprocess.run(["bash", os.path.join(ROOT, "scripts", "postgres-test.sh"), "stop", pg_dir],
                           capture_output=True)
        shutil.rmtree(tmp, ignore_errors=True)
        shutil.rmtree(pg_dir, ignore_errors=True)


if __name__ == "__main__":
    main()
