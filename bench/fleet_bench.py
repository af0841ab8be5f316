#!/usr/bin/env python3
"""Monitor groups over a fleet (docs/fleet.md, docs/performance.md "Fleet"): scale-out and failover.

  python3 bench/fleet_bench.py scale    [--rvc RVC] [--out FILE]
  python3 bench/fleet_bench.py failover [--rvc RVC] [--out FILE] [--kills 20]

Three `rvc router`s in a mesh on loopback, the simulated Autoware fleet (examples/autoware/fleet.py,
one process, vehicles spread over the routers), `rvc monitor --group bench --shard-by 'fleet/*'`
replicas (the ten Table-3 properties, nine typed inputs merged per vehicle), each a client of a
router (round robin).

scale: 100 and 1,000 vehicles x 1, 2, 4 replicas. The simulator publishes as fast as the network
  takes the samples (reliable, blocking): the figure is what the group sustained, next to the
  vehicles' own Table-3 rate (159 msg/s each). Per replica: CPU seconds (wait4 rusage), messages
  received and checked; "projected per core" = messages of the fleet a replica handles per CPU
  second (received/CPU s: each replica receives the whole key space and checks its share).
failover: 3 replicas, 20 vehicles at 1x, kills one replica (SIGKILL) every ~2 s, round robin,
  restarting it under a new member id; per kill the time from the kill to the survivors' takeover
  line (the replay and the first verdict of the new owner follow in the same engine step), and
  the messages each takeover replayed from its window.
Results: printed and written as JSON to --out (default /tmp/rvc_fleet_bench.json).
"""
import argparse
import json
import os
import random
import signal
import socket
import statistics
import subprocess
import sys
import threading
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
EXAMPLE = os.path.join(ROOT, "examples", "autoware")
sys.path.insert(0, EXAMPLE)
import fleet as fleet_sim  # noqa: E402
import vehicle  # noqa: E402


def free_port():
    for _ in range(200):
        port = random.randint(20000, 29999)
        with socket.socket() as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    raise RuntimeError("no free port")


def ep(port):
    return f"tcp/127.0.0.1:{port}"


class Proc:
    def __init__(self, args):
        self.args = args
        self.p = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        self.lines = []  # (monotonic time read, line)
        self.cv = threading.Condition()
        self.rusage = None
        threading.Thread(target=self._pump, daemon=True).start()

    def _pump(self):
        for line in self.p.stderr:
            with self.cv:
                self.lines.append((time.monotonic(), line.rstrip("\n")))
                self.cv.notify_all()

    def wait_for(self, text, after=0.0, timeout=60):
        end = time.monotonic() + timeout
        with self.cv:
            while True:
                for t, line in self.lines:
                    if t >= after and text in line:
                        return t, line
                if time.monotonic() > end:
                    raise RuntimeError(f"'{text}' not seen from {self.args[:2]}: {self.lines[-5:]}")
                self.cv.wait(0.1)

    def reap(self, timeout=300):
        """Waits for the exit and keeps its CPU time (wait4's rusage)."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            pid, status, ru = os.wait4(self.p.pid, os.WNOHANG)
            if pid:
                self.rusage = ru
                self.p.returncode = os.waitstatus_to_exitcode(status)
                return
            time.sleep(0.05)
        raise RuntimeError(f"{self.args[:2]} did not end")

    def counters(self):
        with self.cv:
            lines = [line for _, line in self.lines if line.startswith('{"input"')]
        return json.loads(lines[-1]) if lines else None

    def stop(self):
        if self.p.poll() is None:
            self.p.kill()
            self.p.wait()


def mesh(rvc, procs):
    ports = [free_port() for _ in range(3)]
    for i, port in enumerate(ports):
        args = [rvc, "router", "--listen", ep(port), "--no-multicast-scouting"]
        for earlier in ports[:i]:
            args += ["--connect", ep(earlier)]
        procs.append(Proc(args))
        procs[-1].wait_for("rvc router")
    return ports


def replica(rvc, name, port, vehicles, extra=()):
    topics = vehicle.load_topics()
    # --shard-subscribe owned: a replica sees only its shards' end-of-stream markers, so it ends
    # at --idle-timeout (after the simulator's plan and settle: 15 s; idle CPU is negligible).
    end = (["--idle-timeout", "15"] if "owned" in extra else
           ["--exit-on-eos", "--publishers", str(vehicles), "--idle-timeout", "300"])
    return Proc([rvc, "monitor", *fleet_sim.monitor_flags(topics), "--sync", "merge",
                 "--properties", os.path.join(EXAMPLE, "properties.yaml"), "--group", "bench",
                 "--shard-by", "fleet/*", "--member", name, *end,
                 "--mode", "client", "--connect", ep(port), "--no-multicast-scouting",
                 "-o", "file:/dev/null", *extra])


def simulator(ports, vehicles, duration, speed, loops=1, cache=None):
    args = [sys.executable, os.path.join(EXAMPLE, "fleet.py"), "run", "--vehicles", str(vehicles),
            "--duration", str(duration), "--speed", str(speed), "--loop", str(loops), "--settle", "5"]
    for p in ports:
        args += ["--connect", ep(p)]
    if cache:
        args += ["--plan-cache", cache]
    return Proc(args)


def scale(rvc, sizes=((100, 10), (1000, 1.2)), replicas=(1, 2, 4), extra=()):
    results = []
    for vehicles, duration in sizes:
        cache = f"/tmp/rvc_fleet_bench_plan_{vehicles}_{duration}.pickle"
        for n in replicas:
            procs = []
            try:
                ports = mesh(rvc, procs)
                reps = [replica(rvc, f"r{i}", ports[i % 3], vehicles, extra) for i in range(n)]
                procs += reps
                for r in reps:
                    r.wait_for(f"members {n}")
                sim = simulator(ports, vehicles, duration, 0, cache=cache)
                procs.append(sim)
                sim.reap(600)
                for r in reps:
                    r.reap(300)
                row = {"vehicles": vehicles, "replicas": n, "flags": list(extra), "replica": []}
                firsts, dones, total = [], [], 0
                for r in reps:
                    c = r.counters()
                    cpu = r.rusage.ru_utime + r.rusage.ru_stime
                    firsts.append(c["first_at"])
                    dones.append(c["done_at"])
                    total += c["checked"]
                    row["replica"].append({"cpu_s": round(cpu, 2), "received": c["received"], "checked": c["checked"],
                                           "gaps": c["gaps"], "rss_mb": round(r.rusage.ru_maxrss / 1024, 1),
                                           "received_per_cpu_s": round(c["received"] / cpu),
                                           "checked_per_cpu_s": round(c["checked"] / cpu) if c["checked"] else 0})
                span = max(dones) - min(firsts)
                row["messages"] = row["replica"][0]["received"]
                row["checked_total"] = total
                row["seconds"] = round(span, 2)
                row["group_msgs_per_s"] = round(total / span)
                # The simulator's own rate (reliable, blocking: the slowest replica's pace); a
                # replica ending at --idle-timeout has done_at 15 s late, so this is the figure
                # the two --shard-subscribe modes are compared by.
                with sim.cv:
                    sent = [line for _, line in sim.lines if "fleet: sent" in line]
                if sent:
                    row["sim_msgs_per_s"] = int(sent[-1].split("(")[1].split("/s")[0])
                if "owned" in extra:
                    del row["group_msgs_per_s"], row["seconds"]
                row["offered_vehicle_rate"] = vehicles * 159
                results.append(row)
                print(json.dumps(row), flush=True)
            finally:
                for p in procs:
                    p.stop()
    return results


def failover(rvc, kills):
    vehicles = 20
    procs = []
    out = {"kills": []}
    try:
        ports = mesh(rvc, procs)
        live = {f"m{i}": replica(rvc, f"m{i}", ports[i], vehicles) for i in range(3)}
        procs += live.values()
        for r in live.values():
            r.wait_for("members 3")
        sim = simulator(ports, vehicles, None or 20, 1, loops=3, cache="/tmp/rvc_fleet_bench_failover.pickle")
        procs.append(sim)
        sim.wait_for("fleet: 20 vehicles", timeout=300)
        time.sleep(3)
        gen = 0
        for k in range(kills):
            victim = sorted(live)[k % 3]
            proc = live.pop(victim)
            t_kill = time.monotonic()
            proc.p.send_signal(signal.SIGKILL)
            proc.p.wait()
            seen = []
            for name, r in live.items():
                t, line = r.wait_for(f"left: {victim}", after=t_kill, timeout=30)
                replayed = int(line.split("(")[2].split(" ")[0]) if "messages replayed" in line else 0
                taken = int(line.split("took over ")[1].split(" ")[0])
                seen.append({"member": name, "after_s": round(t - t_kill, 4), "taken": taken, "replayed": replayed})
            first = min(s["after_s"] for s in seen if s["taken"]) if any(s["taken"] for s in seen) else None
            out["kills"].append({"victim": victim, "first_takeover_s": first,
                                 "last_takeover_s": max(s["after_s"] for s in seen), "survivors": seen})
            print(json.dumps(out["kills"][-1]), flush=True)
            gen += 1
            name = f"{victim.split('-')[0]}-{gen}"
            fresh = replica(rvc, name, ports[k % 3], vehicles)
            procs.append(fresh)
            fresh.wait_for("members 3")
            live[name] = fresh
            time.sleep(1.0)
        firsts = [k["first_takeover_s"] for k in out["kills"] if k["first_takeover_s"] is not None]
        replays = [s["replayed"] for k in out["kills"] for s in k["survivors"] if s["taken"]]
        out["summary"] = {"kills": len(out["kills"]), "p50_s": round(statistics.median(firsts), 4),
                          "max_s": round(max(firsts), 4),
                          "replayed_per_takeover_median": statistics.median(replays) if replays else 0,
                          "replayed_per_takeover_max": max(replays) if replays else 0}
        print(json.dumps(out["summary"]), flush=True)
    finally:
        for p in procs:
            p.stop()
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=["scale", "failover", "window", "subscribe"],
                    help="window: 100 vehicles x 4 replicas with --replay-window 0 and the default, "
                         "the cost of keeping the window on the drop path; subscribe: 100 vehicles x 1/2/4 "
                         "replicas, --shard-subscribe all then owned")
    ap.add_argument("--rvc", default=os.path.join(ROOT, "build", "release", "rvc"))
    ap.add_argument("--out", default="/tmp/rvc_fleet_bench.json")
    ap.add_argument("--kills", type=int, default=20)
    args = ap.parse_args()
    if args.what == "scale":
        res = scale(args.rvc)
    elif args.what == "window":
        res = scale(args.rvc, ((100, 10),), (4,), ("--replay-window", "0")) + scale(args.rvc, ((100, 10),), (4,))
    elif args.what == "subscribe":
        res = (scale(args.rvc, ((100, 10),), (1, 2, 4), ("--shard-subscribe", "all")) +
               scale(args.rvc, ((100, 10),), (1, 2, 4), ("--shard-subscribe", "owned")))
    else:
        res = failover(args.rvc, args.kills)
    with open(args.out, "w") as f:
        json.dump({"what": args.what, "load": os.getloadavg(), "results": res}, f, indent=1)
    print(f"written {args.out}")


if __name__ == "__main__":
    main()
