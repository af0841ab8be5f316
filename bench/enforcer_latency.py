#!/usr/bin/env python3
"""Enforcer latency: how long from a violating message's publish to the enforcer's command (and to
the message's verdict) arriving at a subscriber, beside the network's own floor, in one run.

  python3 bench/enforcer_latency.py [--count 2000] [--rate 500] [--rvc PATH] [--transports zenoh,dds]

Per transport, three processes on one host:
- rvc monitor --input zenoh:bench/enf/in --spec '{ok}' --output zenoh:bench/enf/verdicts
              --on-violation 'p1=zenoh:bench/enf/cmd:{"stop":true}'   (dds: topics for the DDS run)
- a Python publisher (this script) sending --count messages at --rate per second: every 5th one
  violating ({"ok":false}, the others true, so every violating message is a violation onset and
  fires one command), each carrying its publish time (time.time_ns(), CLOCK_REALTIME: the same
  clock in every process on the host);
- a Python receiver (this script, --role receiver, another process) subscribed to the commands,
  the verdicts and, directly, the input itself, recording each sample's arrival time.
Latency of a violating message, from its publish time to the arrival of
  (a) its command (the k-th command answers the k-th violating message),
  (b) its verdict on the verdict key (the false verdict at its step: publish -> verdict),
  (c) the message itself at the receiver: the baseline, publisher -> plain subscriber, no rvc;
and "(a) - (c)", per message: what rvc adds. (a) and (b) cross the network twice (publisher -> rvc ->
receiver), (c) once, so the added latency holds one more hop as well as rvc's own work.

Writes bench/results/enforcer_latency.json, docs/img/enforcer-latency.png (the latency CDFs) and the
table into docs/performance.md between the enforcer-latency markers. A benchmark, not a test: it
asserts nothing. Loopback only: Zenoh on explicit tcp/127.0.0.1 ports with multicast scouting off;
DDS pinned to lo (rvc's default configuration; the XML of `rvc dds-config` for the Python peers).
"""
import argparse
import json
import math
import os
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from timescales_bench import machine, write_marked  # noqa: E402

TAG = "enforcer-latency"
EVERY = 5  # every 5th message violates
COMMAND = '{"stop":true}'
HEADING = """
## Enforcer latency (`python3 bench/enforcer_latency.py`)

Reproduce: `python3 bench/enforcer_latency.py` (2000 messages at 500/s per transport, about 15 s; the setup
is described in its docstring and in `docs/enforcer.md`).
"""
ZENOH_KEYS = {"in": "bench/enf/in", "verdicts": "bench/enf/verdicts", "cmd": "bench/enf/cmd"}
DDS_TOPICS = {"in": "/bench/enf/in", "verdicts": "/bench/enf/verdicts", "cmd": "/bench/enf/cmd"}
DDS_EOS = "\x04rvc-eos"


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    p = s.getsockname()[1]
    s.close()
    return p


def zenoh_session(listen=(), connect=()):
    import zenoh
    conf = zenoh.Config()
    conf.insert_json5("mode", '"peer"')
    conf.insert_json5("listen/endpoints", json.dumps(list(listen) or ["tcp/127.0.0.1:0"]))
    conf.insert_json5("connect/endpoints", json.dumps(list(connect)))
    conf.insert_json5("scouting/multicast/enabled", "false")
    return zenoh.open(conf)


def dds_string_type():
    from dataclasses import dataclass

    from cyclonedds.idl import IdlStruct

    @dataclass
    class String_(IdlStruct, typename="std_msgs::msg::dds_::String_"):
        data: str
    return String_


def dds_qos():
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.util import duration
    return Qos(Policy.Reliability.Reliable(duration(seconds=30)), Policy.History.KeepAll,
               Policy.Durability.Volatile)


# ---------------------------------------------------------------- receiver (its own process)

def receiver(args):
    """Records (arrival ns, payload, seq) per stream until each has ended; then writes them as JSON."""
    streams = {name: [] for name in ("in", "verdicts", "cmd")}
    ended = {name: threading.Event() for name in streams}
    keep = []
    if args.transport == "zenoh":
        s = zenoh_session(listen=[args.listen])

        def on(name):
            got, end = streams[name], ended[name]

            def cb(sample):
                t = time.time_ns()
                att = sample.attachment
                a = att.to_bytes() if att is not None else b""
                if len(a) >= 9 and a[8] & 1:
                    end.set()
                    return
                got.append((t, sample.payload.to_bytes(), a[:8]))
            return cb
        keep = [s.declare_subscriber(ZENOH_KEYS[n], on(n)) for n in streams]
    else:
        from cyclonedds.core import Listener
        from cyclonedds.domain import DomainParticipant
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic
        String_ = dds_string_type()
        dp = DomainParticipant(args.domain)

        def on(name):
            got, end = streams[name], ended[name]

            def cb(reader):
                t = time.time_ns()
                for smp in reader.take(N=256):
                    data = getattr(smp, "data", None)  # an InvalidSample (a writer going away) has none
                    if data is None:
                        continue
                    if data.startswith(DDS_EOS):
                        end.set()
                    else:
                        got.append((t, data.encode(), b""))
            return Listener(on_data_available=cb)
        keep = [DataReader(dp, Topic(dp, "rt" + DDS_TOPICS[n], String_), qos=dds_qos(), listener=on(n))
                for n in streams]
    print("ready", flush=True)
    deadline = time.time() + args.timeout
    for ev in ended.values():
        ev.wait(max(0.0, deadline - time.time()))
    time.sleep(0.2)
    out = {name: [(t, p.decode(), int.from_bytes(seq, "little") if seq else 0) for t, p, seq in list(got)]
           for name, got in streams.items()}
    out["ended"] = {name: ev.is_set() for name, ev in ended.items()}
    with open(args.out, "w") as f:
        json.dump(out, f)
    del keep


# ---------------------------------------------------------------- one run

class Pacer:
    def __init__(self, rate):
        self.period, self.t0 = 1.0 / rate, time.perf_counter()

    def wait(self, i):
        target = self.t0 + i * self.period
        while True:
            left = target - time.perf_counter()
            if left <= 0:
                return
            time.sleep(left if left > 0.002 else 0)


def message(i, violating):
    t = time.time_ns()
    return t, '{"ok":%s,"i":%d,"t_ns":%d}' % ("false" if violating else "true", i, t)


def start_receiver(transport, tmp, env, **kw):
    out = os.path.join(tmp, f"received-{transport}.json")
    cmd = [sys.executable, os.path.abspath(__file__), "--role", "receiver", "--transport", transport, "--out", out,
           "--timeout", str(kw.pop("timeout"))]
    for k, v in kw.items():
        cmd += [f"--{k}", str(v)]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, env=env)
    line = p.stdout.readline()
    if line.strip() != "ready":
        raise RuntimeError(f"receiver did not start: {line!r}")
    p.result = out
    return p


def wait_monitor_subscribed(mon):
    """rvc monitor prints 'rvc monitor: N property on URI -> ...' once it has subscribed to its input
    (after --wait-subscribers found the receiver on its verdict and command endpoints)."""
    for line in mon.stderr:
        if line.startswith("rvc monitor:"):
            return
        if line.strip():
            log("  rvc: " + line.rstrip())
    raise RuntimeError("rvc monitor ended before subscribing: exit %s" % mon.wait())


def run_zenoh(args, tmp):
    p_mon, p_rcv = free_port(), free_port()
    ep_mon, ep_rcv = f"tcp/127.0.0.1:{p_mon}", f"tcp/127.0.0.1:{p_rcv}"
    run_time = args.count / args.rate
    rcv = start_receiver("zenoh", tmp, None, listen=ep_rcv, timeout=run_time + 30)
    cmd = [args.rvc, "monitor", "--input", f"zenoh:{ZENOH_KEYS['in']}", "--spec", "{ok}", "--output",
           f"zenoh:{ZENOH_KEYS['verdicts']}", "--on-violation", f"p1=zenoh:{ZENOH_KEYS['cmd']}:{COMMAND}",
           "--exit-on-eos", "--wait-subscribers", "1", "--wait-timeout", "20",
           "--mode", "peer", "--listen", ep_mon, "--connect", ep_rcv, "--no-multicast-scouting"]
    if args.express:
        cmd.append("--express")
    log("[zenoh] " + " ".join(cmd[:10]) + " ...")
    mon = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    sent = []
    try:
        wait_monitor_subscribed(mon)
        s = zenoh_session(connect=[ep_mon, ep_rcv])
        pub = s.declare_publisher(ZENOH_KEYS["in"])
        deadline = time.time() + 20
        while not getattr(pub.matching_status, "matching", False) and time.time() < deadline:
            time.sleep(0.01)
        time.sleep(0.5)  # both subscriptions (rvc's and the receiver's) are declared; let them settle
        log(f"[zenoh] publishing {args.count} messages at {args.rate:g}/s (every {EVERY}th violating)")
        pacer = Pacer(args.rate)
        for i in range(args.count):
            pacer.wait(i)
            violating = i % EVERY == EVERY - 1
            t, payload = message(i, violating)
            pub.put(payload, attachment=struct.pack("<QB", i + 1, 0))
            sent.append((i, t, violating))
            if (i + 1) % max(1, args.count // 4) == 0:
                log(f"[zenoh]   {i + 1}/{args.count} sent")
        pub.put(b"", attachment=struct.pack("<QB", args.count, 1))
        _, err = mon.communicate(timeout=run_time + 60)
        rcv.wait(timeout=run_time + 60)
        s.close()
    finally:
        for p in (mon, rcv):
            if p.poll() is None:
                p.kill()
    return sent, err, mon.returncode, rcv.result


def run_dds(args, tmp):
    cfg = os.path.join(tmp, "cyclonedds.xml")
    subprocess.run([args.rvc, "dds-config", "-o", cfg], check=True)
    xml = open(cfg).read()
    if 'name="lo"' not in xml:
        raise RuntimeError("rvc dds-config did not pin CycloneDDS to lo")
    os.environ["CYCLONEDDS_URI"] = f"file://{cfg}"  # before any Python participant exists
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic
    String_ = dds_string_type()
    domain = 30 + os.getpid() % 50
    run_time = args.count / args.rate
    rcv = start_receiver("dds", tmp, dict(os.environ), domain=domain, timeout=run_time + 30)
    cmd = [args.rvc, "monitor", "--input", f"dds:{DDS_TOPICS['in']}", "--spec", "{ok}", "--output",
           f"dds:{DDS_TOPICS['verdicts']}", "--on-violation", f"p1=dds:{DDS_TOPICS['cmd']}:{COMMAND}",
           "--exit-on-eos", "--wait-subscribers", "1", "--wait-timeout", "20", "--domain", str(domain)]
    log("[dds]   " + " ".join(cmd[:10]) + " ...")
    mon = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    sent = []
    try:
        wait_monitor_subscribed(mon)
        dp = DomainParticipant(domain)
        writer = DataWriter(dp, Topic(dp, "rt" + DDS_TOPICS["in"], String_), qos=dds_qos())
        deadline = time.time() + 20
        while writer.get_publication_matched_status().current_count < 2 and time.time() < deadline:  # rvc + receiver
            time.sleep(0.01)
        time.sleep(0.3)
        log(f"[dds]   publishing {args.count} messages at {args.rate:g}/s (every {EVERY}th violating)")
        pacer = Pacer(args.rate)
        for i in range(args.count):
            pacer.wait(i)
            violating = i % EVERY == EVERY - 1
            t, payload = message(i, violating)
            writer.write(String_(data=payload))
            sent.append((i, t, violating))
            if (i + 1) % max(1, args.count // 4) == 0:
                log(f"[dds]     {i + 1}/{args.count} sent")
        writer.write(String_(data=f"{DDS_EOS} last={args.count} count={args.count}"))
        _, err = mon.communicate(timeout=run_time + 60)
        rcv.wait(timeout=run_time + 60)
        del writer, dp
    finally:
        for p in (mon, rcv):
            if p.poll() is None:
                p.kill()
    return sent, err, mon.returncode, rcv.result


# ---------------------------------------------------------------- analysis

def percentile(sorted_values, q):
    if not sorted_values:
        return float("nan")
    k = max(0, min(len(sorted_values) - 1, math.ceil(q * len(sorted_values)) - 1))
    return sorted_values[k]


def summary(values):
    v = sorted(values)
    return {"n": len(v), "p50": percentile(v, 0.50), "p90": percentile(v, 0.90), "p99": percentile(v, 0.99),
            "max": v[-1] if v else float("nan")}


def analyse(transport, sent, err, rc, received_path):
    with open(received_path) as f:
        rec = json.load(f)
    pub_ns = {i: t for i, t, _ in sent}
    violating = [i for i, _, v in sent if v]
    # (c) the input itself at the receiver
    base = {}
    for t, payload, _ in rec["in"]:
        i = json.loads(payload)["i"]
        base.setdefault(i, t)
    # (b) the false verdicts: discrete time = the message's step index
    verdict = {}
    for t, payload, _ in rec["verdicts"]:
        v = json.loads(payload)
        if not v["value"]:
            verdict.setdefault(v["time"], t)
    # (a) the k-th command answers the k-th violating message (Zenoh: its sequence number k; DDS, which
    # carries none on a std_msgs/String topic: the k-th command to arrive, reliable and in order)
    command = {}
    for k, (t, _, seq) in enumerate(rec["cmd"], 1):
        idx = (seq or k) - 1
        if 0 <= idx < len(violating):
            command.setdefault(violating[idx], t)
    us = lambda a, i: (a[i] - pub_ns[i]) / 1e3  # noqa: E731
    lat_c = [us(base, i) for i in violating if i in base]
    lat_b = [us(verdict, i) for i in violating if i in verdict]
    lat_a = [us(command, i) for i in violating if i in command]
    added = [us(command, i) - us(base, i) for i in violating if i in command and i in base]
    added_b = [us(verdict, i) - us(base, i) for i in violating if i in verdict and i in base]
    stats_lines = [l for l in err.splitlines() if l.startswith('{"input"')]
    stats = json.loads(stats_lines[-1]) if stats_lines else {}
    enforcer_line = next((l for l in err.splitlines() if "sent on violation" in l), "")
    return {
        "transport": transport, "messages": len(sent), "violating": len(violating), "monitor_exit": rc,
        "monitor_stats": stats, "enforcer": enforcer_line.strip(), "streams_ended": rec["ended"],
        "received": {"in": len(rec["in"]), "verdicts": len(rec["verdicts"]), "cmd": len(rec["cmd"])},
        "latency_us": {"command": summary(lat_a), "verdict": summary(lat_b), "baseline": summary(lat_c),
                       "added_command": summary(added), "added_verdict": summary(added_b)},
        "samples_us": {"command": lat_a, "verdict": lat_b, "baseline": lat_c},
    }


ROWS = [("baseline", "(c) publisher → plain Python subscriber (no rvc; the network's floor)"),
        ("verdict", "(b) violating message → its verdict (publish → verdict of rvc monitor)"),
        ("command", "(a) violating message → enforcer command"),
        ("added_verdict", "(b) − (c), per message: added by rvc"),
        ("added_command", "(a) − (c), per message: added by rvc")]


def render(results, args):
    out = [f"Machine: {machine()}. Run of {time.strftime('%Y-%m-%d')}: {args.count} messages at {args.rate:g}/s, "
           f"every {EVERY}th violating `{{ok}}` (each one an onset: {args.count // EVERY} commands); "
           f"`--debounce 0`{', rvc --express' if args.express else ''}. Latency from the publisher's "
           "`time.time_ns()` to the Python receiver's, microseconds, over the violating messages.\n",
           "| transport | latency | n | p50 | p90 | p99 | max |", "|---|---|---:|---:|---:|---:|---:|"]
    for r in results:
        for key, label in ROWS:
            s = r["latency_us"][key]
            out.append(f"| {r['transport']} | {label} | {s['n']} | {s['p50']:.0f} | {s['p90']:.0f} | "
                       f"{s['p99']:.0f} | {s['max']:.0f} |")
    out.append("")
    for r in results:
        st = r["monitor_stats"]
        out.append(f"- {r['transport']}: monitor received {st.get('received', '?')}/{r['messages']} "
                   f"(gaps {st.get('gaps', '?')}), exit {r['monitor_exit']}; receiver got {r['received']['cmd']} "
                   f"commands (of {r['violating']} onsets), {r['received']['verdicts']} verdicts, "
                   f"{r['received']['in']} input messages; \"{r['enforcer']}\"")
    return "\n".join(out) + "\n"


def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(results), figsize=(6.5 * len(results), 4.2), squeeze=False)
    for ax, r in zip(axes[0], results):
        for key, label, style in (("baseline", "(c) publisher → subscriber (no rvc)", ":"),
                                  ("verdict", "(b) → verdict (rvc monitor)", "--"),
                                  ("command", "(a) → enforcer command", "-")):
            v = sorted(r["samples_us"][key])
            if v:
                ax.plot(v, [(k + 1) / len(v) for k in range(len(v))], style, label=label, linewidth=1.6)
        ax.set_xscale("log")
        ax.set_xlabel("latency from the violating message's publish (µs, log)")
        ax.set_ylabel("fraction of violating messages")
        ax.set_title(f"{r['transport']}: {r['messages']} msgs at {r['rate']:g}/s, {r['violating']} onsets")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--count", type=int, default=2000, help="messages per run (default 2000)")
    ap.add_argument("--rate", type=float, default=500, help="messages per second (default 500)")
    ap.add_argument("--rvc", default=os.environ.get("RVC_BIN", os.path.join(ROOT, "build", "release", "rvc")))
    ap.add_argument("--transports", default="zenoh,dds", help="zenoh, dds or both (default; DDS skipped if the "
                    "rvc or the cyclonedds Python package lacks it)")
    ap.add_argument("--express", action="store_true", help="rvc monitor --express (Zenoh: no batching)")
    ap.add_argument("--no-docs", action="store_true", help="do not update docs/performance.md and the plot")
    # internal: the receiver process
    ap.add_argument("--role", default="main", choices=["main", "receiver"], help=argparse.SUPPRESS)
    ap.add_argument("--transport", help=argparse.SUPPRESS)
    ap.add_argument("--listen", help=argparse.SUPPRESS)
    ap.add_argument("--domain", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--out", help=argparse.SUPPRESS)
    ap.add_argument("--timeout", type=float, default=60, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.role == "receiver":
        return receiver(args)

    help_text = subprocess.run([args.rvc, "monitor", "--help"], capture_output=True, text=True).stdout
    wanted = [t.strip() for t in args.transports.split(",") if t.strip()]
    transports = []
    for t in wanted:
        if t == "zenoh" and "--connect" in help_text:
            transports.append(t)
        elif t == "dds" and "--domain" in help_text:
            try:
                import cyclonedds  # noqa: F401
                transports.append(t)
            except ImportError:
                log("[dds]   skipped: the cyclonedds Python package is not installed")
        else:
            log(f"[{t}] skipped: not built into {args.rvc}")
    results = []
    started = time.time()
    with tempfile.TemporaryDirectory(prefix="rvc-enf-bench-") as tmp:
        for t in transports:
            sent, err, rc, received = (run_zenoh if t == "zenoh" else run_dds)(args, tmp)
            r = analyse(t, sent, err, rc, received)
            r["rate"] = args.rate
            results.append(r)
            lat = r["latency_us"]
            log(f"[{t}] p50 command {lat['command']['p50']:.0f} us, verdict {lat['verdict']['p50']:.0f} us, "
                f"baseline {lat['baseline']['p50']:.0f} us; {r['received']['cmd']}/{r['violating']} commands; "
                f"{r['enforcer']}")
    md = render(results, args)
    print(md)
    res_dir = os.path.join(ROOT, "bench", "results")
    os.makedirs(res_dir, exist_ok=True)
    with open(os.path.join(res_dir, "enforcer_latency.json"), "w") as f:
        json.dump({"machine": machine(), "date": time.strftime("%Y-%m-%dT%H:%M:%S"), "count": args.count,
                   "rate": args.rate, "every": EVERY, "express": args.express, "rvc": args.rvc,
                   "seconds": round(time.time() - started, 1), "runs": results}, f, indent=1)
    if not args.no_docs:
        perf = os.path.join(ROOT, "docs", "performance.md")
        text = open(perf).read()
        if f"<!-- {TAG}:begin -->" not in text:
            with open(perf, "a") as f:
                f.write(HEADING)
        write_marked(perf, TAG, md)
        os.makedirs(os.path.join(ROOT, "docs", "img"), exist_ok=True)
        plot(results, os.path.join(ROOT, "docs", "img", "enforcer-latency.png"))
        log("wrote bench/results/enforcer_latency.json, docs/performance.md (enforcer-latency), "
            "docs/img/enforcer-latency.png")
    log(f"done in {time.time() - started:.1f} s")


if __name__ == "__main__":
    main()
