"""A monitor group over a fleet (docs/fleet.md), multi-process on loopback: three `rvc router`s
peered in a mesh, the simulated Autoware fleet (examples/autoware/fleet.py: 50 vehicles in one
process, spread over the three routers, per-vehicle scenarios including faults), three `rvc
monitor --group fleet --shard-by 'fleet/*'` replicas, each a client of a different router.

Oracle: for every vehicle, the verdicts the group published (every replica's output, the killed
one's too, equal duplicates of a handover merged) equal `rvc check` of that vehicle's own bag (the
bag the simulator recorded while publishing: the same CDR at the same stamps, checked offline by
the merge synchronizer). Loss: every surviving replica received every sample each publisher sent
(sent.json, the simulator's per-publisher counters), with no gap or duplicate, and its counters
add up (received = checked + rejected + dropped). The replica killed with SIGKILL mid-run is
replaced: the survivors report its departure, take its shards over and replay them, and the
results database records the handover."""
import glob
import json
import os
import random
import signal
import socket
import sqlite3
import subprocess
import sys
import threading
import time

import pytest

zenoh = pytest.importorskip("zenoh")
pytest.importorskip("rosbags")

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "../../.."))
EXAMPLE = os.path.join(ROOT, "examples", "autoware")
sys.path.insert(0, EXAMPLE)
import vehicle  # noqa: E402

pytestmark = pytest.mark.skipif("zenoh" not in os.environ.get("RVC_TRANSPORTS", "zenoh"), reason="no zenoh")

SCENARIOS = ["drive", "emergency", "fault-hazard-late", "fault-turn-with-hazard", "fault-steer-limit",
             "fault-autonomous-disengaged", "fault-gear-mismatch", "turn"]


def free_port() -> int:
    for _ in range(200):
        port = random.randint(20000, 29999)
        with socket.socket() as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    raise RuntimeError("no free port")


def ep(port: int) -> str:
    return f"tcp/127.0.0.1:{port}"


class Proc:
    """A child process whose stderr is collected line by line (for waiting on what it says)."""

    def __init__(self, args, **kw):
        self.args = args
        self.p = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, **kw)
        self.lines = []
        self.cv = threading.Condition()
        threading.Thread(target=self._pump, daemon=True).start()

    def _pump(self):
        for line in self.p.stderr:
            with self.cv:
                self.lines.append(line.rstrip("\n"))
                self.cv.notify_all()
        with self.cv:
            self.cv.notify_all()

    def wait_for(self, text: str, timeout: float = 30) -> str:
        end = time.monotonic() + timeout
        with self.cv:
            while True:
                for line in self.lines:
                    if text in line:
                        return line
                left = end - time.monotonic()
                if left <= 0 or (self.p.poll() is not None and not any(text in x for x in self.lines)):
                    raise AssertionError(f"'{text}' not seen from {self.args[:3]}: {self.lines[-20:]}")
                self.cv.wait(min(left, 0.2))

    def stderr(self) -> str:
        with self.cv:
            return "\n".join(self.lines)

    def stop(self):
        if self.p.poll() is None:
            self.p.terminate()
            try:
                self.p.wait(10)
            except subprocess.TimeoutExpired:
                self.p.kill()
                self.p.wait()


@pytest.fixture
def procs():
    started = []
    yield lambda *a, **kw: started.append(Proc(*a, **kw)) or started[-1]
    for p in reversed(started):
        p.stop()


def routers(rvc, procs, n=3):
    """n routers, each listening on its own port and connected to every earlier one (a mesh)."""
    ports = [free_port() for _ in range(n)]
    for i, port in enumerate(ports):
        args = [rvc, "router", "--listen", ep(port), "--no-multicast-scouting"]
        for earlier in ports[:i]:
            args += ["--connect", ep(earlier)]
        procs(args).wait_for("rvc router")
    return ports


def counters(stderr: str) -> dict:
    lines = [line for line in stderr.splitlines() if line.startswith('{"input"')]
    assert lines, stderr[-2000:]
    return json.loads(lines[-1])


def group_verdicts(paths, partial=None):
    """vehicle -> {(property, time): value}; a verdict published twice (a handover) must agree.
    A verdict marked "partial" (its instance began mid-history: its discrete steps count from there)
    is not the uninterrupted monitor's: it goes to `partial` (vehicle -> count), never into the map."""
    out, twice = {}, 0
    for path in paths:
        if not os.path.exists(path):
            continue
        with open(path) as f:
            for line in f:
                if not line.endswith("\n"):
                    continue  # the killed replica's last line may be cut short
                v = json.loads(line)
                _, vid, prop = v["property"].split("/", 2)
                if v.get("partial"):
                    assert partial is not None, f"a partial verdict where none is expected: {line}"
                    partial[vid] = partial.get(vid, 0) + 1
                    continue
                key = (prop, v["time"])
                seen = out.setdefault(vid, {})
                if key in seen:
                    assert seen[key] == v["value"], f"{vid} {key}: {seen[key]} then {v['value']} ({path})"
                    twice += 1
                seen[key] = v["value"]
    return out, twice


def offline_verdicts(rvc, bag_dir, topics):
    bag = glob.glob(os.path.join(bag_dir, "*.mcap"))[0]
    props = os.path.join(EXAMPLE, "properties.yaml")
    r = subprocess.run(vehicle.check_command(rvc, bag, topics, props, False), capture_output=True, text=True,
                       timeout=120)
    assert r.returncode in (0, 1), r.stderr
    out = {}
    for line in r.stdout.splitlines():
        v = json.loads(line)
        out[(v["property"], v["time"])] = v["value"]
    return out


def test_group_survives_a_killed_replica_with_verdicts_equal_offline(rvc, procs, tmp_path):
    vehicles = 50
    topics = vehicle.load_topics()
    ports = routers(rvc, procs)
    fleet_flags = []
    for t in topics["topics"]:
        fleet_flags += ["--input", f"{t['name']}=zenoh:fleet/*/{t['topic'].lstrip('/')}", "--type", t["type"]]
    monitors = {}
    for i, name in enumerate(["m1", "m2", "m3"]):
        args = [rvc, "monitor", *fleet_flags, "--sync", "merge",
                "--properties", os.path.join(EXAMPLE, "properties.yaml"),
                "--group", "fleet", "--shard-by", "fleet/*", "--member", name,
                "--exit-on-eos", "--publishers", str(vehicles), "--idle-timeout", "120",
                "--mode", "client", "--connect", ep(ports[i]), "--no-multicast-scouting",
                "-o", f"file:{tmp_path / name}.jsonl", "-o", f"sqlite:{tmp_path / name}.db"]
        monitors[name] = procs(args)
    for m in monitors.values():
        m.wait_for("members 3", timeout=30)

    record = tmp_path / "fleet"
    sim = procs([sys.executable, os.path.join(EXAMPLE, "fleet.py"), "run", "--vehicles", str(vehicles),
                 *sum((["--connect", ep(p)] for p in ports), []), *sum((["--scenario", s] for s in SCENARIOS), []),
                 "--duration", "10", "--speed", "2", "--record", str(record)])
    sim.wait_for("fleet: 50 vehicles", timeout=180)
    time.sleep(2.5)  # mid-run (5 s of publishing)
    victim = monitors["m2"]
    victim.p.send_signal(signal.SIGKILL)
    victim.p.wait()
    sim.p.wait(timeout=120)
    assert sim.p.returncode == 0, sim.stderr()
    survivors = {n: m for n, m in monitors.items() if m is not victim}
    for m in survivors.values():
        m.p.wait(timeout=120)

    # The survivors saw m2 go and took its shards over, replaying them.
    sent = json.loads((record / "sent.json").read_text())
    total = sum(sent.values())
    taken = 0
    for name, m in survivors.items():
        err = m.stderr()
        assert "left: m2" in err, err[-3000:]
        c = counters(err)
        assert m.p.returncode in (0, 1), err[-3000:]  # 1: a fault scenario's property was violated
        # 0 lost end to end: every sample of every publisher, no gap, no duplicate.
        assert c["received"] == total and c["gaps"] == 0 and c["duplicates"] == 0, c
        assert c["publishers"] == len(sent), c
        dropped = sum(c["dropped"].values())
        assert c["received"] == c["checked"] + c["rejected"] + dropped, c
        assert c["rejected"] == 0, c
        taken += c["group"]["handovers"]
        # Each replica had every taken shard's whole history: an exact replay, also of `historically`.
        assert c["group"]["partial_replays"] == 0 and c["group"]["replayed"] > 0, c
        assert c["group"]["members"] == 2, c
        db = sqlite3.connect(tmp_path / f"{name}.db")
        rows = [r[0] for r in db.execute("SELECT counters FROM counters") if '"handover"' in r[0]]
        assert rows and json.loads(rows[0])["handover"]["left"] == "m2", rows
    assert taken >= 2, "both survivors took part of m2's shards (rendezvous spreads them)"

    # Every vehicle's verdicts equal the offline check of its own trace.
    live, twice = group_verdicts([tmp_path / f"{n}.jsonl" for n in monitors])
    ids = json.loads((record / "vehicles.json").read_text())
    assert len(ids) == vehicles
    differ = []
    for vid in sorted(ids):
        offline = offline_verdicts(rvc, record / vid / "bag", topics)
        assert offline, vid
        if live.get(vid) != offline:
            differ.append((vid, ids[vid], sorted(set(offline.items()) ^ set(live.get(vid, {}).items()))[:4]))
    assert not differ, differ
    print(f"{vehicles} vehicles, {total} messages, verdicts equal offline; {twice} published twice at the handover")


def test_group_counts_add_up_across_replicas_and_an_orderly_end_hands_nothing_over(rvc, procs, tmp_path):
    """Two replicas, no kill: the owners' checked messages sum to what the publishers sent, each
    replica's "not owned" is the rest, and a replica ending at the end of the stream says bye, so
    the other one takes nothing over (no handover, no message checked twice)."""
    vehicles = 12
    topics = vehicle.load_topics()
    ports = routers(rvc, procs, 2)
    flags = []
    for t in topics["topics"]:
        flags += ["--input", f"{t['name']}=zenoh:fleet/*/{t['topic'].lstrip('/')}", "--type", t["type"]]
    reps = []
    for i in range(2):
        reps.append(procs([rvc, "monitor", *flags, "--sync", "merge",
                           "--properties", os.path.join(EXAMPLE, "properties.yaml"),
                           "--group", "pair", "--shard-by", "fleet/*", "--member", f"p{i}",
                           "--exit-on-eos", "--publishers", str(vehicles), "--idle-timeout", "120",
                           "--mode", "client", "--connect", ep(ports[i]), "--no-multicast-scouting",
                           "-o", "file:/dev/null"]))
    for r in reps:
        r.wait_for("members 2", timeout=30)
    record = tmp_path / "fleet"
    sim = procs([sys.executable, os.path.join(EXAMPLE, "fleet.py"), "run", "--vehicles", str(vehicles),
                 "--connect", ep(ports[0]), "--connect", ep(ports[1]), "--scenario", "drive",
                 "--duration", "4", "--speed", "0", "--record", str(record)])
    sim.p.wait(timeout=180)
    assert sim.p.returncode == 0, sim.stderr()
    total = sum(json.loads((record / "sent.json").read_text()).values())
    checked = 0
    for r in reps:
        r.p.wait(timeout=120)
        c = counters(r.stderr())
        assert r.p.returncode == 0, r.stderr()[-2000:]
        assert c["received"] == total and c["gaps"] == 0, c
        assert c["dropped"] == {"not owned": total - c["checked"]}, c
        assert c["group"]["handovers"] == 0 and c["group"]["replayed"] == 0, c
        assert c["group"]["owned"] > 0, c
        checked += c["checked"]
    assert checked == total


def test_a_replica_joining_mid_run_takes_its_shards_and_reports_them_partial(rvc, procs, tmp_path):
    """Scale-up, 2 -> 3 replicas while 12 vehicles publish: the newcomer takes the shards rendezvous
    gives it (the others hand them on), reports them as partial (it never saw their start), counts
    the numbers its publishers had sent before it joined as before_join, not as loss; the vehicles
    that stayed with the first two replicas still have exactly the offline verdicts."""
    vehicles = 12
    topics = vehicle.load_topics()
    ports = routers(rvc, procs, 2)
    flags = []
    for t in topics["topics"]:
        flags += ["--input", f"{t['name']}=zenoh:fleet/*/{t['topic'].lstrip('/')}", "--type", t["type"]]

    def replica(name, port):
        return procs([rvc, "monitor", *flags, "--sync", "merge",
                      "--properties", os.path.join(EXAMPLE, "properties.yaml"),
                      "--group", "grow", "--shard-by", "fleet/*", "--member", name,
                      "--exit-on-eos", "--publishers", str(vehicles), "--idle-timeout", "120",
                      "--mode", "client", "--connect", ep(port), "--no-multicast-scouting",
                      "-o", f"file:{tmp_path / name}.jsonl"])

    reps = {"g0": replica("g0", ports[0]), "g1": replica("g1", ports[1])}
    for r in reps.values():
        r.wait_for("members 2", timeout=30)
    record = tmp_path / "fleet"
    sim = procs([sys.executable, os.path.join(EXAMPLE, "fleet.py"), "run", "--vehicles", str(vehicles),
                 "--connect", ep(ports[0]), "--connect", ep(ports[1]), "--scenario", "drive",
                 "--scenario", "fault-hazard-late", "--duration", "8", "--speed", "2", "--record", str(record)])
    sim.wait_for(f"fleet: {vehicles} vehicles", timeout=120)
    time.sleep(1.5)
    reps["g2"] = replica("g2", ports[0])
    reps["g2"].wait_for("members 3", timeout=30)
    sim.p.wait(timeout=120)
    assert sim.p.returncode == 0, sim.stderr()
    total = sum(json.loads((record / "sent.json").read_text()).values())
    c = {}
    for name, r in reps.items():
        r.p.wait(timeout=120)
        assert r.p.returncode in (0, 1), r.stderr()[-2000:]
        c[name] = counters(r.stderr())
        assert c[name]["gaps"] == 0 and c[name]["duplicates"] == 0, c[name]
        assert c[name]["received"] + c[name]["before_join"] == total, c[name]
        dropped = sum(c[name]["dropped"].values())
        assert c[name]["received"] == c[name]["checked"] + c[name]["rejected"] + dropped, c[name]
    assert c["g0"]["before_join"] == 0 and c["g1"]["before_join"] == 0
    assert c["g2"]["before_join"] > 0
    g2 = c["g2"]["group"]
    assert g2["owned"] > 0 and g2["partial_replays"] == g2["owned"], g2
    handed = sum("handed" in line and "handed 0 on" not in line
                 for n in ("g0", "g1") for line in reps[n].stderr().splitlines())
    assert handed >= 1, "the first replicas handed shards on"

    partial = {}
    live, _ = group_verdicts([tmp_path / f"{n}.jsonl" for n in reps], partial)
    moved = {vid for vid in json.loads((record / "vehicles.json").read_text())
             if fleet_owner(f"fleet/{vid}", ["g0", "g1", "g2"]) == "g2"}
    # The newcomer's verdicts, and only those, are marked partial: it never saw its vehicles' start.
    assert set(partial) <= moved and partial, (partial, moved)
    stayed = sorted(set(json.loads((record / "vehicles.json").read_text())) - moved)
    assert moved and stayed
    for vid in stayed:
        assert live.get(vid) == offline_verdicts(rvc, record / vid / "bag", topics), vid


def fleet_owner(shard, members):
    """rvc's rendezvous owner (runtime/fleet/shard_map.cpp), written again from its description:
    FNV-1a 64 over member, NUL, shard; splitmix64's finalizer; the highest hash wins."""
    def h(a, b):
        x = 14695981039346656037
        for ch in a.encode() + b"\0" + b.encode():
            x = ((x ^ ch) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
        x ^= x >> 30
        x = (x * 0xbf58476d1ce4e5b9) & 0xFFFFFFFFFFFFFFFF
        x ^= x >> 27
        x = (x * 0x94d049bb133111eb) & 0xFFFFFFFFFFFFFFFF
        x ^= x >> 31
        return x
    return max(sorted(members), key=lambda m: h(m, shard))


def owned_replica(rvc, procs, tmp_path, flags, group, name, port):
    """A replica subscribing per owned and backed-up shard (--shard-subscribe owned): it sees only
    its shards' end-of-stream markers, so it ends at --idle-timeout once the fleet is quiet."""
    return procs([rvc, "monitor", *flags, "--sync", "merge",
                  "--properties", os.path.join(EXAMPLE, "properties.yaml"),
                  "--group", group, "--shard-by", "fleet/*", "--member", name, "--shard-subscribe", "owned",
                  "--idle-timeout", "12", "--mode", "client", "--connect", ep(port), "--no-multicast-scouting",
                  "-o", f"file:{tmp_path / name}.jsonl", "-o", f"sqlite:{tmp_path / name}.db"])


def fleet_inputs(topics):
    flags = []
    for t in topics["topics"]:
        flags += ["--input", f"{t['name']}=zenoh:fleet/*/{t['topic'].lstrip('/')}", "--type", t["type"]]
    return flags


def test_owned_subscriptions_survive_a_killed_replica_with_verdicts_equal_offline(rvc, procs, tmp_path):
    """--shard-subscribe owned, 3 replicas, 30 vehicles, one replica killed mid-run: each survivor
    received only the shards it owned or backed up (fewer samples than were sent), every sample of
    those with no gap; the backup of each of the killed replica's shards had its whole window (an
    exact replay), and every vehicle's verdicts equal `rvc check` of its own bag."""
    vehicles = 30
    topics = vehicle.load_topics()
    ports = routers(rvc, procs)
    flags = fleet_inputs(topics)
    monitors = {n: owned_replica(rvc, procs, tmp_path, flags, "owned", n, ports[i])
                for i, n in enumerate(["m1", "m2", "m3"])}
    for m in monitors.values():
        m.wait_for("members 3", timeout=30)
    record = tmp_path / "fleet"
    sim = procs([sys.executable, os.path.join(EXAMPLE, "fleet.py"), "run", "--vehicles", str(vehicles),
                 *sum((["--connect", ep(p)] for p in ports), []), *sum((["--scenario", s] for s in SCENARIOS), []),
                 "--duration", "10", "--speed", "2", "--settle", "3", "--record", str(record)])
    sim.wait_for(f"fleet: {vehicles} vehicles", timeout=180)
    time.sleep(2.5)
    victim = monitors["m2"]
    victim.p.send_signal(signal.SIGKILL)
    victim.p.wait()
    sim.p.wait(timeout=120)
    assert sim.p.returncode == 0, sim.stderr()
    survivors = {n: m for n, m in monitors.items() if m is not victim}
    sent = json.loads((record / "sent.json").read_text())
    total = sum(sent.values())
    for name, m in survivors.items():
        m.p.wait(timeout=120)
        err = m.stderr()
        assert m.p.returncode in (0, 1), err[-3000:]
        assert "left: m2" in err and "subscribed to" in err, err[-3000:]
        c = counters(err)
        assert c["gaps"] == 0 and c["duplicates"] == 0 and c["rejected"] == 0, c
        assert c["received"] == c["checked"] + sum(c["dropped"].values()), c
        assert 0 < c["received"] < total, c  # not the whole key space
        g = c["group"]
        assert g["members"] == 2 and g["partial_replays"] == 0 and g["replayed"] > 0, g
    live, _ = group_verdicts([tmp_path / f"{n}.jsonl" for n in monitors])
    ids = json.loads((record / "vehicles.json").read_text())
    differ = []
    for vid in sorted(ids):
        offline = offline_verdicts(rvc, record / vid / "bag", topics)
        if live.get(vid) != offline:
            differ.append((vid, ids[vid], sorted(set(offline.items()) ^ set(live.get(vid, {}).items()))[:4]))
    assert not differ, differ


def test_owned_subscriptions_count_up_across_the_group(rvc, procs, tmp_path):
    """--shard-subscribe owned, 3 replicas, 12 vehicles, no kill: each replica receives exactly the
    samples of the shards it owns (checked) or backs up ("not owned"), computed here from rvc's
    rendezvous order written again; the owners' checked sum to what was sent; no handover at the end."""
    vehicles = 12
    topics = vehicle.load_topics()
    ports = routers(rvc, procs, 2)
    flags = fleet_inputs(topics)
    names = ["o0", "o1", "o2"]
    reps = {n: owned_replica(rvc, procs, tmp_path, flags, "count", n, ports[i % 2]) for i, n in enumerate(names)}
    for r in reps.values():
        r.wait_for("members 3", timeout=30)
    record = tmp_path / "fleet"
    sim = procs([sys.executable, os.path.join(EXAMPLE, "fleet.py"), "run", "--vehicles", str(vehicles),
                 "--connect", ep(ports[0]), "--connect", ep(ports[1]), "--scenario", "drive",
                 "--duration", "4", "--speed", "0", "--settle", "3", "--record", str(record)])
    sim.p.wait(timeout=180)
    assert sim.p.returncode == 0, sim.stderr()
    sent = json.loads((record / "sent.json").read_text())
    per_shard = {}
    for key, n in sent.items():
        shard = "/".join(key.split("/")[:2])
        per_shard[shard] = per_shard.get(shard, 0) + n
    checked = 0
    for name, r in reps.items():
        r.p.wait(timeout=120)
        assert r.p.returncode == 0, r.stderr()[-2000:]
        c = counters(r.stderr())
        owned = sum(n for s, n in per_shard.items() if fleet_owner(s, names) == name)
        backed = sum(n for s, n in per_shard.items() if fleet_ranked(s, names)[1] == name)
        assert c["gaps"] == 0 and c["duplicates"] == 0, c
        assert c["checked"] == owned and c["dropped"] == {"not owned": backed}, (name, c, owned, backed)
        assert c["received"] == owned + backed, c
        assert c["group"]["handovers"] == 0, c
        checked += c["checked"]
    assert checked == sum(sent.values())


def fleet_ranked(shard, members):
    """Members in rendezvous order: the owner, then the owner of the rest (the backup), ..."""
    order, rest = [], list(members)
    while rest:
        order.append(fleet_owner(shard, rest))
        rest.remove(order[-1])
    return order
