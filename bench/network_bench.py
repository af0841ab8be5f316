#!/usr/bin/env python3
"""RV over the network vs local: Timescales files through rvc replay ->
transport -> rvc monitor, side by side with rvc check on the same file.

  python3 bench/network_bench.py [--transports zenoh-p2p,zenoh-router,dds,dds-wb] [--steps 1000000]

(dds-wb: DDS with rvc replay --dds-write-batch, several samples per UDP packet.)

For each file and transport: total time from the first publish (replay's
started_at) to the last verdict out (monitor's done_at), and the loss
counters; beside it `rvc check` on the same file, best of --reps. Then a
ping-pong latency run per transport: publish -> verdict received back
(monitor --all), p50/p90/p99 at 10 Hz, 1 kHz, 10 kHz and max.

Writes bench/results/network.{csv,md} and the tables into
docs/performance.md between the network markers. A benchmark, not a test.
All traffic on loopback: DDS pinned to lo, Zenoh on tcp/127.0.0.1 with
multicast scouting off.
"""
import argparse
import csv
import json
import os
import socket
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from timescales_bench import FAMILIES, BOUNDS, machine, best_of, write_marked  # noqa: E402


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    p = s.getsockname()[1]
    s.close()
    return p


class Setup:
    def __init__(self, rvc, name, domain):
        self.rvc, self.name, self.router = rvc, name, None
        if name in ("dds", "dds-wb"):
            self.mon = self.rep = ["--domain", str(domain)]
            if name == "dds-wb":  # replay packs samples into packets (CycloneDDS write batching)
                self.rep = self.rep + ["--dds-write-batch"]
            self.key = "dds:/rv/bench"
            self.out = "dds:/rv/bench_verdicts"
        else:
            port = free_port()
            ep = f"tcp/127.0.0.1:{port}"
            self.key, self.out = "zenoh:rv/bench", "zenoh:rv/bench_verdicts"
            if name == "zenoh-router":
                self.router = subprocess.Popen([rvc, "router", "--listen", ep, "--no-multicast-scouting"],
                                               stderr=subprocess.DEVNULL)
                time.sleep(0.5)
                self.mon = self.rep = ["--mode", "client", "--connect", ep, "--no-multicast-scouting"]
            else:
                self.mon = ["--mode", "peer", "--listen", ep, "--no-multicast-scouting"]
                self.rep = ["--mode", "peer", "--connect", ep, "--no-multicast-scouting"]

    def close(self):
        if self.router:
            self.router.terminate()
            self.router.wait()


def run_pair(setup, spec, trace, extra_mon=(), extra_rep=(), output="file:/dev/null"):
    rvc = setup.rvc
    mon = subprocess.Popen([rvc, "monitor", "--spec", spec, "--input", setup.key, "--output", output,
                            "--exit-on-eos", *extra_mon, *setup.mon], stdout=subprocess.DEVNULL,
                           stderr=subprocess.PIPE, text=True)
    rep = subprocess.run([rvc, "replay", trace, "--to", setup.key, "--no-progress", "--wait-timeout", "30",
                          *extra_rep, *setup.rep], capture_output=True, text=True)
    _, err = mon.communicate(timeout=900)
    stats = json.loads([l for l in err.splitlines() if l.startswith("{")][-1])
    sent = json.loads(rep.stdout.strip().splitlines()[-1])
    return stats, sent


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--transports", default="zenoh-p2p,zenoh-router,dds,dds-wb")
    ap.add_argument("--steps", type=int, default=1_000_000)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--families", default=",".join(FAMILIES))
    ap.add_argument("--bounds", default="10,100,1000")
    ap.add_argument("--skip-latency", action="store_true")
    ap.add_argument("--batch", type=int, default=1, help="events per published sample (rvc replay --batch)")
    ap.add_argument("--build", default=os.path.join(ROOT, "build", "release"))
    ap.add_argument("--no-docs", action="store_true")
    args = ap.parse_args()
    rvc = os.path.join(args.build, "rvc")
    help_text = subprocess.run([rvc, "monitor", "--help"], capture_output=True, text=True).stdout
    transports = [t for t in args.transports.split(",")
                  if (t.startswith("dds") and "--domain" in help_text) or (t.startswith("zenoh") and "--connect" in help_text)]
    data = os.path.join(ROOT, "bench", "results", "timescales")
    os.makedirs(data, exist_ok=True)
    rows = []
    domain = 60
    files = [(f, int(b)) for f in args.families.split(",") for b in args.bounds.split(",")]
    for n, (family, bound) in enumerate(files, 1):
        name = f"{family}{bound}"
        path = os.path.join(data, f"{name}.jsonl")
        if not os.path.exists(path):
            subprocess.run([rvc, "timescales", family, "--ubound", str(bound), "--duration", str(args.steps),
                            "--seed", "1", "-o", path], check=True)
        spec = subprocess.run([rvc, "timescales", family, "--ubound", str(bound), "--formula"],
                              capture_output=True, text=True, check=True).stdout.strip()
        local_s, _, _ = best_of([rvc, "check", "--spec", spec, path], args.reps)
        row = dict(property=name, local_ms=local_s * 1e3)
        for t in transports:
            domain += 1
            setup = Setup(rvc, t, domain)
            try:
                stats, sent = run_pair(setup, spec, path, extra_rep=["--batch", str(args.batch)])
            finally:
                setup.close()
            net_s = stats["done_at"] - sent["started_at"]
            row[f"{t}_ms"] = net_s * 1e3
            row[f"{t}_ratio"] = net_s / local_s
            row[f"{t}_lost"] = stats["gaps"] + stats["duplicates"] + (sent.get("samples", sent["sent"]) - stats["received"]) \
                + (sent["sent"] - stats["checked"])
        rows.append(row)
        print(f"[{n:2d}/{len(files)}] {name:14s} local {local_s*1e3:7.1f} ms  " +
              "  ".join(f"{t} {row[f'{t}_ms']:8.1f} ms ({row[f'{t}_ratio']:.2f}x, lost {row[f'{t}_lost']})"
                        for t in transports), flush=True)

    latency = []
    if not args.skip_latency:
        for t in transports:
            for rate, count in (("10", 100), ("1000", 3000), ("10000", 30000), ("max", 100000)):
                domain += 1
                setup = Setup(rvc, t, domain)
                trace = os.path.join(data, f"latency_{count}.jsonl")
                if not os.path.exists(trace):
                    subprocess.run([rvc, "timescales", "RecurGLB", "--ubound", "10", "--duration", str(count),
                                    "--seed", "3", "-o", trace], check=True)
                try:
                    stats, sent = run_pair(setup, "once[:10]{p}", trace, extra_mon=["--all"],
                                           extra_rep=["--rate", rate, "--latency-from", setup.out],
                                           output=setup.out)
                finally:
                    setup.close()
                lat = sent.get("latency_us", {})
                latency.append(dict(transport=t, rate=rate, messages=count, back=sent.get("verdicts_back", 0), **lat))
                print(f"latency {t:13s} rate {rate:>5s}: p50 {lat.get('p50', 0):8.1f} us  p90 {lat.get('p90', 0):8.1f}"
                      f"  p99 {lat.get('p99', 0):9.1f}  ({sent.get('verdicts_back', 0)}/{count} back)", flush=True)

    out = os.path.join(ROOT, "bench", "results")
    with open(os.path.join(out, f"network-batch{args.batch}.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    md = render(rows, latency, transports, args)
    with open(os.path.join(out, f"network-batch{args.batch}.md"), "w") as f:
        f.write(md)
    if not args.no_docs:
        tag = "network" if args.batch == 1 else f"network-batch{args.batch}"
        write_marked(os.path.join(ROOT, "docs", "performance.md"), tag, md)
    print(md)


def render(rows, latency, transports, args):
    out = [f"Machine: {machine()}. {args.steps:,} events per file, {args.batch} event(s) per published sample; "
           f"network time = first publish to last verdict; local = `rvc check`, best of {args.reps}.\n"]
    head = "| property | local ms | " + " | ".join(f"{t} ms | {t} / local | {t} lost" for t in transports) + " |"
    out.append(head)
    out.append("|---|---:|" + "---:|---:|---:|" * len(transports))
    for r in rows:
        out.append(f"| {r['property']} | {r['local_ms']:.0f} | " + " | ".join(
            f"{r[f'{t}_ms']:.0f} | {r[f'{t}_ratio']:.2f} | {r[f'{t}_lost']}" for t in transports) + " |")
    out.append("")
    for t in transports:
        ratios = [r[f"{t}_ratio"] for r in rows]
        lost = sum(r[f"{t}_lost"] for r in rows)
        out.append(f"- {t}: network / local ratio median **{sorted(ratios)[len(ratios)//2]:.2f}**, "
                   f"min {min(ratios):.2f}, max {max(ratios):.2f}; lost {lost}")
    if latency:
        out.append("")
        out.append("Publish -> verdict received back (monitor --all), microseconds:\n")
        out.append("| transport | rate (msg/s) | messages | verdicts back | p50 | p90 | p99 | max |")
        out.append("|---|---:|---:|---:|---:|---:|---:|---:|")
        for l in latency:
            out.append(f"| {l['transport']} | {l['rate']} | {l['messages']} | {l['back']} | {l.get('p50', 0):.0f} | "
                       f"{l.get('p90', 0):.0f} | {l.get('p99', 0):.0f} | {l.get('max', 0):.0f} |")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    main()
