#!/usr/bin/env python3
"""Dense time on a clock (issue 26): how soon a silence is reported, and what an idle monitor costs.

  python3 bench/tick_bench.py [--silences 1000] [--rvc PATH] [--transports zenoh,dds] [--skip-idle]

Detection latency, per transport: `rvc monitor --dense --clock wall --spec 'once[0:0.02]{alive}'`
and a Python peer (this script) that, --silences times, publishes {"alive":true} then
{"alive":false} stamped with time.time() (epoch seconds, the wall clock rvc ticks on) and stays
silent for 50 ms. The property falls 20 ms after the false message's stamp: that instant is the
false verdict's own "time", so the latency is its arrival at this script's subscriber
(time.time()) minus its "time": missed deadline -> verdict received, no message involved. Beside
it, in the same run, the transport's one-way floor: the same script subscribes to the input too
and takes each message's arrival minus its stamp. rvc's own counters add `tick_lag_us`: how late
its engine thread woke for each deadline it slept for (the scheduler's part of the latency).

Idle cost (Zenoh, loopback): a monitor whose clock has nothing due, sampled for 10 s from
/proc/PID/stat (CPU) and /proc/PID/task/*/status (voluntary context switches over every thread:
wake-ups), in two shapes:
- 100 silent topics: `--input tK=zenoh:bench/idle/tK` for K < 100 (merge), one message each at the
  start, properties `once[0:0.05]{tK.alive}` that fall 50 ms later; then nothing is due;
- 1000 properties with deadlines: one input, `once[0:D]{alive}` with D = 0.01 * (1..1000): after one
  message with alive false, each falls at its own deadline over the 10 s, one tick each.
The rvc figures include Zenoh's own threads; the same monitor with `--clock off` is sampled beside
it as the floor.

Writes bench/results/tick_bench.json and the tables into docs/performance.md between the
tick-latency markers. A benchmark, not a test: it asserts nothing. Loopback only: Zenoh on
tcp/127.0.0.1 with multicast scouting off; DDS pinned to lo (`rvc dds-config`'s XML for Python).
"""
import argparse
import glob
import json
import os
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from enforcer_latency import dds_qos, dds_string_type, free_port, zenoh_session  # noqa: E402
from timescales_bench import machine, write_marked  # noqa: E402

TAG = "tick-latency"
BOUND = 0.02   # the property's window: the deadline is 20 ms after the false message
SILENCE = 0.05  # how long the publisher stays silent after it
HEADING = """
## Clock ticks: silences detected, idle cost (`python3 bench/tick_bench.py`)

Reproduce: `python3 bench/tick_bench.py` (1000 silences per transport, about 70 s each, then 2 × 2 idle
samples of 10 s; the setup is in its docstring and in `docs/semantics.md`, "Ticks").
"""


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def pct(xs, q):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(round(q / 100 * (len(xs) - 1))))]


def summary(xs):
    return {"n": len(xs), "p50": pct(xs, 50), "p99": pct(xs, 99), "max": max(xs)} if xs else {"n": 0}


# ---------------------------------------------------------------- detection latency

class Peer:
    """Publishes the input, receives the verdicts and the input itself (the floor)."""

    def __init__(self, transport, domain=0, endpoint=None):
        self.transport = transport
        self.verdicts, self.floor = [], []
        self.lock = threading.Lock()
        if transport == "zenoh":
            self.s = zenoh_session(connect=[endpoint])
            self.subs = [self.s.declare_subscriber("bench/tick/verdicts", self._zv),
                         self.s.declare_subscriber("bench/tick/in", self._zi)]
            self.pub = self.s.declare_publisher("bench/tick/in")
        else:
            from cyclonedds.core import Listener
            from cyclonedds.domain import DomainParticipant
            from cyclonedds.pub import DataWriter
            from cyclonedds.sub import DataReader
            from cyclonedds.topic import Topic
            self.String_ = dds_string_type()
            self.dp = DomainParticipant(domain)
            self.readers = [
                DataReader(self.dp, Topic(self.dp, "rt/bench/tick/verdicts", self.String_), qos=dds_qos(),
                           listener=Listener(on_data_available=lambda r: self._dds(r, self._verdict))),
                DataReader(self.dp, Topic(self.dp, "rt/bench/tick/in", self.String_), qos=dds_qos(),
                           listener=Listener(on_data_available=lambda r: self._dds(r, self._input)))]
            self.writer = DataWriter(self.dp, Topic(self.dp, "rt/bench/tick/in", self.String_), qos=dds_qos())

    def _zv(self, sample):
        self._verdict(time.time(), sample.payload.to_bytes().decode())

    def _zi(self, sample):
        self._input(time.time(), sample.payload.to_bytes().decode())

    def _dds(self, reader, handle):
        t = time.time()
        for smp in reader.take(N=256):
            data = getattr(smp, "data", None)
            if data:
                handle(t, data)

    def _verdict(self, t, text):
        if text.startswith("{"):
            with self.lock:
                self.verdicts.append((t, json.loads(text)))

    def _input(self, t, text):
        with self.lock:
            self.floor.append(t - json.loads(text)["time"])

    def publish(self, alive):
        text = json.dumps({"time": time.time(), "alive": alive})
        if self.transport == "zenoh":
            self.pub.put(text)
        else:
            self.writer.write(self.String_(data=text))


def latency_run(rvc, transport, silences, tmp):
    env = dict(os.environ)
    args = [rvc, "monitor", "--dense", "--clock", "wall", "--spec", f"once[0:{BOUND}]{{alive}}"]
    domain, endpoint = 0, None
    if transport == "zenoh":
        endpoint = f"tcp/127.0.0.1:{free_port()}"
        args += ["--input", "zenoh:bench/tick/in", "--output", "zenoh:bench/tick/verdicts", "--listen", endpoint,
                 "--no-multicast-scouting"]
    else:
        domain = 100 + os.getpid() % 50
        cfg = os.path.join(tmp, "cyclonedds.xml")
        subprocess.run([rvc, "dds-config", "-o", cfg], check=True)
        env["CYCLONEDDS_URI"] = f"file://{cfg}"
        os.environ["CYCLONEDDS_URI"] = env["CYCLONEDDS_URI"]  # this script's own participant, before it exists
        args += ["--input", "dds:/bench/tick/in", "--output", "dds:/bench/tick/verdicts", "--domain", str(domain)]
    mon = subprocess.Popen(args, stderr=subprocess.PIPE, text=True, env=env)
    time.sleep(0.5)
    peer = Peer(transport, domain, endpoint)
    time.sleep(1.5)  # discovery
    for _ in range(silences):
        peer.publish(True)
        time.sleep(0.002)
        peer.publish(False)
        time.sleep(SILENCE)
    time.sleep(0.5)
    mon.terminate()
    _, err = mon.communicate(timeout=30)
    stats = json.loads(err.strip().splitlines()[-1])
    with peer.lock:
        falls = [t - v["time"] for t, v in peer.verdicts if v["value"] is False and v["time"] > 1e9]
        floor = list(peer.floor)
    return {"transport": transport, "silences": silences,
            "detection_us": summary([x * 1e6 for x in falls]),
            "floor_us": summary([x * 1e6 for x in floor]),
            "stats": {k: stats.get(k) for k in ("received", "checked", "ticks", "late_to_clock", "clock", "tick_lag_us")}}


# ---------------------------------------------------------------- idle cost

def cpu_and_wakeups(pid, seconds):
    """(CPU % of one core, voluntary context switches per second over all threads) over `seconds`."""
    tick = os.sysconf("SC_CLK_TCK")

    def sample():
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        cpu = (int(fields[11]) + int(fields[12])) / tick  # utime + stime
        switches = 0
        for status in glob.glob(f"/proc/{pid}/task/*/status"):
            try:
                with open(status) as f:
                    for line in f:
                        if line.startswith("voluntary_ctxt_switches"):
                            switches += int(line.split()[1])
            except FileNotFoundError:
                pass
        return cpu, switches, time.monotonic()

    c0, s0, t0 = sample()
    time.sleep(seconds)
    c1, s1, t1 = sample()
    return {"cpu_percent": 100 * (c1 - c0) / (t1 - t0), "wakeups_per_s": (s1 - s0) / (t1 - t0)}


def idle_run(rvc, shape, clock, seconds):
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    if shape == "100 silent topics":
        n = 100
        args = [rvc, "monitor", "--dense", "--clock", clock]
        for k in range(n):
            args += ["--input", f"t{k}=zenoh:bench/idle/t{k}"]
        args += ["--spec", " and ".join(f"once[0:0.05]{{t{k}.alive}}" for k in range(n))]
        keys = [f"bench/idle/t{k}" for k in range(n)]
    else:
        args = [rvc, "monitor", "--dense", "--clock", clock, "--input", "zenoh:bench/idle/one"]
        for d in range(1, 1001):
            args += ["--spec", f"once[0:{d / 100:g}]{{alive}}"]
        keys = ["bench/idle/one"]
    args += ["--output", "file:/dev/null", "--listen", endpoint, "--no-multicast-scouting"]
    mon = subprocess.Popen(args, stderr=subprocess.PIPE, text=True)
    time.sleep(1.0)
    s = zenoh_session(connect=[endpoint])
    pubs = [s.declare_publisher(k) for k in keys]
    time.sleep(1.5)
    for p in pubs:  # one message each, stamped now, then silence
        p.put(json.dumps({"time": time.time(), "alive": True}))
    for p in pubs:
        p.put(json.dumps({"time": time.time(), "alive": False}))
    time.sleep(0.2)
    cost = cpu_and_wakeups(mon.pid, seconds)
    mon.terminate()
    _, err = mon.communicate(timeout=30)
    stats = json.loads(err.strip().splitlines()[-1])
    s.close()
    return dict(cost, shape=shape, clock=clock, seconds=seconds,
                stats={k: stats.get(k) for k in ("received", "checked", "ticks", "verdicts")})


# ---------------------------------------------------------------- report

def table(results):
    lines = ["| transport | latency, µs | n | p50 | p99 | max |", "|---|---|---:|---:|---:|---:|"]
    for r in results["latency"]:
        for label, key in [("transport floor: publish → plain Python subscriber", "floor_us"),
                           ("missed deadline → false verdict at the subscriber", "detection_us")]:
            s = r[key]
            lines.append(f"| {r['transport']} | {label} | {s['n']} | {s['p50']:.0f} | {s['p99']:.0f} | {s['max']:.0f} |")
        lag = r["stats"].get("tick_lag_us")
        if lag:
            lines.append(f"| {r['transport']} | inside rvc: deadline → the engine thread's wake-up (`tick_lag_us`) | "
                         f"those slept for, of {r['stats'].get('ticks')} ticks | {lag['p50']:.0f} | {lag['p99']:.0f} | {lag['max']:.0f} |")
    lines += ["", "| idle monitor (Zenoh) | clock | CPU, % of a core | wake-ups/s (all threads) | ticks |",
              "|---|---|---:|---:|---:|"]
    for r in results["idle"]:
        lines.append(f"| {r['shape']} | {r['clock']} | {r['cpu_percent']:.2f} | {r['wakeups_per_s']:.1f} | "
                     f"{r['stats'].get('ticks') if r['stats'].get('ticks') is not None else '-'} |")
    notes = [f"- {r['transport']}: rvc counters {json.dumps(r['stats'])}" for r in results["latency"]]
    return "\n".join(lines + [""] + notes)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--silences", type=int, default=1000)
    ap.add_argument("--rvc", default=os.path.join(ROOT, "build", "release", "rvc"))
    ap.add_argument("--transports", default="zenoh,dds")
    ap.add_argument("--idle-seconds", type=float, default=10)
    ap.add_argument("--skip-idle", action="store_true")
    ap.add_argument("--no-docs", action="store_true")
    a = ap.parse_args()
    results = {"latency": [], "idle": [], "loadavg_before": open("/proc/loadavg").read().split()[:3]}
    with tempfile.TemporaryDirectory() as tmp:
        for t in a.transports.split(","):
            log(f"latency over {t}: {a.silences} silences")
            results["latency"].append(latency_run(a.rvc, t, a.silences, tmp))
            log(json.dumps(results["latency"][-1]))
    if not a.skip_idle:
        for shape in ("100 silent topics", "1000 properties with deadlines"):
            for clock in ("wall", "off"):
                log(f"idle: {shape}, --clock {clock}")
                results["idle"].append(idle_run(a.rvc, shape, clock, a.idle_seconds))
                log(json.dumps(results["idle"][-1]))
    results["loadavg_after"] = open("/proc/loadavg").read().split()[:3]
    os.makedirs(os.path.join(ROOT, "bench", "results"), exist_ok=True)
    with open(os.path.join(ROOT, "bench", "results", "tick_bench.json"), "w") as f:
        json.dump(results, f, indent=1)
    text = table(results)
    print(text)
    if not a.no_docs:
        body = (f"Machine: {machine()}. Run of {time.strftime('%Y-%m-%d')}: {a.silences} silences per transport, "
                f"`once[0:{BOUND}]{{alive}}` on the wall clock, {SILENCE * 1000:.0f} ms of silence after each false "
                f"message. Load average (1, 5, 15 min) before: {' '.join(results['loadavg_before'])}, after: "
                f"{' '.join(results['loadavg_after'])} (other builds and test runs shared the 2 cores).\n\n" + text)
        path = os.path.join(ROOT, "docs", "performance.md")
        if f"<!-- {TAG}:begin -->" not in open(path).read():
            with open(path, "a") as f:
                f.write(HEADING)
        write_marked(path, TAG, body + "\n")


if __name__ == "__main__":
    main()
    sys.stdout.flush()
    sys.stderr.flush()
    # The peers' Zenoh session and DDS participant are still open: their binding's finalizers can
    # hang the interpreter's exit, and everything is written by now.
    os._exit(0)
