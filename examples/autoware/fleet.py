#!/usr/bin/env python3
"""A fleet of simulated Autoware vehicles in one process (docs/fleet.md).

Vehicle i runs scenario SCENARIOS[i % len] (nominal or fault: per-vehicle faults) with its own
jitter seed, and publishes the nine Table-3 topics of topics.yaml on Zenoh under its own
namespace, the zenoh-bridge-ros2dds convention: key `fleet/<id>/<ROS topic without '/'>`, e.g.
`fleet/v0007/vehicle/status/gear_status`, payload the full CDR sample. Each (vehicle, topic) is
its own publisher with rvc's attachment (sequence number, publisher id, an end-of-stream marker
at the end), so a monitor counts loss per publisher. Vehicles are spread over the routers given
(--connect, one Zenoh client session per router), round robin.

  fleet.py run --vehicles 50 --connect tcp/127.0.0.1:7447 --connect tcp/127.0.0.1:7448 \\
      --scenario drive --scenario fault-hazard-late --speed 2 --record /tmp/fleet
  fleet.py commands          # the monitor's --input/--type flags for the nine topics

--record DIR writes, per vehicle, the bag it published (DIR/<id>/bag, the same CDR at each
message's stamp: the offline oracle, `rvc check BAG --topic ... --sync merge`) and DIR/sent.json,
the number of samples each publisher sent.
"""
from __future__ import annotations

import argparse
import json
import os
import pickle
import random
import struct
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import vehicle  # noqa: E402


def vehicle_id(i: int) -> str:
    return f"v{i:04d}"


def key_of(vid: str, topic: str, prefix: str = "fleet") -> str:
    return f"{prefix}/{vid}/{topic.lstrip('/')}"


def monitor_flags(topics: dict, prefix: str = "fleet") -> list[str]:
    """rvc monitor's inputs for every vehicle at once: NAME=zenoh:fleet/*/TOPIC with its --type."""
    flags = []
    for t in topics["topics"]:
        flags += ["--input", f"{t['name']}=zenoh:{key_of('*', t['topic'], prefix)}", "--type", t["type"]]
    return flags


def scenario_path(name: str) -> str:
    return name if os.path.exists(name) else os.path.join(HERE, "scenarios", name + ".yaml")


def plan(n: int, scenarios: list[str], topics: dict, rate_scale: float, duration: float | None, loops: int = 1):
    """Per vehicle: (id, scenario name, {topic name: [(stamp_ns, cdr bytes)]}); `loops` > 1 runs
    the scenario again after itself (stamps moved on by its length plus 1 s; the CDR stamps stay
    those of the first run, which no property reads)."""
    ts = vehicle.typestore()
    by_name = {t["name"]: t for t in topics["topics"]}
    loaded = {s: vehicle.Scenario(scenario_path(s)) for s in scenarios}
    fleet = []
    for i in range(n):
        sc = loaded[scenarios[i % len(scenarios)]]
        msgs = vehicle.generate(sc, topics, rate_scale, seed=f"{sc.seed}:{vehicle_id(i)}")
        epoch_ns = int(topics.get("epoch", 1_700_000_000)) * 1_000_000_000
        out = {}
        for name, lst in msgs.items():
            type_name = by_name[name]["type"]
            once = [(ns, bytes(ts.serialize_cdr(vehicle.to_rosbags(ts, type_name, m), type_name)))
                    for ns, m in lst if duration is None or ns - epoch_ns < duration * 1e9]
            span = int(((duration or sc.duration) + 1) * 1e9)
            out[name] = [(ns + k * span, d) for k in range(loops) for ns, d in once]
        fleet.append((vehicle_id(i), sc.name, out))
    return fleet


def write_bag(path: str, msgs: dict, topics: dict) -> None:
    from rosbags.rosbag2 import Writer
    from rosbags.rosbag2.enums import StoragePlugin
    ts = vehicle.typestore()
    by_name = {t["name"]: t for t in topics["topics"]}
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conns = {name: w.add_connection(by_name[name]["topic"], by_name[name]["type"], typestore=ts)
                 for name in msgs}
        for ns, name, data in sorted((ns, name, d) for name, lst in msgs.items() for ns, d in lst):
            w.write(conns[name], ns, data)


def open_sessions(connect: list[str]):
    import zenoh
    sessions = []
    for ep in connect:
        conf = zenoh.Config()
        conf.insert_json5("mode", '"client"')
        conf.insert_json5("connect/endpoints", json.dumps([ep]))
        conf.insert_json5("scouting/multicast/enabled", "false")
        sessions.append(zenoh.open(conf))
    return sessions


def attachment(seq: int, publisher: int, eos: bool = False) -> bytes:
    return struct.pack("<QBQ", seq, 1 if eos else 0, publisher)


def publish(fleet, topics: dict, sessions, speed: float, prefix: str, settle: float, log=print) -> dict:
    """Publishes every vehicle's messages in stamp order, paced at `speed` x the stamps; returns
    the samples sent per key."""
    import zenoh
    by_name = {t["name"]: t for t in topics["topics"]}
    rng = random.Random()
    pubs, events, tokens = {}, [], []
    for v, (vid, _, msgs) in enumerate(fleet):
        session = sessions[v % len(sessions)]
        # The vehicle announces itself (a liveliness token on its shard key, fleet/<id>): replicas
        # with --shard-subscribe owned find their shards by these tokens (docs/fleet.md).
        tokens.append(session.liveliness().declare_token(f"{prefix}/{vid}"))
        for name, lst in msgs.items():
            key = key_of(vid, by_name[name]["topic"], prefix)
            pub = session.declare_publisher(key, congestion_control=zenoh.CongestionControl.BLOCK)
            pubs[key] = [pub, rng.getrandbits(63) | 1, 0]
            events += [(ns, key, data) for ns, data in lst]
    events.sort(key=lambda e: e[0])
    time.sleep(settle)  # the routers learn the publishers' subscribers (and replicas subscribe per vehicle)
    log(f"fleet: {len(fleet)} vehicles, {len(pubs)} publishers, {len(events)} messages over "
        f"{len(sessions)} router(s), speed {speed}")
    start_ns = events[0][0] if events else 0
    t0 = time.monotonic()
    for ns, key, data in events:
        if speed > 0:
            due = t0 + (ns - start_ns) / 1e9 / speed
            delay = due - time.monotonic()
            if delay > 0.002:
                time.sleep(delay)
        p = pubs[key]
        p[2] += 1
        p[0].put(data, attachment=attachment(p[2], p[1]))
    for key, p in pubs.items():
        p[0].put(b"", attachment=attachment(p[2], p[1], eos=True))
    # Closing a session may drop samples still queued: first a flush barrier per session, rvc's
    # query on rvc/flush/<key> (docs/zenoh.md, "Flush"), which travels behind the data and is
    # answered by each rvc subscriber once it has taken every earlier sample.
    answered = 0
    for session in sessions:
        for reply in session.get(f"rvc/flush/{prefix}/**", timeout=60.0,
                                 congestion_control=zenoh.CongestionControl.BLOCK,
                                 consolidation=zenoh.ConsolidationMode.NONE):
            answered += reply.ok is not None
    elapsed = time.monotonic() - t0
    log(f"fleet: {answered} flush answers")
    log(f"fleet: sent {len(events)} messages in {elapsed:.2f} s ({len(events) / max(elapsed, 1e-9):.0f}/s)")
    for token in tokens:
        token.undeclare()
    return {key: p[2] for key, p in pubs.items()}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="simulate and publish the fleet")
    r.add_argument("--vehicles", type=int, default=10)
    r.add_argument("--connect", action="append", required=True, help="a router endpoint (repeatable)")
    r.add_argument("--scenario", action="append", help="scenario names or files, assigned round robin")
    r.add_argument("--speed", type=float, default=1.0,
                   help="publish at this many times the stamps' pace (0: as fast as the network takes them)")
    r.add_argument("--loop", type=int, default=1, help="run each scenario this many times, one after the other")
    r.add_argument("--plan-cache", help="pickle of the generated messages: reused if it exists (benchmarks)")
    r.add_argument("--rate-scale", type=float, default=1.0)
    r.add_argument("--duration", type=float, help="only the first S seconds of each scenario")
    r.add_argument("--prefix", default="fleet")
    r.add_argument("--record", help="folder for each vehicle's bag and sent.json")
    r.add_argument("--settle", type=float, default=1.0, help="seconds between declaring and publishing")
    r.add_argument("--start-file", help="wait until this file exists before publishing")
    c = sub.add_parser("commands", help="print rvc monitor's --input/--type flags")
    c.add_argument("--prefix", default="fleet")
    args = ap.parse_args(argv)
    topics = vehicle.load_topics()
    if args.cmd == "commands":
        print(" ".join(monitor_flags(topics, args.prefix)))
        return 0
    log = lambda s: print(s, file=sys.stderr, flush=True)  # noqa: E731
    if args.record and os.path.isdir(args.record) and os.listdir(args.record):
        # Its bags, vehicles.json and sent.json are the oracle of a run: never mixed with, or
        # written over, what the folder already holds.
        log(f"fleet: --record {args.record}: the folder is not empty: refusing to write into it")
        return 2
    if args.plan_cache and os.path.exists(args.plan_cache):
        with open(args.plan_cache, "rb") as f:
            fleet = pickle.load(f)
    else:
        fleet = plan(args.vehicles, args.scenario or ["drive"], topics, args.rate_scale, args.duration, args.loop)
        if args.plan_cache:
            with open(args.plan_cache, "wb") as f:
                pickle.dump(fleet, f)
    if args.record:
        os.makedirs(args.record, exist_ok=True)
        for vid, sc, msgs in fleet:
            write_bag(os.path.join(args.record, vid, "bag"), msgs, topics)
        with open(os.path.join(args.record, "vehicles.json"), "w") as f:
            json.dump({vid: sc for vid, sc, _ in fleet}, f)
    sessions = open_sessions(args.connect)
    if args.start_file:
        while not os.path.exists(args.start_file):
            time.sleep(0.05)
    sent = publish(fleet, topics, sessions, args.speed, args.prefix, args.settle, log)
    if args.record:
        with open(os.path.join(args.record, "sent.json"), "w") as f:
            json.dump(sent, f)
    time.sleep(0.5)  # let the end-of-stream markers leave before the sessions close
    for s in sessions:
        s.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
