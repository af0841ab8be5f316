#!/usr/bin/env python3
"""Zenoh shared memory on one host: where it helps, measured side by side in one run.

  python3 bench/zenoh_shm_bench.py                 # builds build/shm (-DRVC_ZENOH_SHM=ON) if missing; ~4 min
  python3 bench/zenoh_shm_bench.py --quick         # 1 rep, shorter runs: ~1.5 min

Two rvc binaries from the same sources: build/release/rvc (rvc's default, Zenoh without shared
memory) and build/shm/rvc (the zenoh crate's `shared-memory` feature; Zenoh's defaults then put
payloads of 3 KiB and more into /dev/shm when both peers are on one host and both support it).
Per payload size, interleaved (the same load for both builds), `--reps` times, median:
- a plain pair: `rvc perf pub --rate max` -> `rvc perf sub` (two peers over tcp/127.0.0.1, congestion
  control Block): messages/s, MiB/s, CPU per message of each side (/usr/bin/time);
- latency: `rvc perf ping` -> `rvc perf pong` at --ping-rate, round trip p50/p99 (rvc perf prints
  RTT/2: doubled);
- the monitor's path: `rvc replay --rate max` -> `rvc monitor --exit-on-eos` of a trace whose lines
  carry the payload (a JSON string field beside the checked one), time from first publish to last
  verdict, 0 lost asserted by the counters.
Whether shared memory was used is observed, not assumed: the /dev/shm/*.zenoh segments present while
the SHM build's pair runs (none appear for the default build). The run has a /dev/shm of its own (a
tmpfs in a private mount namespace, as root): Zenoh's segments never land in the host's.

Writes bench/results/zenoh-shm.{json,md} and docs/img/zenoh-shm.png, and the table into docs/zenoh.md
between the shm markers. A benchmark, not a test: it asserts nothing about speed. Loopback only.
"""
import argparse
import glob
import json
import os
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TIME = "/usr/bin/time"
SIZES = [37, 4096, 65536, 1048576]


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def size_text(n):
    return f"{n // 1048576} MiB" if n >= 1048576 else f"{n // 1024} KiB" if n >= 1024 else f"{n} B"


def timed(cmd, tfile):
    return [TIME, "-o", tfile, "-f", "%e %U %S"] + cmd


def cpu_of(tfile):
    with open(tfile) as f:
        _, u, s = f.read().strip().splitlines()[-1].split()
    return float(u) + float(s)


class ShmWatch:
    """Counts the distinct /dev/shm/*.zenoh segments seen while a run lasts."""

    def __init__(self):
        self.seen, self._stop = set(), threading.Event()
        self._t = threading.Thread(target=self._run, daemon=True)

    def _run(self):
        while not self._stop.is_set():
            self.seen.update(glob.glob("/dev/shm/*.zenoh"))
            time.sleep(0.05)

    def __enter__(self):
        self.before = set(glob.glob("/dev/shm/*.zenoh"))
        self._t.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._t.join()

    def count(self):
        return len(self.seen - self.before)


def pair(rvc, size, secs, tmp, tag):
    ep = f"tcp/127.0.0.1:{free_port()}"
    ts, tp = os.path.join(tmp, f"{tag}-sub.time"), os.path.join(tmp, f"{tag}-pub.time")
    with ShmWatch() as watch:
        sub = subprocess.Popen(timed([rvc, "perf", "sub", "-t", "zenoh", "--listen", ep, "--no-multicast-scouting",
                                      "--report-interval", "0"], ts), stdout=subprocess.PIPE,
                               stderr=subprocess.DEVNULL, text=True)
        time.sleep(0.4)
        subprocess.run(timed([rvc, "perf", "pub", "-t", "zenoh", "--connect", ep, "--no-multicast-scouting",
                              "--size", str(size), "--duration", str(secs), "--report-interval", "0"], tp),
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=secs + 120)
        out, _ = sub.communicate(timeout=120)
    r = json.loads(out.strip().splitlines()[-1])
    n = max(r["received"], 1)
    return dict(per_s=r["avg_msgs_per_s"], mib_s=r["avg_msgs_per_s"] * size / 1048576, lost=r["lost"],
                pub_us=cpu_of(tp) / n * 1e6, sub_us=cpu_of(ts) / n * 1e6, shm_segments=watch.count())


def ping(rvc, size, rate, secs):
    ep = f"tcp/127.0.0.1:{free_port()}"
    pong = subprocess.Popen([rvc, "perf", "pong", "-t", "zenoh", "--listen", ep, "--no-multicast-scouting",
                             "--report-interval", "0"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(0.4)
    out = subprocess.run([rvc, "perf", "ping", "-t", "zenoh", "--connect", ep, "--no-multicast-scouting", "--rate",
                          str(rate), "--size", str(size), "--duration", str(secs), "--warmup", "0.5",
                          "--report-interval", "0"], capture_output=True, text=True, timeout=secs + 120).stdout
    pong.terminate()
    pong.wait()
    r = json.loads(out.strip().splitlines()[-1])
    return dict(p50=2 * r["p50_us"], p99=2 * r["p99_us"])


def trace_with_payload(path, size, n):
    filler = "x" * max(size - 24, 0)
    with open(path, "w") as f:
        for i in range(n):
            f.write('{"p":%s,"blob":"%s"}\n' % ("true" if i % 5 else "false", filler))


def monitor_path(rvc, trace, n, tmp, tag):
    ep = f"tcp/127.0.0.1:{free_port()}"
    tm = os.path.join(tmp, f"{tag}-mon.time")
    mon = subprocess.Popen(timed([rvc, "monitor", "--spec", "once[0:3]{p}", "--input", "zenoh:rv/shm", "--exit-on-eos",
                                  "--output", "file:/dev/null", "--listen", ep, "--no-multicast-scouting"], tm),
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    rep = subprocess.run([rvc, "replay", trace, "--to", "zenoh:rv/shm", "--rate", "max", "--no-progress",
                          "--wait-subscribers", "1", "--wait-timeout", "30", "--connect", ep, "--no-multicast-scouting"],
                         capture_output=True, text=True, timeout=600)
    _, err = mon.communicate(timeout=600)
    stats = json.loads([ln for ln in err.splitlines() if ln.startswith("{")][-1])
    sent = json.loads([ln for ln in rep.stdout.splitlines() if ln.startswith("{")][-1])
    lost = stats["gaps"] + stats["duplicates"] + (n - stats["received"]) + (n - stats["checked"])
    secs = stats["done_at"] - sent["started_at"]
    return dict(ms=secs * 1e3, per_s=n / secs, lost=lost, mon_us=cpu_of(tm) / n * 1e6)


def private_dev_shm():
    """Runs this benchmark in its own mount namespace with a fresh tmpfs on /dev/shm (re-executing
    itself under unshare): Zenoh leaves the last exiting process's segments there, and its orphan
    cleanup removes other Zenoh processes' dead segments, neither of which may touch the host's
    /dev/shm. The namespace's tmpfs goes away with it."""
    if os.environ.get("RVC_SHM_BENCH_NS") == "1":
        return
    if os.geteuid() != 0 or not shutil.which("unshare"):
        sys.exit("zenoh_shm_bench.py runs in a private /dev/shm (unshare --mount, as root): not possible here")
    script = 'mount -t tmpfs -o size=512m,mode=1777 rvc-shm-bench /dev/shm && exec "$@"'
    env = dict(os.environ, RVC_SHM_BENCH_NS="1")
    os.execvpe("unshare", ["unshare", "--mount", "--propagation", "private", "sh", "-c", script, "sh",
                           sys.executable, os.path.abspath(__file__), *sys.argv[1:]], env)


def ensure_shm_build(build):
    rvc = os.path.join(build, "rvc")
    if os.path.exists(rvc):
        return rvc
    env = dict(os.environ)
    cache = os.path.join(ROOT, "scripts", "cache-env.sh")
    print(f"building {build} (-DRVC_ZENOH_SHM=ON): the zenoh crate with shared memory, several minutes", flush=True)
    subprocess.run(["bash", "-c", f". {cache}; cmake -S {ROOT} -B {build} -G Ninja -DCMAKE_BUILD_TYPE=Release "
                    f"-DRVC_ZENOH_SHM=ON -DRVC_BUILD_TESTS=OFF >/dev/null && cmake --build {build} --target rvc -j2"],
                   check=True, env=env, cwd=ROOT)
    return rvc


def med(xs):
    return statistics.median(xs) if xs else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--reps", type=int, default=None)
    ap.add_argument("--seconds", type=float, default=None, help="per pub/sub run (default 2, quick 1)")
    ap.add_argument("--ping-rate", type=int, default=100)
    ap.add_argument("--monitor-bytes", type=int, default=262144, help="MiB-order traffic per monitor run: "
                    "messages = this many KiB / size (min 200)")
    ap.add_argument("--sizes", default=",".join(map(str, SIZES)))
    ap.add_argument("--default-build", default=os.path.join(ROOT, "build", "release"))
    ap.add_argument("--shm-build", default=os.path.join(ROOT, "build", "shm"))
    ap.add_argument("--no-docs", action="store_true")
    args = ap.parse_args()
    reps = args.reps or (1 if args.quick else 3)
    secs = args.seconds or (1 if args.quick else 2)
    sizes = [int(s) for s in args.sizes.split(",")]
    builds = {"default": os.path.join(args.default_build, "rvc"), "shm": ensure_shm_build(args.shm_build)}
    if not os.path.exists(builds["default"]):
        sys.exit(f"{builds['default']} missing: build rvc first (scripts/build.sh)")
    private_dev_shm()
    tmp = tempfile.mkdtemp(prefix="rvc-shm-bench-")
    t0 = time.time()
    res = {b: {s: dict(pair=[], ping=[], mon=[]) for s in sizes} for b in builds}
    for rep in range(reps):
        for size in sizes:
            n = max(200, args.monitor_bytes * 1024 // size // (4 if args.quick else 1))
            n = min(n, 200000)
            trace = os.path.join(tmp, f"t{size}.jsonl")
            if not os.path.exists(trace):
                trace_with_payload(trace, size, n)
            for b, rvc in builds.items():
                p = pair(rvc, size, secs, tmp, f"{b}-{size}-{rep}")
                g = ping(rvc, size, args.ping_rate, secs)
                m = monitor_path(rvc, trace, n, tmp, f"{b}-{size}-{rep}")
                for k, v in (("pair", p), ("ping", g), ("mon", m)):
                    res[b][size][k].append(v)
                print(f"[{rep + 1}/{reps}] {size_text(size):>7s} {b:7s}: pair {p['per_s'] / 1e3:8.1f} k/s "
                      f"{p['mib_s']:8.0f} MiB/s (pub {p['pub_us']:.1f} / sub {p['sub_us']:.1f} us/msg, lost "
                      f"{p['lost']}, shm segments {p['shm_segments']}) | ping RTT p50 {g['p50']:.0f} p99 {g['p99']:.0f}"
                      f" us | monitor {m['per_s'] / 1e3:.1f} k/s ({m['mon_us']:.1f} us/msg, lost {m['lost']})",
                      flush=True)
    elapsed = time.time() - t0
    md = render(res, sizes, reps, secs, args, elapsed)
    out = os.path.join(ROOT, "bench", "results")
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "zenoh-shm.json"), "w") as f:
        json.dump(dict(results={b: {str(s): v for s, v in d.items()} for b, d in res.items()}, sizes=sizes,
                       reps=reps, seconds=secs, elapsed_s=elapsed), f, indent=1)
    with open(os.path.join(out, "zenoh-shm.md"), "w") as f:
        f.write(md)
    plot(res, sizes, os.path.join(ROOT, "docs", "img", "zenoh-shm.png"))
    if not args.no_docs:
        write_marked(os.path.join(ROOT, "docs", "zenoh.md"), "shm", md)
    print(md)


def render(res, sizes, reps, secs, args, elapsed):
    def m(b, s, k, f):
        return med([x[f] for x in res[b][s][k]])
    load = os.getloadavg()[0]
    out = [f"Median of {reps} interleaved runs ({secs:g} s per pub/sub run, pings at {args.ping_rate}/s); run time "
           f"{elapsed / 60:.1f} min, load average {load:.1f} at the end. Command: `python3 bench/zenoh_shm_bench.py"
           f"{' --quick' if args.quick else ''}`.\n",
           "| payload | build | pub → sub msg/s | MiB/s | shm / default | pub / sub CPU µs per msg | ping RTT p50 / p99 µs "
           "| replay → monitor msg/s | monitor CPU µs per msg | lost | /dev/shm segments |",
           "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for s in sizes:
        for b in ("default", "shm"):
            ratio = m(b, s, "pair", "per_s") / m("default", s, "pair", "per_s")
            lost = sum(x["lost"] for k in ("pair", "mon") for x in res[b][s][k])
            out.append(f"| {size_text(s)} | {b} | {m(b, s, 'pair', 'per_s'):,.0f} | {m(b, s, 'pair', 'mib_s'):,.0f} | "
                       f"{'' if b == 'default' else f'**{ratio:.2f}×**'} | {m(b, s, 'pair', 'pub_us'):.2f} / "
                       f"{m(b, s, 'pair', 'sub_us'):.2f} | {m(b, s, 'ping', 'p50'):.0f} / {m(b, s, 'ping', 'p99'):.0f} | "
                       f"{m(b, s, 'mon', 'per_s'):,.0f} | {m(b, s, 'mon', 'mon_us'):.2f} | {lost} | "
                       f"{max(x['shm_segments'] for x in res[b][s]['pair'])} |")
    return "\n".join(out) + "\n"


def plot(res, sizes, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plot", file=sys.stderr)
        return
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4))
    x = range(len(sizes))
    for i, b in enumerate(("default", "shm")):
        a1.bar([j - 0.2 + 0.4 * i for j in x], [med([r["mib_s"] for r in res[b][s]["pair"]]) for s in sizes], 0.4,
               label=b)
        a2.bar([j - 0.2 + 0.4 * i for j in x], [med([r["p50"] for r in res[b][s]["ping"]]) for s in sizes], 0.4,
               label=b)
    for a, t in ((a1, "pub → sub MiB/s"), (a2, "ping round trip p50, µs")):
        a.set_xticks(list(x))
        a.set_xticklabels([size_text(s) for s in sizes])
        a.set_title(t)
        a.legend()
    fig.suptitle("Zenoh on one host: default build vs shared memory (-DRVC_ZENOH_SHM=ON)")
    fig.tight_layout()
    os.makedirs(os.path.dirname(path), exist_ok=True)
    fig.savefig(path, dpi=100)


def write_marked(path, tag, md):
    begin, end = f"<!-- {tag}:begin -->", f"<!-- {tag}:end -->"
    text = open(path).read()
    if begin in text and end in text:
        text = text[:text.index(begin) + len(begin)] + "\n" + md + text[text.index(end):]
    else:
        text += f"\n{begin}\n{md}{end}\n"
    with open(path, "w") as f:
        f.write(text)


if __name__ == "__main__":
    main()
