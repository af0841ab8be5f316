"""The fleet scenario of docs/fleet.md in containers (issue 30), short: three `rvc router`s, each
in its own container and on its own internal Docker network, peered as a mesh over a fourth
internal network; three `rvc monitor --group fleet --shard-by 'fleet/*'` replicas, each a
container on a different router's network (a client of that router only); 50 simulated Autoware
vehicles (examples/autoware/fleet.py, on the host: no Python image can be pulled here) as Zenoh
clients of the three routers, reached through the host's address on each of those networks. One
replica's container is killed mid-run (`docker kill -s KILL`).

Oracle (the loopback test's, tests/integration/fleet/test_fleet_group.py, whose helpers this
reuses): every vehicle's verdicts, gathered from all replicas' output files (the killed one's
too), equal `rvc check` of the bag the simulator recorded for it; each survivor received every
sample each publisher sent (the simulator's per-publisher counters, sent.json) with no gap or
duplicate, and its counters add up. Afterwards no container or network made here is left.

Network: every network is created here, `--internal` (no route out, no NAT), with a /24 picked
away from the machine's own (rvc_compose.pick_subnet); routers listen on their container
addresses only. The host talks to the routers through its gateway address on their networks.
"""
import importlib.util
import json
import os
import sqlite3
import sys
import time

import pytest

from test_containers import IMAGE, ROOT, docker, image, rc, run  # noqa: F401 (fixtures)

pytest.importorskip("zenoh")
pytest.importorskip("rosbags")

_spec = importlib.util.spec_from_file_location(
    "fleet_group", os.path.join(ROOT, "tests", "integration", "fleet", "test_fleet_group.py"))
fg = importlib.util.module_from_spec(_spec)
sys.modules["fleet_group"] = fg
_spec.loader.exec_module(fg)  # also puts examples/autoware on sys.path (vehicle.py)

VEHICLES = 50
MEMBERS = ["m1", "m2", "m3"]
VICTIM = "m2"
PORT = 7447


class Fleet:
    """The containers and networks of one run, all labelled with the run's name, so that cleanup
    (and the check that nothing is left) finds exactly them."""

    def __init__(self, name):
        self.name = name
        self.label = "rvc.test.fleet=" + name
        self.networks = []
        self.subnets = {}

    def network(self, suffix):
        net = "%s_%s" % (self.name, suffix)
        for _ in range(4):
            subnet = rc.pick_subnet()
            r = run(["docker", "network", "create", "--internal", "--label", self.label,
                     "--subnet", str(subnet), net])
            if r.returncode == 0:
                self.networks.append(net)
                self.subnets[net] = list(subnet.hosts())
                return net
            if "overlap" not in r.stderr.lower():  # a concurrent run took the subnet: try another
                break
        pytest.fail("docker network create %s: %s" % (net, r.stderr))

    def addr(self, net, host):
        return str(self.subnets[net][host - 1])

    def container(self, cname, nets, args, volumes=()):
        """Creates the container on its first network at the given host number, connects the
        others, then starts it (an address per network, known before rvc starts)."""
        cname = "%s_%s" % (self.name, cname)
        (net0, host0), rest = nets[0], nets[1:]
        cmd = ["docker", "create", "--name", cname, "--label", self.label, "--network", net0,
               "--ip", self.addr(net0, host0)]
        for v in volumes:
            cmd += ["-v", v]
        r = run(cmd + [IMAGE] + list(args))
        assert r.returncode == 0, r.stderr
        for net, host in rest:
            r = run(["docker", "network", "connect", "--ip", self.addr(net, host), net, cname])
            assert r.returncode == 0, r.stderr
        r = run(["docker", "start", cname])
        assert r.returncode == 0, r.stderr
        return cname

    def logs(self, cname, timestamps=False):
        r = run(["docker", "logs"] + (["-t"] if timestamps else []) + [cname])
        return r.stdout + r.stderr

    def wait_log(self, cname, text, timeout):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if text in self.logs(cname):
                return
            time.sleep(0.3)
        pytest.fail("'%s' not seen from %s:\n%s" % (text, cname, self.logs(cname)[-3000:]))

    def wait_exit(self, cname, timeout):
        r = run(["docker", "wait", cname], timeout=timeout)
        assert r.returncode == 0, r.stderr
        return int(r.stdout.strip())

    def leftovers(self):
        return {"containers": run(["docker", "ps", "-aq", "--filter", "label=" + self.label]).stdout.split(),
                "networks": run(["docker", "network", "ls", "-q", "--filter", "label=" + self.label]).stdout.split()}

    def down(self):
        ids = run(["docker", "ps", "-aq", "--filter", "label=" + self.label]).stdout.split()
        if ids:
            run(["docker", "rm", "-f"] + ids, timeout=120)
        for net in reversed(self.networks):
            run(["docker", "network", "rm", net])


def test_fleet_group_in_containers_survives_a_killed_monitor_container(image, rvc, tmp_path):  # noqa: F811
    topics = fg.vehicle.load_topics()
    out = tmp_path / "out"
    out.mkdir()
    os.chmod(out, 0o777)  # the monitors run as uid 10001
    props = os.path.join(ROOT, "examples", "autoware", "properties.yaml")
    fleet = Fleet("rvcfleet%d" % (os.getpid() % 100000))
    try:
        peer = fleet.network("peer")
        nets = [fleet.network("r%d" % i) for i in range(3)]
        # Routers: router i is .10 on its own network and on the peer network (.10+i), listens on
        # both addresses, and connects to every earlier router's peer address (a mesh).
        routers = []
        for i, net in enumerate(nets):
            args = ["router", "--listen", "tcp/%s:%d" % (fleet.addr(net, 10), PORT),
                    "--listen", "tcp/%s:%d" % (fleet.addr(peer, 10 + i), PORT), "--no-multicast-scouting"]
            for j in range(i):
                args += ["--connect", "tcp/%s:%d" % (fleet.addr(peer, 10 + j), PORT)]
            routers.append(fleet.container("router%d" % i, [(net, 10), (peer, 10 + i)], args))
            fleet.wait_log(routers[-1], "listening on", 30)
        # Monitors: replica i is .20 on router i's network, a client of router i only.
        flags = []
        for t in topics["topics"]:
            flags += ["--input", "%s=zenoh:fleet/*/%s" % (t["name"], t["topic"].lstrip("/")), "--type", t["type"]]
        monitors = {}
        for i, name in enumerate(MEMBERS):
            args = ["monitor", *flags, "--sync", "merge", "--properties", "/props.yaml",
                    "--group", "fleet", "--shard-by", "fleet/*", "--member", name,
                    "--exit-on-eos", "--publishers", str(VEHICLES), "--idle-timeout", "90",
                    "--mode", "client", "--connect", "tcp/%s:%d" % (fleet.addr(nets[i], 10), PORT),
                    "--no-multicast-scouting", "-o", "file:/out/%s.jsonl" % name, "-o", "sqlite:/out/%s.db" % name]
            monitors[name] = fleet.container(name, [(nets[i], 20)], args,
                                             volumes=["%s:/props.yaml:ro" % props, "%s:/out" % out])
        for cname in monitors.values():
            fleet.wait_log(cname, "members 3", 60)

        # The vehicles: one host process, round robin over the three routers' addresses.
        record = tmp_path / "fleet"
        sim_cmd = [sys.executable, os.path.join(ROOT, "examples", "autoware", "fleet.py"), "run",
                   "--vehicles", str(VEHICLES), "--duration", "10", "--speed", "2", "--record", str(record)]
        for net in nets:
            sim_cmd += ["--connect", "tcp/%s:%d" % (fleet.addr(net, 10), PORT)]
        for s in fg.SCENARIOS:
            sim_cmd += ["--scenario", s]
        sim = fg.Proc(sim_cmd)
        try:
            sim.wait_for("fleet: %d vehicles" % VEHICLES, timeout=120)
            time.sleep(2.5)  # mid-run (5 s of publishing)
            kill_sent = time.time()
            k = run(["docker", "kill", "-s", "KILL", monitors[VICTIM]])
            assert k.returncode == 0, k.stderr
            sim.p.wait(timeout=120)
        finally:
            sim.stop()
        assert sim.p.returncode == 0, sim.stderr()
        exits = {n: fleet.wait_exit(c, 120) for n, c in monitors.items()}
        assert exits[VICTIM] == 137, exits  # SIGKILL
        logs = {n: fleet.logs(c) for n, c in monitors.items()}
        stamped = {n: fleet.logs(c, timestamps=True) for n, c in monitors.items() if n != VICTIM}
    finally:
        fleet.down()
        left = fleet.leftovers()
    assert left == {"containers": [], "networks": []}, "left behind: %s" % left

    sent = json.loads((record / "sent.json").read_text())
    total = sum(sent.values())
    taken, takeover = 0, []
    for name in MEMBERS:
        if name == VICTIM:
            continue
        err = logs[name]
        assert "left: %s" % VICTIM in err, err[-3000:]
        assert exits[name] in (0, 1), err[-3000:]  # 1: a fault scenario's property was violated
        c = fg.counters(err)
        # 0 lost end to end: every sample of every publisher, no gap, no duplicate.
        assert c["received"] == total and c["gaps"] == 0 and c["duplicates"] == 0, c
        assert c["publishers"] == len(sent), c
        assert c["received"] == c["checked"] + c["rejected"] + sum(c["dropped"].values()), c
        assert c["rejected"] == 0, c
        assert c["group"]["members"] == 2 and c["group"]["partial_replays"] == 0, c
        taken += c["group"]["handovers"]
        db = sqlite3.connect(out / ("%s.db" % name))  # the results database records the handover
        rows = [r[0] for r in db.execute("SELECT counters FROM counters") if '"handover"' in r[0]]
        db.close()
        assert rows and json.loads(rows[0])["handover"]["left"] == VICTIM, rows
        line = next(ln for ln in stamped[name].splitlines() if "left: %s" % VICTIM in ln)
        takeover.append(_seconds_after(line.split()[0], kill_sent))
    assert taken >= 2, "both survivors took part of %s's shards" % VICTIM

    live, twice = fg.group_verdicts([out / ("%s.jsonl" % n) for n in MEMBERS])
    ids = json.loads((record / "vehicles.json").read_text())
    assert len(ids) == VEHICLES
    differ = []
    for vid in sorted(ids):
        offline = fg.offline_verdicts(rvc, record / vid / "bag", topics)
        assert offline, vid
        if live.get(vid) != offline:
            differ.append((vid, ids[vid], sorted(set(offline.items()) ^ set(live.get(vid, {}).items()))[:4]))
    assert not differ, differ
    print("\ncontainers: %d vehicles, %d messages, 0 lost, verdicts equal offline; %d published twice at the "
          "handover; takeover logged %s s after `docker kill` was run" %
          (VEHICLES, total, twice, ", ".join("%.3f" % s for s in takeover)))


def _seconds_after(stamp, t0):
    """docker logs -t stamps (RFC 3339, nanoseconds, UTC) as seconds after t0 (time.time())."""
    from datetime import datetime, timezone
    main, _, frac = stamp.rstrip("Z").partition(".")
    t = datetime.strptime(main, "%Y-%m-%dT%H:%M:%S").replace(tzinfo=timezone.utc).timestamp()
    return t + float("0." + (frac or "0")) - t0
