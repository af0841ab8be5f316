#!/usr/bin/env python3
"""RV over the network vs local, and vs the transport's own tools, in one run.

  python3 bench/network_bench.py            # 30 Timescales files, DDS + Zenoh p2p, baselines, latency: ~5 min
  python3 bench/network_bench.py --quick    # 5 files of 200k events, shorter baselines: ~1 min
  python3 bench/network_bench.py --batch 64 --skip-latency --skip-baselines   # 64 events per sample

Per Timescales file and transport: `rvc replay FILE --to URI --rate max` -> `rvc monitor --input URI
--exit-on-eos` (two processes on one host), time from replay's first publish (`started_at`) to the
monitor's last verdict (`done_at`), beside `rvc check` on the same file (best of --reps), and the loss
counters (gaps + duplicates + sent - received + sent - checked). Transports: dds (CycloneDDS on lo,
reliable keep-all, rvc's defaults: replay packs samples into packets), dds-1pkt (the same with
`--no-dds-write-batch`: one UDP packet per sample, the old default), zenoh-p2p (two peers over
tcp/127.0.0.1; the monitor checks on Zenoh's receive thread, `--handoff inline`, its default there),
zenoh-queue (the same with `--handoff queue`: a queue to the checker's thread, the old default),
zenoh-router (both clients of an `rvc router`).

Baselines, measured in the same run, interleaved with the files (--baseline-reps times, median):
- DDS: `ddsperf pub size S` -> `ddsperf sub` (reliable keep-all, what ddsperf does: write batching), S =
  the mean line length of the files; samples/s = what the subscriber counted / the publish seconds;
- Zenoh: `rvc perf pub` -> `rvc perf sub` at size S: a plain Zenoh publisher/subscriber pair (the zenoh
  crate through rvc's C ABI: put with congestion control Block, callback subscriber that only counts);
- CPU per sample (user + sys of each process, /usr/bin/time) of every publisher and subscriber, and
  the ratio it implies where the CPU is the limit (2 cores, both processes busy): baseline (pub + sub)
  CPU per sample / rvc (replay + monitor) CPU per sample; less noisy than samples/s on a loaded machine;
- the cause, measured: dds-1pkt (one UDP packet per sample) and zenoh-queue (the queued hand-off) on
  the first --cause-files files, and zenoh-queue's latency beside zenoh-p2p's;
- "baseline-bound network / local": the file's samples at the baseline's rate / `rvc check`'s time,
  the best a monitor that cost nothing could do with one sample per event.
Latency: publish -> verdict received back (`rvc monitor --all`, `rvc replay --latency-from`), a round
trip, beside the transport's own ping round trip (ddsperf ping/pong; rvc perf ping/pong for Zenoh) at
the same rates.

Writes bench/results/network-batch{B}.{csv,md,json}, docs/network.png (--batch 1) and the tables into
docs/performance.md between the network markers. A benchmark, not a test: it prints ratios measured side
by side and asserts nothing. All traffic on loopback: DDS pinned to lo (rvc's generated config; ddsperf
gets the XML of `rvc dds-config`), Zenoh on tcp/127.0.0.1 with multicast scouting off.
"""
import argparse
import csv
import json
import os
import re
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from timescales_bench import FAMILIES, machine, write_marked  # noqa: E402

TIME = "/usr/bin/time"


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    p = s.getsockname()[1]
    s.close()
    return p


def loadavg():
    return os.getloadavg()[0]


def timed_cmd(cmd, tfile):
    """cmd under /usr/bin/time writing 'elapsed user sys' to tfile (the command's own output untouched)."""
    return [TIME, "-o", tfile, "-f", "%e %U %S"] + cmd


def read_time(tfile):
    with open(tfile) as f:
        e, u, s = f.read().strip().splitlines()[-1].split()
    return float(e), float(u) + float(s)


class Ctx:
    def __init__(self, args, tmp):
        self.args, self.tmp = args, tmp
        self.rvc = os.path.join(args.build, "rvc")
        self.domain = 60
        self.cfg = os.path.join(tmp, "dds.xml")
        subprocess.run([self.rvc, "dds-config", "-o", self.cfg], check=True)
        self.env = dict(os.environ, CYCLONEDDS_URI=f"file://{self.cfg}")
        self.ddsperf = shutil.which("ddsperf")
        self.n = 0

    def next_domain(self):
        self.domain = 61 + (self.domain - 60) % 150
        return self.domain

    def tfile(self, tag):
        self.n += 1
        return os.path.join(self.tmp, f"{tag}-{self.n}.time")


class Setup:
    def __init__(self, ctx, name):
        self.ctx, self.name, self.router = ctx, name, None
        rvc = ctx.rvc
        if name.startswith("dds"):
            self.mon = self.rep = ["--domain", str(ctx.next_domain())]
            if name == "dds-1pkt":
                self.rep = self.rep + ["--no-dds-write-batch"]
            self.key, self.out = "dds:/rv/bench", "dds:/rv/bench_verdicts"
        else:
            ep = f"tcp/127.0.0.1:{free_port()}"
            self.key, self.out = "zenoh:rv/bench", "zenoh:rv/bench_verdicts"
            if name == "zenoh-router":
                self.router = subprocess.Popen([rvc, "router", "--listen", ep, "--no-multicast-scouting"],
                                               stderr=subprocess.DEVNULL)
                time.sleep(0.5)
                self.mon = self.rep = ["--mode", "client", "--connect", ep, "--no-multicast-scouting"]
            else:
                self.mon = ["--mode", "peer", "--listen", ep, "--no-multicast-scouting"]
                self.rep = ["--mode", "peer", "--connect", ep, "--no-multicast-scouting"]
                if name == "zenoh-queue":
                    self.mon = self.mon + ["--handoff", "queue"]

    def close(self):
        if self.router:
            self.router.terminate()
            self.router.wait()


def run_pair(ctx, t, spec, trace, extra_mon=(), extra_rep=(), output="file:/dev/null"):
    """replay -> monitor over transport t; returns (monitor stats, replay summary, cpu dict)."""
    setup = Setup(ctx, t)
    tm, tr = ctx.tfile("mon"), ctx.tfile("rep")
    try:
        mon = subprocess.Popen(timed_cmd([ctx.rvc, "monitor", "--spec", spec, "--input", setup.key, "--output", output,
                                          "--exit-on-eos", *extra_mon, *setup.mon], tm),
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        rep = subprocess.run(timed_cmd([ctx.rvc, "replay", trace, "--to", setup.key, "--no-progress", "--wait-timeout",
                                        "30", *extra_rep, *setup.rep], tr), capture_output=True, text=True)
        _, err = mon.communicate(timeout=600)
    finally:
        setup.close()
    stats = json.loads([l for l in err.splitlines() if l.startswith("{")][-1])
    sent = json.loads([l for l in rep.stdout.splitlines() if l.startswith("{")][-1])
    return stats, sent, {"monitor": read_time(tm)[1], "replay": read_time(tr)[1]}


def lost_of(stats, sent):
    return stats["gaps"] + stats["duplicates"] + (sent.get("samples", sent["sent"]) - stats["received"]) \
        + (sent["sent"] - stats["checked"])


def local_best(ctx, spec, path, reps):
    best = None
    for _ in range(reps):
        t0 = time.perf_counter()
        subprocess.run([ctx.rvc, "check", "--spec", spec, path], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        dt = time.perf_counter() - t0
        best = dt if best is None else min(best, dt)
    return best


# ------------------------------------------------------------------ baselines

def ddsperf_throughput(ctx, size, secs):
    """ddsperf pub size S -> ddsperf sub: samples/s and CPU us per sample of each side."""
    d = str(ctx.next_domain())
    out = open(os.path.join(ctx.tmp, "ddsperf-sub.txt"), "w+")
    ts, tp = ctx.tfile("dsub"), ctx.tfile("dpub")
    sub = subprocess.Popen(timed_cmd([ctx.ddsperf, "-i", d, "-D", str(secs + 2), "sub"], ts), env=ctx.env,
                           stdout=out, stderr=subprocess.STDOUT)
    time.sleep(0.5)
    subprocess.run(timed_cmd([ctx.ddsperf, "-i", d, "-D", str(secs), "pub", "size", str(size)], tp), env=ctx.env,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=secs + 30)
    sub.wait(timeout=60)
    out.seek(0)
    text = out.read()
    out.close()
    totals = [(int(m.group(1)), int(m.group(2))) for m in re.finditer(r"size \d+ total (\d+) lost (\d+)", text)]
    total, lost = totals[-1] if totals else (0, 0)
    return dict(per_s=total / secs, samples=total, lost=lost,
                pub_us=read_time(tp)[1] / max(total, 1) * 1e6, sub_us=read_time(ts)[1] / max(total, 1) * 1e6)


def zenoh_throughput(ctx, size, secs):
    """rvc perf pub -> rvc perf sub over Zenoh p2p (a plain zenoh pub/sub pair)."""
    ep = f"tcp/127.0.0.1:{free_port()}"
    ts, tp = ctx.tfile("zsub"), ctx.tfile("zpub")
    sub = subprocess.Popen(timed_cmd([ctx.rvc, "perf", "sub", "-t", "zenoh", "--listen", ep, "--no-multicast-scouting",
                                      "--report-interval", "0"], ts), stdout=subprocess.PIPE,
                           stderr=subprocess.DEVNULL, text=True)
    time.sleep(0.3)
    subprocess.run(timed_cmd([ctx.rvc, "perf", "pub", "-t", "zenoh", "--connect", ep, "--no-multicast-scouting",
                              "--size", str(size), "--duration", str(secs), "--report-interval", "0"], tp),
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=secs + 60)
    out, _ = sub.communicate(timeout=60)
    r = json.loads(out.strip().splitlines()[-1])
    n = r["received"]
    return dict(per_s=r["avg_msgs_per_s"], samples=n, lost=r["lost"],
                pub_us=read_time(tp)[1] / max(n, 1) * 1e6, sub_us=read_time(ts)[1] / max(n, 1) * 1e6)


def ddsperf_ping(ctx, rate, size, secs):
    """ddsperf ping/pong: round-trip percentiles (ddsperf prints RTT/2 per second; x2, cnt-weighted mean
    of the per-second values, first second left out)."""
    d = str(ctx.next_domain())
    pong = subprocess.Popen([ctx.ddsperf, "-i", d, "-D", str(secs + 3), "pong"], env=ctx.env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(0.5)
    out = subprocess.run([ctx.ddsperf, "-i", d, "-D", str(secs + 1), "ping", f"{rate}Hz", "size", str(size)],
                         env=ctx.env, capture_output=True, text=True, timeout=secs + 30).stdout
    pong.wait(timeout=30)
    rows = []
    for m in re.finditer(r"\] (\d+\.\d+)\s+\S+ size \d+ mean [\d.]+us min [\d.]+us 50% ([\d.]+)us 90% ([\d.]+)us "
                         r"99% ([\d.]+)us max ([\d.]+)us cnt (\d+)", out):
        if float(m.group(1)) > 1.5:
            rows.append([float(m.group(i)) for i in range(2, 7)])
    if not rows:
        return {}
    cnt = sum(r[4] for r in rows)
    avg = lambda i: 2 * sum(r[i] * r[4] for r in rows) / cnt  # noqa: E731
    return dict(p50=avg(0), p90=avg(1), p99=avg(2), max=2 * max(r[3] for r in rows), count=int(cnt))


def zenoh_ping(ctx, rate, size, secs):
    """rvc perf ping/pong over Zenoh p2p; rvc perf reports RTT/2: x2."""
    ep = f"tcp/127.0.0.1:{free_port()}"
    pong = subprocess.Popen([ctx.rvc, "perf", "pong", "-t", "zenoh", "--listen", ep, "--no-multicast-scouting",
                             "--report-interval", "0"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(0.3)
    out = subprocess.run([ctx.rvc, "perf", "ping", "-t", "zenoh", "--connect", ep, "--no-multicast-scouting",
                          "--rate", str(rate), "--size", str(size), "--duration", str(secs), "--warmup", "0.5",
                          "--report-interval", "0"], capture_output=True, text=True, timeout=secs + 60).stdout
    pong.terminate()
    pong.wait()
    r = json.loads(out.strip().splitlines()[-1])
    return dict(p50=2 * r["p50_us"], p90=2 * r["p90_us"], p99=2 * r["p99_us"], max=2 * r["max_us"], count=r["count"])


def mean_line_bytes(path, limit=20000):
    n = tot = 0
    with open(path, "rb") as f:
        for line in f:
            n += 1
            tot += len(line.rstrip(b"\n"))
            if n >= limit:
                break
    return tot / max(n, 1)


# ---------------------------------------------------------------------- main

def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="5 files of 200k events, 1 rep, short baselines (~1 min)")
    ap.add_argument("--transports", default="dds,zenoh-p2p",
                    help="comma list of dds, dds-1pkt, zenoh-p2p, zenoh-queue, zenoh-router")
    ap.add_argument("--steps", type=int, default=None, help="events per file (default 1M, --quick 200k)")
    ap.add_argument("--reps", type=int, default=None, help="rvc check repetitions, best taken (default 3, quick 1)")
    ap.add_argument("--families", default=None)
    ap.add_argument("--bounds", default="10,100,1000")
    ap.add_argument("--skip-latency", action="store_true")
    ap.add_argument("--skip-baselines", action="store_true")
    ap.add_argument("--baseline-seconds", type=float, default=None, help="per baseline run (default 3, quick 2)")
    ap.add_argument("--baseline-reps", type=int, default=None, help="baseline runs per transport (default 3, quick 1)")
    ap.add_argument("--cause-files", type=int, default=1,
                    help="also run dds-1pkt (--no-dds-write-batch) and zenoh-queue (--handoff queue), the old "
                         "defaults, on the first N files (0: none)")
    ap.add_argument("--latency-seconds", type=float, default=None, help="per latency run (default 5, quick 1)")
    ap.add_argument("--latency-rounds", type=int, default=3,
                    help="latency runs per transport and rate, interleaved; the tables give the medians (default 3)")
    ap.add_argument("--batch", type=int, default=1, help="events per published sample (rvc replay --batch)")
    ap.add_argument("--build", default=os.path.join(ROOT, "build", "release"))
    ap.add_argument("--no-docs", action="store_true")
    ap.add_argument("--from-json", metavar="FILE", help="only re-render the tables/plot of a saved run")
    args = ap.parse_args()
    if args.from_json:
        return rerender(args)
    q = args.quick
    args.steps = args.steps or (200_000 if q else 1_000_000)
    args.reps = args.reps or (1 if q else 3)
    args.baseline_seconds = args.baseline_seconds or (2 if q else 3)
    args.baseline_reps = args.baseline_reps or (1 if q else 3)
    families = (args.families or ("AbsentAQ,AlwaysBR,RecurGLB,RespondBQR,AbsentBQR" if q else ",".join(FAMILIES)))
    bounds = "100" if q and args.bounds == "10,100,1000" else args.bounds
    t_start = time.time()
    tmp = tempfile.mkdtemp(prefix="rvc-netbench-")
    ctx = Ctx(args, tmp)
    rvc = ctx.rvc
    transports = args.transports.split(",")
    if not ctx.ddsperf and not args.skip_baselines and any(t.startswith("dds") for t in transports):
        sys.exit("ddsperf missing (Debian cyclonedds-tools): needed for the DDS baseline (or --skip-baselines)")
    data = os.path.join(ROOT, "bench", "results", "timescales" if args.steps == 1_000_000 else f"timescales-{args.steps}")
    os.makedirs(data, exist_ok=True)
    files = [(f, int(b)) for f in families.split(",") for b in bounds.split(",")]
    paths = []
    for family, bound in files:
        path = os.path.join(data, f"{family}{bound}.jsonl")
        if not os.path.exists(path):
            subprocess.run([rvc, "timescales", family, "--ubound", str(bound), "--duration", str(args.steps),
                            "--seed", "1", "-o", path], check=True)
        paths.append(path)
    size = int(round(statistics.mean(mean_line_bytes(p) for p in paths)))

    # Baseline runs spread over the file loop (same load as the files they are compared with).
    base = {"dds": [], "zenoh": []}
    want_base = [] if args.skip_baselines or args.batch != 1 else \
        [k for k in ("dds", "zenoh") if any(t.startswith(k) for t in transports)]
    slots = {int(i * len(files) / max(args.baseline_reps, 1)) for i in range(args.baseline_reps)}

    def baseline_rep():
        for k in want_base:
            r = ddsperf_throughput(ctx, size, args.baseline_seconds) if k == "dds" \
                else zenoh_throughput(ctx, size, args.baseline_seconds)
            r["load"] = loadavg()
            base[k].append(r)
            print(f"baseline {k:5s} size {size} B: {r['per_s'] / 1e3:7.0f} kS/s  pub {r['pub_us']:.2f} us/S  "
                  f"sub {r['sub_us']:.2f} us/S  lost {r['lost']}  load {r['load']:.1f}", flush=True)

    rows = []
    for n, ((family, bound), path) in enumerate(zip(files, paths), 1):
        if n - 1 in slots:
            baseline_rep()
        name = f"{family}{bound}"
        spec = subprocess.run([rvc, "timescales", family, "--ubound", str(bound), "--formula"],
                              capture_output=True, text=True, check=True).stdout.strip()
        local_s = local_best(ctx, spec, path, args.reps)
        row = dict(property=name, local_ms=local_s * 1e3, load=loadavg())
        extra = []
        if n <= args.cause_files and args.batch == 1:
            extra += ["dds-1pkt"] if "dds" in transports and "dds-1pkt" not in transports else []
            extra += ["zenoh-queue"] if "zenoh-p2p" in transports and "zenoh-queue" not in transports else []
        for t in transports + extra:
            stats, sent, cpu = run_pair(ctx, t, spec, path, extra_rep=["--batch", str(args.batch)])
            net_s = stats["done_at"] - sent["started_at"]
            nsamp = sent.get("samples", sent["sent"])
            row[f"{t}_ms"] = net_s * 1e3
            row[f"{t}_ratio"] = net_s / local_s
            row[f"{t}_per_s"] = nsamp / net_s
            row[f"{t}_rep_us"] = cpu["replay"] / nsamp * 1e6
            row[f"{t}_mon_us"] = cpu["monitor"] / nsamp * 1e6
            row[f"{t}_lost"] = lost_of(stats, sent)
        rows.append(row)
        print(f"[{n:2d}/{len(files)}] {name:14s} local {local_s*1e3:6.0f} ms  " +
              "  ".join(f"{t} {row[f'{t}_ms']:6.0f} ms ({row[f'{t}_ratio']:.2f}x, {row[f'{t}_per_s']/1e3:.0f} kS/s, "
                        f"lost {row[f'{t}_lost']})" for t in transports + extra) + f"  load {row['load']:.1f}", flush=True)

    latency = []
    if not args.skip_latency:
        lat_secs = args.latency_seconds or (1 if q else 5)
        trace_rates = [(1000, int(1000 * lat_secs)), (10000, int(10000 * lat_secs))]
        lat_transports = [t for t in transports if t in ("dds", "zenoh-p2p", "zenoh-queue")]
        if "zenoh-p2p" in lat_transports and "zenoh-queue" not in lat_transports and args.cause_files:
            lat_transports.insert(lat_transports.index("zenoh-p2p") + 1, "zenoh-queue")
        runs = {}  # (transport, rate) -> [(rv, ping, back, load)], one per round, rounds interleaved
        for rnd, t, (rate, count) in [(r, t, tr) for r in range(args.latency_rounds) for t in lat_transports
                                      for tr in trace_rates]:
            trace = os.path.join(data, f"latency_{count}.jsonl")
            if not os.path.exists(trace):
                subprocess.run([rvc, "timescales", "RecurGLB", "--ubound", "10", "--duration", str(count),
                                "--seed", "3", "-o", trace], check=True)
            setup_out = "dds:/rv/bench_verdicts" if t.startswith("dds") else "zenoh:rv/bench_verdicts"
            stats, sent, _ = run_pair(ctx, t, "once[:10]{p}", trace, extra_mon=["--all"],
                                      extra_rep=["--rate", str(rate), "--latency-from", setup_out],
                                      output=setup_out)
            lat = sent.get("latency_us", {})
            lsize = int(round(mean_line_bytes(trace)))
            ping = ddsperf_ping(ctx, rate, lsize, lat_secs + 1) if t.startswith("dds") \
                else zenoh_ping(ctx, rate, lsize, lat_secs + 1)
            runs.setdefault((t, rate, count), []).append((lat, ping, sent.get("verdicts_back", 0), loadavg()))
            print(f"latency [{rnd + 1}/{args.latency_rounds}] {t:10s} {rate:>6d}/s: rv p50 {lat.get('p50', 0):7.1f} p99 {lat.get('p99', 0):8.1f} us"
                  f" | ping RTT p50 {ping.get('p50', 0):7.1f} p99 {ping.get('p99', 0):8.1f} us "
                  f"({sent.get('verdicts_back', 0)}/{count} back)", flush=True)

        # Each figure: the median over the rounds (rv and ping alike); "back": verdicts over all rounds.
        for (t, rate, count), rs in runs.items():
            pick = lambda which, k: med([r[which].get(k, float("nan")) for r in rs])  # noqa: E731
            latency.append(dict(transport=t, rate=rate, messages=count * len(rs), back=sum(r[2] for r in rs),
                                rounds=len(rs), load=med([r[3] for r in rs]),
                                rv={k: pick(0, k) for k in ("p50", "p99", "max")},
                                ping={k: pick(1, k) for k in ("p50", "p99")} if all(r[1] for r in rs) else {},
                                rv_p50s=[r[0].get("p50") for r in rs], ping_p50s=[r[1].get("p50") for r in rs],
                                rv_p99s=[r[0].get("p99") for r in rs], ping_p99s=[r[1].get("p99") for r in rs]))

    elapsed = time.time() - t_start
    cmd = "python3 bench/network_bench.py" + (" " + " ".join(sys.argv[1:]) if sys.argv[1:] else "")
    out = os.path.join(ROOT, "bench", "results")
    os.makedirs(out, exist_ok=True)
    stem = os.path.join(out, f"network-batch{args.batch}")
    with open(stem + ".csv", "w", newline="") as f:
        keys = list(dict.fromkeys(k for r in rows for k in r))
        w = csv.DictWriter(f, fieldnames=keys, restval="")
        w.writeheader()
        w.writerows(rows)
    with open(stem + ".json", "w") as f:
        json.dump(dict(rows=rows, baselines=base, latency=latency, size=size, elapsed_s=elapsed, transports=transports,
                       args=vars(args), command=cmd), f, indent=1)
    md = render(rows, base, latency, transports, args, size, elapsed, cmd)
    with open(stem + ".md", "w") as f:
        f.write(md)
    if args.batch == 1:
        plot(rows, base, transports, os.path.join(ROOT, "docs", "network.png"))
    if not args.no_docs:
        tag = "network" if args.batch == 1 else f"network-batch{args.batch}"
        write_marked(os.path.join(ROOT, "docs", "performance.md"), tag, md)
    shutil.rmtree(tmp, ignore_errors=True)
    print(md)


def rerender(args):
    with open(args.from_json) as f:
        d = json.load(f)
    saved = argparse.Namespace(**dict(vars(args), **d.get("args", {})))
    saved.no_docs = args.no_docs
    for k, v in (("steps", 1_000_000), ("reps", 3), ("baseline_seconds", 3), ("baseline_reps", 3)):
        if getattr(saved, k, None) is None:
            setattr(saved, k, v)
    transports = d.get("transports") or [k[:-3] for k in d["rows"][0] if k.endswith("_ms") and k != "local_ms"
                                         and k not in ("dds-1pkt_ms", "zenoh-queue_ms")]
    md = render(d["rows"], d["baselines"], d["latency"], transports, saved, d["size"], d["elapsed_s"],
                d.get("command", "python3 bench/network_bench.py"))
    if saved.batch == 1:
        plot(d["rows"], d["baselines"], transports, os.path.join(ROOT, "docs", "network.png"))
    if not saved.no_docs:
        write_marked(os.path.join(ROOT, "docs", "performance.md"),
                     "network" if saved.batch == 1 else f"network-batch{saved.batch}", md)
    print(md)


def med(xs):
    xs = [x for x in xs if x == x]
    return statistics.median(xs) if xs else float("nan")


def render(rows, base, latency, transports, args, size, elapsed, cmd):
    loads = [r["load"] for r in rows]
    out = [f"Machine: {machine()}; load average (1 min) {min(loads):.1f}–{max(loads):.1f} during the run. "
           f"{args.steps:,} events per file, {args.batch} event(s) per published sample; network time = first "
           f"publish to last verdict; local = `rvc check`, best of {args.reps}. Run time {elapsed / 60:.1f} min. "
           f"Command: `{cmd}`.\n"]
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
        out.append(f"- {t}: network / local median **{med(ratios):.2f}**, min {min(ratios):.2f}, "
                   f"max {max(ratios):.2f}; median {med([r[f'{t}_per_s'] for r in rows]) / 1e3:.0f} k samples/s; "
                   f"CPU per sample: replay {med([r[f'{t}_rep_us'] for r in rows]):.2f} µs, monitor "
                   f"{med([r[f'{t}_mon_us'] for r in rows]):.2f} µs; lost {lost}")
    if any(base.values()):
        out.append("")
        out.append(f"Against the transport's own publisher → subscriber at the same sample size ({size} B, the mean "
                   f"line; {args.baseline_seconds:g} s runs, median of {args.baseline_reps}, interleaved with the files):\n")
        out.append("| transport | baseline | baseline kS/s | rvc replay → monitor kS/s (median of files) | rvc / baseline "
                   "| baseline pub / sub CPU µs per sample | rvc replay / monitor CPU µs per sample | CPU-bound rvc / "
                   "baseline | baseline-bound network / local | load |")
        out.append("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
        for k, label in (("dds", "ddsperf pub → ddsperf sub"), ("zenoh", "rvc perf pub → sub (zenoh crate)")):
            if not base[k]:
                continue
            t = "dds" if k == "dds" else "zenoh-p2p"
            if t not in transports:
                continue
            b = med([x["per_s"] for x in base[k]])
            mine = med([r[f"{t}_per_s"] for r in rows])
            # the best ratio a monitor could reach if it cost nothing: the baseline's time for the file / local
            floor = med([args.steps / b / (r["local_ms"] / 1e3) for r in rows])
            bp, bs = med([x['pub_us'] for x in base[k]]), med([x['sub_us'] for x in base[k]])
            variants = [(t, label)]
            for cause in ("dds-1pkt", "zenoh-queue"):
                if cause.startswith(k) and cause not in transports and any(f"{cause}_per_s" in r for r in rows):
                    variants.append((cause, label))
            for tv, lab in variants:
                sel = [r for r in rows if f"{tv}_per_s" in r]
                mine = med([r[f"{tv}_per_s"] for r in sel])
                rp, rm = med([r[f"{tv}_rep_us"] for r in sel]), med([r[f"{tv}_mon_us"] for r in sel])
                name = tv if tv == t else f"{tv} ({len(sel)} file{'s' if len(sel) != 1 else ''})"
                out.append(f"| {name} | {lab} | {b / 1e3:.0f} | {mine / 1e3:.0f} | **{mine / b:.2f}** | "
                           f"{bp:.2f} / {bs:.2f} | {rp:.2f} / {rm:.2f} | {(bp + bs) / (rp + rm):.2f} | "
                           f"{floor:.2f} | {med([x['load'] for x in base[k]]):.1f} |")
    if latency:
        out.append("")
        rounds = max(l.get("rounds", 1) for l in latency)
        out.append("Latency, publish → verdict received back (`rvc monitor --all`; a round trip) beside the "
                   "transport's own ping round trip at the same rate and size (DDS: ddsperf ping/pong, which prints "
                   "RTT/2, doubled; Zenoh: rvc perf ping/pong, doubled), microseconds; each figure the median of "
                   f"{rounds} interleaved rounds (rv run, then its ping run), p50 and p99 of each round in the last "
                   "columns:\n")
        out.append("| transport | rate (msg/s) | verdicts back | rv p50 | ping p50 | rv − ping p50 | rv p99 | ping p99 | "
                   "rv − ping p99 | rv max | load | rounds: rv / ping p50 | rounds: rv / ping p99 |")
        out.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|")
        for l in latency:
            rv, pg = l["rv"], l["ping"]
            out.append(f"| {l['transport']} | {l['rate']} | {l['back']}/{l['messages']} | {rv.get('p50', 0):.0f} | "
                       f"{pg.get('p50', float('nan')):.0f} | {rv.get('p50', 0) - pg.get('p50', float('nan')):+.0f} | "
                       f"{rv.get('p99', 0):.0f} | {pg.get('p99', float('nan')):.0f} | "
                       f"{rv.get('p99', 0) - pg.get('p99', float('nan')):+.0f} | {rv.get('max', 0):.0f} | "
                       f"{l['load']:.1f} | {each(l.get('rv_p50s'), l.get('ping_p50s'))} | "
                       f"{each(l.get('rv_p99s'), l.get('ping_p99s'))} |")
    out += targets(rows, base, latency, transports, args)
    return "\n".join(out) + "\n"


def each(rv, ping):
    """Each round's rv / ping figure: '106/73, 98/70, ...'."""
    if not rv:
        return ""
    return ", ".join(f"{a:.0f}/{b:.0f}" if a is not None and b is not None else "?" for a, b in zip(rv, ping or []))


def targets(rows, base, latency, transports, args):
    """Issue 27's targets against this run's figures: met, or not met with the measured bound."""
    out = ["", "Targets (issue 27), from the figures above:\n", "| target | measured | met |", "|---|---|---|"]
    yes = lambda ok: "**yes**" if ok else "no"  # noqa: E731
    for k, t, want_rate, want_local in (("dds", "dds", 0.8, 2.0), ("zenoh", "zenoh-p2p", 0.8, 1.5)):
        if t not in transports:
            continue
        ratios = [r[f"{t}_ratio"] for r in rows]
        if base.get(k):
            b = med([x["per_s"] for x in base[k]])
            mine = med([r[f"{t}_per_s"] for r in rows])
            cpu = (med([x["pub_us"] for x in base[k]]) + med([x["sub_us"] for x in base[k]])) / \
                (med([r[f"{t}_rep_us"] for r in rows]) + med([r[f"{t}_mon_us"] for r in rows]))
            out.append(f"| {t}: replay → monitor ≥ {want_rate}× the transport's own pub → sub, 0 lost | "
                       f"{mine / b:.2f}× samples/s ({cpu:.2f}× by CPU per sample); lost "
                       f"{sum(r[f'{t}_lost'] for r in rows)} | {yes(mine / b >= want_rate and not sum(r[f'{t}_lost'] for r in rows))} |")
            floor = med([args.steps / b / (r["local_ms"] / 1e3) for r in rows])
            bound = f"; the transport's own pub → sub alone needs {floor:.1f}× local for the same samples"
        else:
            bound = ""
        out.append(f"| {t}: network / local ≤ {want_local}× ({args.batch} event(s) per sample) | median "
                   f"{med(ratios):.2f}×{bound} | {yes(med(ratios) <= want_local)} |")
    for l in latency:
        rv, pg = l["rv"], l["ping"]
        if not pg:
            continue
        d50, d99 = rv.get("p50", 0) - pg["p50"], rv.get("p99", 0) - pg["p99"]
        out.append(f"| {l['transport']} at {l['rate']}/s: p50 ≤ ping p50 + 20 µs, p99 ≤ ping p99 + 50 µs | "
                   f"p50 {d50:+.0f} µs, p99 {d99:+.0f} µs over the ping | {yes(d50 <= 20 and d99 <= 50)} |")
    return out


def plot(rows, base, transports, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plot", file=sys.stderr)
        return
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(15, 4.5), gridspec_kw=dict(width_ratios=[3, 1]))
    names = [r["property"] for r in rows]
    x = range(len(rows))
    w = 0.8 / len(transports)
    for i, t in enumerate(transports):
        a1.bar([j - 0.4 + (i + 0.5) * w for j in x], [r[f"{t}_ratio"] for r in rows], w, label=t)
    a1.axhline(2, color="k", lw=0.8, ls="--")
    a1.set_xticks(list(x))
    a1.set_xticklabels(names, rotation=70, fontsize=7)
    a1.set_ylabel("network / local (rvc check)")
    a1.set_title("One sample per event: replay → monitor vs rvc check")
    a1.legend()
    labels, vals, colors = [], [], []
    for k, t in (("dds", "dds"), ("zenoh", "zenoh-p2p")):
        if base.get(k) and t in transports:
            labels += [f"{k}\nbaseline", f"{k}\nrvc"]
            vals += [med([b["per_s"] for b in base[k]]) / 1e3, med([r[f"{t}_per_s"] for r in rows]) / 1e3]
            colors += ["0.6", "C0" if k == "dds" else "C1"]
    if vals:
        a2.bar(range(len(vals)), vals, color=colors)
        a2.set_xticks(range(len(vals)))
        a2.set_xticklabels(labels, fontsize=8)
        a2.set_ylabel("k samples/s")
        a2.set_title("vs the transport's own pub → sub")
    fig.tight_layout()
    fig.savefig(path, dpi=100)


if __name__ == "__main__":
    main()
