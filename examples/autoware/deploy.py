#!/usr/bin/env python3
"""The Autoware case study deployed in containers: setup 1 (one host, DDS) or setup 2 (two hosts:
DDS -> Zenoh bridge -> router -> monitor), as in the paper's Table 3. One command each:

  examples/autoware/deploy.py --setup 1 --scenario emergency
  examples/autoware/deploy.py --setup 2 --scenario fault-hazard-late --dense
  examples/autoware/deploy.py --setup 2 --rate-scale 10 --speed 1      # ten times the rates

What it does: writes the scenario's nine topics (vehicle.py), picks two free /24 subnets, starts the
compose profile (examples/autoware/compose.yml) in order (router, monitor, bridge, vehicle), samples
`docker stats` of every container while the vehicle publishes, waits for the monitor to end (idle
timeout after the vehicle stops), then checks the final verdicts against expected.yaml and counts:
per topic, messages sent by the vehicle, received by the monitor and the rate at which they arrived;
synchronized sets per second; messages lost (not received, or dropped late by the synchronizer);
CPU and RSS per container. Prints a JSON line (--json) or a table; removes every container and
network it created, also on failure. Needs the rvc image (deploy/docker/build.sh) and Docker
(scripts/docker-setup.sh).
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import threading
import time

import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(ROOT, "deploy", "compose"))
import rvc_compose as rc  # noqa: E402
import vehicle  # noqa: E402

COMPOSE = os.path.join(HERE, "compose.yml")
# The paper's Table 3: rate (msg/s) received in setup 1 and setup 2.
PAPER = {"steer": (25.10, 23.55), "gear": (25.02, 23.69), "mode": (24.95, 22.59), "turn": (24.88, 22.68),
         "hazard": (25.07, 23.70), "engage": (9.95, 7.95), "failsafe": (9.95, 7.84), "emergency": (10.05, 8.90),
         "status": (4.99, 2.97)}


def zenoh_key(topic):
    """zenoh-bridge-ros2dds's key for a ROS 2 topic: its name without the leading '/'."""
    return topic.lstrip("/")


class Deployment:
    def __init__(self, setup, scenario, dense=False, rate_scale=1.0, speed=1.0, image="rvc:latest", seed=None,
                 max_delay=1.0, idle=5.0):
        self.setup, self.scenario, self.dense = setup, scenario, dense
        self.rate_scale, self.speed, self.image, self.seed = rate_scale, speed, image, seed
        self.max_delay, self.idle = max_delay, idle
        self.project = "aw%d%d" % (setup, os.getpid() % 100000)
        self.compose = rc.compose_command()
        self.tmp = tempfile.mkdtemp(prefix="rvc-autoware-")
        self.data, self.out = os.path.join(self.tmp, "data"), os.path.join(self.tmp, "out")
        os.makedirs(self.data)
        os.makedirs(self.out)
        os.chmod(self.tmp, 0o755)
        os.chmod(self.data, 0o755)
        os.chmod(self.out, 0o777)  # the services run as uid 10001
        self.started = False
        self.samples = {}  # service -> [(cpu %, rss bytes)]

    # ------------------------------------------------------------ preparation
    def prepare(self):
        topics = yaml.safe_load(open(os.path.join(HERE, "topics.yaml")))
        self.topics = topics["topics"]
        scen = vehicle.Scenario(os.path.join(HERE, "scenarios", self.scenario + ".yaml"))
        msgs = vehicle.generate(scen, topics, rate_scale=self.rate_scale, seed=self.seed)
        self.sent_expected = {}
        for t in self.topics:
            rows = [m for _, m in msgs[t["name"]]]
            self.sent_expected[t["name"]] = len(rows)
            with open(os.path.join(self.data, t["name"] + ".jsonl"), "w") as f:
                f.writelines(json.dumps(m) + "\n" for m in rows)
        props = "properties-dense.yaml" if self.dense else "properties.yaml"
        with open(os.path.join(HERE, props)) as src, open(os.path.join(self.data, "properties.yaml"), "w") as dst:
            dst.write(src.read())
        net_a, net_b = rc.pick_subnet(), None
        net_b = rc.pick_subnet(skip=[net_a])
        self.net_a = ".".join(str(net_a.network_address).split(".")[:3])
        self.net_b = ".".join(str(net_b.network_address).split(".")[:3])
        peer = "%s.%d" % (self.net_a, 11 if self.setup == 1 else 12)
        lines = ["#!/bin/sh", "# The simulated vehicle: one ROS 2 publisher per topic (written by deploy.py)"]
        for t in self.topics:
            rate = t["rate"] * self.rate_scale * self.speed
            lines.append("rvc replay /data/%s.jsonl --to dds:%s --type %s --rate %g --no-progress "
                         "--wait-subscribers 1 --wait-timeout 120 --dds-interface %s.10 --dds-peer %s "
                         "> /out/replay-%s.json 2> /out/replay-%s.log &"
                         % (t["name"], t["topic"], t["type"], rate, self.net_a, peer, t["name"], t["name"]))
        lines += ["wait", ""]
        path = os.path.join(self.data, "vehicle.sh")
        with open(path, "w") as f:
            f.write("\n".join(lines))
        for name in os.listdir(self.data):
            os.chmod(os.path.join(self.data, name), 0o644)
        dds_in, zenoh_in, routes = [], [], []
        for t in self.topics:
            dds_in += ["--input", "%s=dds:%s" % (t["name"], t["topic"]), "--type", t["type"]]
            zenoh_in += ["--input", "%s=zenoh:%s" % (t["name"], zenoh_key(t["topic"])), "--type", t["type"]]
            routes += ["dds:" + t["topic"], "zenoh:" + zenoh_key(t["topic"])]
        bridge_types = [a for t in self.topics for a in ("--type", t["type"])]
        flags = ["--properties", "/data/properties.yaml", "--sync", "merge", "--max-delay", str(self.max_delay),
                 "--idle-timeout", str(self.idle), "--output", "file:/out/verdicts.jsonl",
                 "--stats-output", "file:/out/monitor-stats.json"] + (["--dense"] if self.dense else [])
        # the vehicle runs a shell script: it uses the image with a shell (deploy/docker/build.sh)
        debug = os.environ.get("RVC_DEBUG_IMAGE") or (
            self.image + "-debug" if ":" in self.image.rsplit("/", 1)[-1] else self.image + ":latest-debug")
        self.env = dict(os.environ, RVC_IMAGE=self.image, RVC_DEBUG_IMAGE=debug, AW_DATA=self.data, AW_OUT=self.out, AW_NET_A=self.net_a,
                        AW_NET_B=self.net_b, AW_INPUTS_DDS=" ".join(dds_in), AW_INPUTS_ZENOH=" ".join(zenoh_in),
                        AW_BRIDGE_ROUTES=" ".join(routes + bridge_types), AW_MONITOR_FLAGS=" ".join(flags))

    def compose_cmd(self, *args, check=True, timeout=300):
        cmd = self.compose + ["-p", self.project, "-f", COMPOSE, "--profile", "setup%d" % self.setup] + list(args)
        r = subprocess.run(cmd, env=self.env, capture_output=True, text=True, timeout=timeout)
        if check and r.returncode != 0:
            raise rc.DeployError("%s failed: %s" % (" ".join(args), r.stderr[-2000:]))
        return r

    def container(self, service):
        return self.compose_cmd("ps", "-q", service).stdout.strip()

    def wait_log(self, service, pattern, timeout=60):
        cid, end = self.container(service), time.time() + timeout
        while time.time() < end:
            r = subprocess.run(["docker", "logs", cid], capture_output=True, text=True)
            if re.search(pattern, r.stdout + r.stderr):
                return
            time.sleep(0.2)
        raise rc.DeployError("%s: no '%s' in its log within %d s" % (service, pattern, timeout))

    # ------------------------------------------------------------ run
    def services(self):
        return ["monitor1", "vehicle"] if self.setup == 1 else ["router", "monitor2", "bridge", "vehicle"]

    def sample_stats(self, stop):
        names = {}
        while not stop.is_set():
            r = subprocess.run(["docker", "stats", "--no-stream", "--format", "{{.Name}}\t{{.CPUPerc}}\t{{.MemUsage}}"],
                               capture_output=True, text=True)
            for line in r.stdout.splitlines():
                name, cpu, mem = (line.split("\t") + ["", "", ""])[:3]
                if not name.startswith(self.project):
                    continue
                service = names.setdefault(name, re.sub(r"^%s[_-]|[_-]\d+$" % self.project, "", name))
                rss = parse_size(mem.split("/")[0])
                try:
                    self.samples.setdefault(service, []).append((float(cpu.rstrip("%")), rss))
                except ValueError:
                    pass
            stop.wait(0.5)

    def run(self, timeout=600):
        self.prepare()
        stop = threading.Event()
        sampler = threading.Thread(target=self.sample_stats, args=(stop,), daemon=True)
        try:
            self.started = True
            for s in self.services():
                self.compose_cmd("up", "-d", "--no-deps", s)
                if s == "router":
                    self.wait_log(s, r"listening on")
                if s.startswith("monitor"):
                    self.wait_log(s, r"rvc monitor:")
            sampler.start()
            mon = "monitor%d" % self.setup
            cid = self.container(mon)
            code = int(subprocess.run(["docker", "wait", cid], capture_output=True, text=True,
                                      timeout=timeout).stdout.strip())
            log = subprocess.run(["docker", "logs", cid], capture_output=True, text=True).stderr
            stop.set()
            sampler.join(timeout=10)
            if self.setup == 2:  # the bridge runs until stopped; its counts come at exit
                bid = self.container("bridge")
                subprocess.run(["docker", "stop", "-t", "5", bid], capture_output=True)
                blog = subprocess.run(["docker", "logs", bid], capture_output=True, text=True)
                lines = [l for l in blog.stdout.splitlines() if l.startswith("{")]
                self.bridge = json.loads(lines[-1]) if lines else None
            return self.result(code, log)
        finally:
            stop.set()
            self.down()

    def down(self):
        if self.started:
            self.compose_cmd("down", "-v", "--remove-orphans", "-t", "3", check=False)
            self.started = False

    # ------------------------------------------------------------ results
    def result(self, code, log):
        stats = json.loads(open(os.path.join(self.out, "monitor-stats.json")).read().splitlines()[-1])
        verdicts = open(os.path.join(self.out, "verdicts.jsonl")).read()
        got = {p: "held" if v else "violated" for p, (v, _) in vehicle.final_verdicts(verdicts).items()}
        expected = yaml.safe_load(open(os.path.join(HERE, "expected.yaml")))["scenarios"][self.scenario]
        sync = stats.get("sync", {})
        by_input = {i["name"]: i for i in sync.get("inputs", [])}
        topics, seconds = [], 0.0
        for t in self.topics:
            rep = {}
            try:
                rep = json.loads(open(os.path.join(self.out, "replay-%s.json" % t["name"])).read().splitlines()[-1])
            except (OSError, IndexError, ValueError):
                pass
            i = by_input.get(t["name"], {})
            secs = rep.get("seconds") or 0.0
            seconds = max(seconds, secs)
            late = (i.get("dropped") or {}).get("late", 0)
            topics.append({"name": t["name"], "type": t["type"], "rate": t["rate"] * self.rate_scale * self.speed,
                           "sent": rep.get("sent", 0), "received": i.get("received", 0), "late": late,
                           "rate_received": i.get("received", 0) / secs if secs else 0.0})
        sent = sum(t["sent"] for t in topics)
        received = sum(t["received"] for t in topics)
        lost = sent - received + sum(t["late"] for t in topics) + stats.get("gaps", 0)
        resources = {s: {"cpu_mean_pct": sum(c for c, _ in v) / len(v), "cpu_max_pct": max(c for c, _ in v),
                         "rss_max_mb": max(r for _, r in v) / 1e6} for s, v in self.samples.items() if v}
        return {"setup": self.setup, "scenario": self.scenario, "dense": self.dense, "rate_scale": self.rate_scale,
                "speed": self.speed, "monitor_exit": code, "verdicts": got, "expected": expected,
                "verdicts_ok": got == expected, "topics": topics, "sent": sent, "received": received, "lost": lost,
                "sets": sync.get("sets", 0), "sets_per_s": sync.get("sets", 0) / seconds if seconds else 0.0,
                "seconds": seconds, "resources": resources, "bridge": getattr(self, "bridge", None),
                "rejected": stats.get("rejected", 0), "monitor_log": log[-1500:]}


def parse_size(text):
    m = re.match(r"\s*([\d.]+)\s*([KMGT]?i?B)", text)
    if not m:
        return 0.0
    mult = {"B": 1, "KiB": 1024, "MiB": 1024**2, "GiB": 1024**3, "kB": 1e3, "KB": 1e3, "MB": 1e6, "GB": 1e9}
    return float(m.group(1)) * mult.get(m.group(2), 1)


def table(results):
    """Table 3 side by side with the paper's: rate received per topic in each setup."""
    by = {(r["setup"]): r for r in results}
    head = "| topic | type | rate (Hz) | paper setup 1 | paper setup 2 |" + "".join(
        " rvc setup %d |" % s for s in sorted(by)) + "\n|---|---|---:|---:|---:|" + "---:|" * len(by)
    rows = [head]
    first = results[0]
    for k, t in enumerate(first["topics"]):
        p1, p2 = PAPER[t["name"]]
        cells = "".join(" %.2f |" % by[s]["topics"][k]["rate_received"] for s in sorted(by))
        rows.append("| %s | %s | %g | %.2f | %.2f |%s" % (t["name"], t["type"].split("/")[-1], t["rate"], p1, p2, cells))
    return "\n".join(rows) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--setup", type=int, choices=[1, 2], default=1)
    ap.add_argument("--scenario", default="emergency")
    ap.add_argument("--dense", action="store_true", help="dense-time properties (properties-dense.yaml)")
    ap.add_argument("--rate-scale", type=float, default=1.0, help="multiply every topic's rate (load)")
    ap.add_argument("--speed", type=float, default=1.0, help="publish this much faster than the stamps")
    ap.add_argument("--image", default=os.environ.get("RVC_IMAGE", "rvc:latest"))
    ap.add_argument("--json", action="store_true", help="print the result as one JSON line")
    args = ap.parse_args()
    d = Deployment(args.setup, args.scenario, args.dense, args.rate_scale, args.speed, args.image)
    res = d.run()
    if args.json:
        print(json.dumps(res))
    else:
        print(table([res]))
        print("verdicts %s expected.yaml; sent %d, received %d, lost %d; %d sets (%.1f/s); monitor exit %d"
              % ("equal" if res["verdicts_ok"] else "DIFFER from", res["sent"], res["received"], res["lost"],
                 res["sets"], res["sets_per_s"], res["monitor_exit"]))
        for s, r in sorted(res["resources"].items()):
            print("  %-9s CPU mean %5.1f %% max %5.1f %%, RSS max %6.1f MB" % (s, r["cpu_mean_pct"], r["cpu_max_pct"],
                                                                               r["rss_max_mb"]))
    sys.exit(0 if res["verdicts_ok"] and res["lost"] == 0 else 1)


if __name__ == "__main__":
    main()
