#!/usr/bin/env python3
"""Runs the paper's Fig. 3 container architectures (deploy/compose/compose.yml) in one network mode.

  rvc_compose.py run   --arch a --transport zenoh --mode bridge --trace T.jsonl --spec 'SPEC'
  rvc_compose.py up    ... (same options; leaves the containers running, prints the project name)
  rvc_compose.py down  --project NAME
  rvc_compose.py env   ... (prints the variables and the docker-compose commands, for manual use)
  rvc_compose.py modes (which network modes this machine can run, and why not)

Architectures: a (publisher + RV container), b (application + synchronizer placeholder + RV),
c (DDS publisher -> DDS->Zenoh bridge -> Zenoh router -> RV on Zenoh), d (application version of c).
Transports for a and b: zenoh, dds (c and d are always DDS -> Zenoh).
Modes: bridge, host, macvlan, ipvlan, shared (one network namespace).

Network safety: networked modes use a Docker network with an explicit /24 in 172.28.0.0/17 that
is internal (bridge) or whose parent is a veth pair created here for the run (macvlan, ipvlan),
never the machine's interface; host and shared modes keep every endpoint on 127.0.0.1 / lo.
Zenoh endpoints are explicit, multicast scouting off; DDS is pinned to the container's own
address (or lo) with unicast discovery. Everything created is removed again, also on failure.

`run` prints one JSON line: the monitor's stats, the replay summary, the monitor's exit code and
seconds = monitor done_at - replay started_at (first publish to last verdict).
Used as a library by tests/integration/containers and deploy/experiments/table2.py.
"""
import argparse
import ipaddress
import json
import os
import random
import re
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
ARCHS = ("a", "b", "c", "d")
MODES = ("bridge", "host", "macvlan", "ipvlan", "shared")
TRANSPORTS = ("zenoh", "dds")
NETWORKED = ("bridge", "macvlan", "ipvlan")
POOL = ipaddress.ip_network("172.28.0.0/17")  # docker-setup.sh keeps dockerd's own pools out of it
ZN = "--no-multicast-scouting"



def debug_image(image):
    """The image with a shell beside IMAGE (deploy/docker/build.sh makes both): rvc:latest ->
    rvc:latest-debug. RVC_DEBUG_IMAGE overrides. The runtime image has no shell and no sleep."""
    if os.environ.get("RVC_DEBUG_IMAGE"):
        return os.environ["RVC_DEBUG_IMAGE"]
    return image + "-debug" if ":" in image.rsplit("/", 1)[-1] else image + ":latest-debug"

class Unsupported(Exception):
    """This machine cannot run the requested mode (the message says why)."""


class DeployError(Exception):
    pass


def sh(cmd, check=True, timeout=120, **kw):
    return subprocess.run(cmd, check=check, timeout=timeout, capture_output=True, text=True, **kw)


def root_cmd(cmd):
    return cmd if os.geteuid() == 0 else ["sudo", "-n"] + cmd


def compose_command():
    """`docker compose` (v2) when present, else docker-compose (1.29). RVC_COMPOSE=v1 or v2 insists on one."""
    want = os.environ.get("RVC_COMPOSE", "")
    cands = {"v1": [["docker-compose"]], "v2": [["docker", "compose"]]}.get(
        want, [["docker", "compose"], ["docker-compose"]])
    for cmd in cands:
        if shutil.which(cmd[0]) and subprocess.run(cmd + ["version"], capture_output=True).returncode == 0:
            return cmd
    if want in ("v1", "v2"):
        raise Unsupported("RVC_COMPOSE=%s but %s is not installed (%s)" % (
            want, "docker-compose" if want == "v1" else "`docker compose`",
            "scripts/docker-setup.sh" if want == "v1" else "scripts/compose-v2.sh"))
    raise Unsupported("neither `docker compose` nor docker-compose is installed (scripts/docker-setup.sh)")


def docker_available():
    """None when Docker can run containers here, else the reason."""
    if not shutil.which("docker"):
        return "no docker client (scripts/docker-setup.sh installs Debian's docker.io)"
    r = subprocess.run(["docker", "info"], capture_output=True, text=True)
    if r.returncode != 0:
        return "dockerd is not reachable: " + (r.stderr.strip().splitlines() or ["?"])[-1]
    return None


def used_subnets():
    nets = []
    ids = sh(["docker", "network", "ls", "-q"]).stdout.split()
    if ids:
        out = sh(["docker", "network", "inspect", "-f", "{{range .IPAM.Config}}{{.Subnet}} {{end}}"] + ids).stdout
        for s in out.split():
            try:
                nets.append(ipaddress.ip_network(s, strict=False))
            except ValueError:
                pass
    for line in sh(["ip", "-4", "route", "show", "table", "all"], check=False).stdout.splitlines():
        tok = line.split()
        if tok and tok[0] not in ("default", "broadcast", "local") and re.match(r"^\d", tok[0]):
            try:
                nets.append(ipaddress.ip_network(tok[0], strict=False))
            except ValueError:
                pass
        elif len(tok) > 1 and tok[0] in ("broadcast", "local") and re.match(r"^\d", tok[1]):
            try:
                nets.append(ipaddress.ip_network(tok[1], strict=False))
            except ValueError:
                pass
    return nets


def pick_subnet(skip=()):
    used = used_subnets()
    cands = [n for n in POOL.subnets(new_prefix=24) if n.network_address.packed[2] != 0]
    random.shuffle(cands)
    for n in cands:
        if n not in skip and not any(n.overlaps(u) for u in used):
            return n
    raise DeployError("no free /24 left in %s" % POOL)


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    p = s.getsockname()[1]
    s.close()
    return p


def link_exists(name):
    return subprocess.run(["ip", "link", "show", name], capture_output=True).returncode == 0


def ipvlan_supported(parent):
    """None if an ipvlan link can be created on `parent`, else the kernel's error."""
    test = parent + "t"
    r = subprocess.run(root_cmd(["ip", "link", "add", test, "link", parent, "type", "ipvlan", "mode", "l2"]),
                       capture_output=True, text=True)
    if r.returncode == 0:
        subprocess.run(root_cmd(["ip", "link", "del", test]), capture_output=True)
        return None
    return r.stderr.strip() or "ip link add type ipvlan failed"


class Deployment:
    """One architecture in one network mode: plan (variables), up, wait, down."""

    def __init__(self, arch="a", transport="zenoh", mode="bridge", trace=None, spec=None, properties=None,
                 image=None, monitor_flags="--all", monitor_output="file:/out/verdicts.jsonl", out_dir=None,
                 project=None, domain=None, wait_timeout=60, replay_flags="", log=None):
        if arch not in ARCHS:
            raise ValueError("arch must be one of %s" % ", ".join(ARCHS))
        if mode not in MODES:
            raise ValueError("mode must be one of %s" % ", ".join(MODES))
        if arch in ("a", "b") and transport not in TRANSPORTS:
            raise ValueError("transport must be one of %s" % ", ".join(TRANSPORTS))
        self.arch, self.mode = arch, mode
        self.transport = transport if arch in ("a", "b") else "dds-zenoh"
        self.trace = os.path.abspath(trace) if trace else None
        self.spec, self.properties = spec, properties
        self.image = image or os.environ.get("RVC_IMAGE", "rvc:latest")
        self.monitor_flags, self.monitor_output = monitor_flags, monitor_output
        self.own_out = out_dir is None
        self.out_dir = out_dir
        self.project = project or "rvc%s%s%d%04d" % (arch, mode[:3], os.getpid() % 100000, random.randrange(10000))
        self.domain = domain if domain is not None else random.randrange(150, 230)
        self.wait_timeout, self.replay_flags = wait_timeout, replay_flags
        self.log = log or (lambda msg: print("rvc-compose: " + msg, file=sys.stderr))
        self.compose = None
        self.links = []  # veth ends created for this deployment
        self.subnet = None
        self.env = None
        self.started = False

    # -- plan ---------------------------------------------------------------------------------
    def services(self):
        holder = ["netns"] if self.mode == "shared" else []  # owner of the shared namespace
        return holder + {"a": ["monitor", "publisher"], "b": ["monitor", "sync", "app"],
                "c": ["router", "monitor", "bridge", "publisher"],
                "d": ["router", "monitor", "bridge", "sync", "app"]}[self.arch]

    def compose_files(self):
        return ["-f", os.path.join(HERE, "compose.yml"), "-f", os.path.join(HERE, "net-%s.yml" % self.mode)]

    def base_cmd(self):
        return self.compose + ["-p", self.project] + self.compose_files() + ["--profile", self.arch]

    def plan(self, subnet=None):
        """Computes every compose variable for this (architecture, transport, mode)."""
        svc = ("monitor", "publisher", "router", "bridge", "app", "sync")
        env = {"RVC_IMAGE": self.image, "RVC_DEBUG_IMAGE": debug_image(self.image), "RVC_WAIT_TIMEOUT": str(self.wait_timeout),
               "RVC_MONITOR_FLAGS": self.monitor_flags, "RVC_MONITOR_OUTPUT": self.monitor_output,
               "RVC_REPLAY_FLAGS": self.replay_flags}
        if self.trace:
            env.update(RVC_DATA=os.path.dirname(self.trace), RVC_TRACE=os.path.basename(self.trace),
                       RVC_APP_TRACE=os.path.basename(self.trace))
        if self.out_dir:
            env["RVC_OUT"] = self.out_dir
        env["RVC_PROPS"] = "/out/props.yaml"
        if self.mode in NETWORKED:
            self.subnet = subnet or pick_subnet()
            hosts = list(self.subnet.hosts())
            ip = {s: str(hosts[9 + i]) for i, s in enumerate(svc)}  # .10 .. .15
            env["RVC_SUBNET"] = str(self.subnet)
            for s in svc:
                env["RVC_IP_" + s.upper()] = ip[s]
            port = {"monitor": 7447, "router": 7447, "sync": 7448}
            octet = self.subnet.network_address.packed[2]
            env["RVC_MACVLAN_PARENT"] = "rvcmv%d" % octet
            env["RVC_IPVLAN_PARENT"] = "rvciv%d" % octet
        else:
            ip = {s: "127.0.0.1" for s in svc}
            port = {"monitor": free_port(), "router": free_port(), "sync": free_port()}
        ep = {s: "tcp/%s:%d" % (ip[s], port[s]) for s in port}

        def dds(me, *peers):
            if self.mode in NETWORKED:
                return "--domain %d --dds-interface %s %s" % (
                    self.domain, ip[me], " ".join("--dds-peer " + ip[p] for p in peers))
            return "--domain %d --dds-interface lo" % self.domain

        a, t = self.arch, self.transport
        if a == "a" and t == "zenoh":
            env.update(RVC_MONITOR_INPUT="zenoh:rv/timescales", RVC_PUBLISH_TO="zenoh:rv/timescales",
                       RVC_MONITOR_NET="--mode peer --listen %s %s" % (ep["monitor"], ZN),
                       RVC_PUBLISHER_NET="--mode peer --connect %s %s" % (ep["monitor"], ZN))
        elif a == "a":
            env.update(RVC_MONITOR_INPUT="dds:/rv/timescales", RVC_PUBLISH_TO="dds:/rv/timescales",
                       RVC_MONITOR_NET=dds("monitor", "publisher"), RVC_PUBLISHER_NET=dds("publisher", "monitor"))
        elif a == "b" and t == "zenoh":
            env.update(RVC_APP_TOPIC="zenoh:app/status", RVC_SYNC_TOPIC="zenoh:rv/timescales",
                       RVC_MONITOR_INPUT="zenoh:rv/timescales",
                       RVC_MONITOR_NET="--mode peer --listen %s %s" % (ep["monitor"], ZN),
                       RVC_SYNC_NET="--mode peer --listen %s --connect %s %s" % (ep["sync"], ep["monitor"], ZN),
                       RVC_APP_NET="--mode peer --connect %s %s" % (ep["sync"], ZN))
        elif a == "b":
            env.update(RVC_APP_TOPIC="dds:/app/status", RVC_SYNC_TOPIC="dds:/rv/timescales",
                       RVC_MONITOR_INPUT="dds:/rv/timescales", RVC_MONITOR_NET=dds("monitor", "sync", "app"),
                       RVC_SYNC_NET=dds("sync", "monitor", "app"), RVC_APP_NET=dds("app", "monitor", "sync"))
        else:
            client = "--mode client --connect %s %s" % (ep["router"], ZN)
            env.update(RVC_ROUTER_NET="--listen %s %s" % (ep["router"], ZN),
                       RVC_MONITOR_INPUT="zenoh:rv/timescales", RVC_MONITOR_NET=client,
                       RVC_BRIDGE_FROM="dds:/rv/timescales", RVC_BRIDGE_TO="zenoh:rv/timescales")
            if a == "c":
                env.update(RVC_PUBLISH_TO="dds:/rv/timescales", RVC_PUBLISHER_NET=dds("publisher", "bridge"),
                           RVC_BRIDGE_NET=client + " " + dds("bridge", "publisher"))
            else:
                env.update(RVC_APP_TOPIC="dds:/app/status", RVC_SYNC_TOPIC="dds:/rv/timescales",
                           RVC_APP_NET=dds("app", "sync", "bridge"), RVC_SYNC_NET=dds("sync", "app", "bridge"),
                           RVC_BRIDGE_NET=client + " " + dds("bridge", "app", "sync"))
        self.env = env
        return env

    # -- network links ------------------------------------------------------------------------
    def make_parent(self, name):
        if link_exists(name):
            raise DeployError("link %s already exists (another run, or left over: ip link del %s)" % (name, name))
        sh(root_cmd(["ip", "link", "add", name, "type", "veth", "peer", "name", name + "p"]))
        self.links.append(name)
        for n in (name, name + "p"):
            subprocess.run(root_cmd(["sysctl", "-qw", "net.ipv6.conf.%s.disable_ipv6=1" % n]), capture_output=True)
            sh(root_cmd(["ip", "link", "set", n, "up"]))

    def setup_links(self):
        if self.mode == "macvlan":
            self.make_parent(self.env["RVC_MACVLAN_PARENT"])
        elif self.mode == "ipvlan":
            parent = self.env["RVC_IPVLAN_PARENT"]
            self.make_parent(parent)
            err = ipvlan_supported(parent)
            if err:
                self.remove_links()
                raise Unsupported("[platform] ipvlan: this kernel cannot create ipvlan links (%s); mode skipped" % err)

    def remove_links(self):
        for name in self.links:
            subprocess.run(root_cmd(["ip", "link", "del", name]), capture_output=True)
        self.links = []

    # -- lifecycle ----------------------------------------------------------------------------
    def prepare(self):
        why = docker_available()
        if why:
            raise Unsupported(why)
        self.compose = compose_command()
        if subprocess.run(["docker", "image", "inspect", self.image], capture_output=True).returncode != 0:
            raise DeployError("image %s not found: build it with deploy/docker/build.sh" % self.image)
        if self.out_dir is None:
            self.out_dir = tempfile.mkdtemp(prefix="rvc-compose-")
        os.makedirs(self.out_dir, exist_ok=True)
        os.chmod(self.out_dir, 0o777)  # the containers run as uid 10001
        props = os.path.join(self.out_dir, "props.yaml")
        if self.properties:
            shutil.copyfile(self.properties, props)
        elif self.spec:
            with open(props, "w") as f:
                f.write("properties:\n  - name: p1\n    spec: %s\n" % json.dumps(self.spec))
        os.chmod(props, 0o644)
        for name in ("verdicts.jsonl", "monitor-stats.json"):
            try:
                os.unlink(os.path.join(self.out_dir, name))
            except FileNotFoundError:
                pass
        if not self.env:
            self.plan()
        self.env["RVC_OUT"] = self.out_dir

    def run_compose(self, *args, timeout=180, check=True):
        env = dict(os.environ)
        env.update(self.env)
        r = subprocess.run(self.base_cmd() + list(args), env=env, capture_output=True, text=True, timeout=timeout)
        if check and r.returncode != 0:
            raise DeployError("%s %s failed:\n%s" % (" ".join(self.compose), " ".join(args), r.stderr.strip()))
        return r

    def container(self, service):
        ids = sh(["docker", "ps", "-aq", "--filter", "label=com.docker.compose.project=" + self.project,
                  "--filter", "label=com.docker.compose.service=" + service]).stdout.split()
        return ids[0] if ids else None

    def wait_log(self, service, pattern, timeout=60):
        cid = self.container(service)
        deadline = time.time() + timeout
        while time.time() < deadline:
            r = subprocess.run(["docker", "logs", cid], capture_output=True, text=True)
            if re.search(pattern, r.stdout + r.stderr):
                return
            st = sh(["docker", "inspect", "-f", "{{.State.Status}} {{.State.ExitCode}}", cid]).stdout.split()
            if st and st[0] in ("exited", "dead"):
                raise DeployError("%s exited (%s) before it was ready:\n%s" % (service, st[1], r.stderr[-2000:]))
            time.sleep(0.2)
        raise DeployError("%s not ready after %d s" % (service, timeout))

    def up(self):
        """Starts the services in dependency order, each once the one it needs is ready."""
        self.prepare()
        for attempt in range(3):
            try:
                self.setup_links()
                self.started = True
                ready = {"router": r"listening on", "monitor": r"rvc monitor:"}
                for s in self.services():
                    self.run_compose("up", "-d", "--no-deps", s)
                    if s in ready:
                        self.wait_log(s, ready[s])
                return self
            except DeployError as e:
                # a concurrent run may have taken the subnet between pick and create: try another
                if self.mode in NETWORKED and "overlap" in str(e).lower() and attempt < 2:
                    self.down()
                    self.plan(subnet=pick_subnet(skip=[self.subnet]))
                    self.env["RVC_OUT"] = self.out_dir
                    continue
                raise

    def wait(self, timeout=600):
        """Waits for the monitor to exit; returns its exit code, stats and the replay summary."""
        cid = self.container("monitor")
        try:
            code = int(sh(["docker", "wait", cid], timeout=timeout).stdout.strip())
        except subprocess.TimeoutExpired:
            raise DeployError("monitor did not finish within %d s" % timeout)
        res = {"project": self.project, "arch": self.arch, "transport": self.transport, "mode": self.mode,
               "monitor_exit": code}
        logs = subprocess.run(["docker", "logs", cid], capture_output=True, text=True)
        stats = [l for l in logs.stderr.splitlines() if l.startswith("{")]
        res["monitor"] = json.loads(stats[-1]) if stats else None
        res["monitor_log"] = logs.stderr[-3000:]
        pub = "publisher" if self.arch in ("a", "c") else "app"
        pid = self.container(pub)
        try:
            sh(["docker", "wait", pid], timeout=60)
        except subprocess.TimeoutExpired:
            pass
        plog = subprocess.run(["docker", "logs", pid], capture_output=True, text=True)
        lines = [l for l in plog.stdout.splitlines() if l.startswith("{")]
        res["replay"] = json.loads(lines[-1]) if lines else None
        res["replay_log"] = plog.stderr[-2000:]
        if res["monitor"] and res["replay"]:
            res["seconds"] = res["monitor"]["done_at"] - res["replay"]["started_at"]
            res["lost"] = (res["monitor"]["gaps"] + res["monitor"]["duplicates"]
                           + res["replay"].get("samples", res["replay"]["sent"]) - res["monitor"]["received"])
        res["verdicts"] = os.path.join(self.out_dir, "verdicts.jsonl")
        return res

    def down(self):
        # veth parents of this project's macvlan/ipvlan networks (also after a crash of `up`)
        ids = sh(["docker", "network", "ls", "-q", "--filter", "label=com.docker.compose.project=" + self.project],
                 check=False).stdout.split()
        for i in ids:
            parent = sh(["docker", "network", "inspect", "-f", '{{index .Options "parent"}}', i], check=False).stdout
            if re.fullmatch(r"rvc(mv|iv)\d+", parent.strip()) and parent.strip() not in self.links:
                self.links.append(parent.strip())
        if self.compose and self.env and self.started:
            self.run_compose("down", "-v", "--remove-orphans", "-t", "5", check=False)
            self.started = False
        self.remove_links()

    def leftovers(self):
        """Containers and networks of this project still present (empty after down())."""
        label = "label=com.docker.compose.project=" + self.project
        c = sh(["docker", "ps", "-aq", "--filter", label]).stdout.split()
        n = sh(["docker", "network", "ls", "-q", "--filter", label]).stdout.split()
        links = [l for l in self.links if link_exists(l)]
        for name in (self.env or {}).get("RVC_MACVLAN_PARENT"), (self.env or {}).get("RVC_IPVLAN_PARENT"):
            if name and self.mode in ("macvlan", "ipvlan") and link_exists(name):
                links.append(name)
        return {"containers": c, "networks": n, "links": sorted(set(links))}

    def run(self, timeout=600):
        try:
            self.up()
            return self.wait(timeout)
        finally:
            self.down()

    def manual(self):
        """Shell lines that reproduce this deployment by hand."""
        lines = ["export %s=%s" % (k, shlex.quote(v)) for k, v in sorted(self.env.items())]
        if self.mode in ("macvlan", "ipvlan"):
            p = self.env["RVC_%s_PARENT" % self.mode.upper()]
            lines.append("ip link add %s type veth peer name %sp && ip link set %s up && ip link set %sp up"
                         % (p, p, p, p))
        c = " ".join(shlex.quote(x) for x in (self.compose or ["docker-compose"]) + ["-p", self.project]
                     + self.compose_files() + ["--profile", self.arch])
        for s in self.services():
            lines.append("%s up -d --no-deps %s" % (c, s))
        lines.append("docker wait $(%s ps -q monitor); %s logs monitor" % (c, c))
        lines.append("%s down -v --remove-orphans" % c)
        if self.mode in ("macvlan", "ipvlan"):
            lines.append("ip link del %s" % self.env["RVC_%s_PARENT" % self.mode.upper()])
        return "\n".join(lines)


def mode_support():
    """{mode: None if it can run here, else the reason}."""
    why = docker_available()
    res = {m: why for m in MODES}
    if why:
        return res
    name = "rvcprobe%d" % (os.getpid() % 10000)
    try:
        r = subprocess.run(root_cmd(["ip", "link", "add", name, "type", "veth", "peer", "name", name + "p"]),
                           capture_output=True, text=True)
        if r.returncode != 0:
            res["macvlan"] = res["ipvlan"] = "[platform] cannot create a veth pair: " + r.stderr.strip()
            return res
        subprocess.run(root_cmd(["ip", "link", "set", name, "up"]), capture_output=True)
        for kind in ("macvlan", "ipvlan"):
            r = subprocess.run(root_cmd(["ip", "link", "add", name + "t", "link", name, "type", kind]),
                               capture_output=True, text=True)
            if r.returncode != 0:
                res[kind] = "[platform] the kernel cannot create %s links (%s)" % (kind, r.stderr.strip())
            else:
                subprocess.run(root_cmd(["ip", "link", "del", name + "t"]), capture_output=True)
    finally:
        subprocess.run(root_cmd(["ip", "link", "del", name]), capture_output=True)
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("action", choices=["run", "up", "down", "env", "modes"])
    ap.add_argument("--arch", default="a", choices=ARCHS)
    ap.add_argument("--transport", default="zenoh", choices=TRANSPORTS)
    ap.add_argument("--mode", default="bridge", choices=MODES)
    ap.add_argument("--trace", help="JSON-lines trace to publish")
    ap.add_argument("--spec", help="property to monitor (or --properties)")
    ap.add_argument("--properties", help="properties file (YAML/JSON)")
    ap.add_argument("--image", default=None, help="image (default $RVC_IMAGE or rvc:latest)")
    ap.add_argument("--monitor-flags", default="--all", help="extra flags of rvc monitor (default --all)")
    ap.add_argument("--out", help="directory for props.yaml, verdicts.jsonl, monitor-stats.json")
    ap.add_argument("--project", help="compose project name (down: required)")
    ap.add_argument("--timeout", type=int, default=600)
    args = ap.parse_args()

    if args.action == "modes":
        for m, why in mode_support().items():
            print("%-8s %s" % (m, "ok" if why is None else "unavailable: " + why))
        return 0
    if args.action == "down":
        if not args.project:
            ap.error("down needs --project")
        d = Deployment(arch=args.arch, mode=args.mode, project=args.project)
        d.compose, d.env, d.started = compose_command(), d.plan(), True
        d.down()
        return 0
    if args.action in ("run", "up") and not args.trace:
        ap.error("--trace is required")
    if args.action in ("run", "up") and not (args.spec or args.properties):
        ap.error("--spec or --properties is required")
    d = Deployment(arch=args.arch, transport=args.transport, mode=args.mode, trace=args.trace, spec=args.spec,
                   properties=args.properties, image=args.image, monitor_flags=args.monitor_flags,
                   out_dir=args.out, project=args.project)
    if args.action == "env":
        d.plan()
        if args.out:
            d.env["RVC_OUT"] = os.path.abspath(args.out)
        d.compose = compose_command()
        print(d.manual())
        return 0

    def on_signal(signum, frame):
        raise KeyboardInterrupt
    signal.signal(signal.SIGTERM, on_signal)
    try:
        if args.action == "up":
            d.up()
            print(json.dumps({"project": d.project, "out": d.out_dir, "env": d.env}))
            return 0
        res = d.run(args.timeout)
    except Unsupported as e:
        print("rvc-compose: skipped: %s" % e, file=sys.stderr)
        return 77
    except DeployError as e:
        print("rvc-compose: %s" % e, file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        if args.action == "up":
            d.down()
        return 130
    print(json.dumps({k: v for k, v in res.items() if not k.endswith("_log")}))
    return res["monitor_exit"]


if __name__ == "__main__":
    sys.exit(main())
