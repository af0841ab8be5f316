#!/usr/bin/env python3
"""The Autoware case study's simulated vehicle.

A scenario (scenarios/*.yaml) describes the vehicle over time: a start state and piecewise changes
of speed, gear, steering, indicators, hazard lights, control mode, engage, emergency and fail-safe
state. This program samples that state on each of the nine Table-3 topics (topics.yaml) at the
topic's rate, with seeded jitter on the stamps, and

  generate  writes one JSON-lines file per topic (one message of the topic's type per line) and,
            with --bag DIR, a rosbag2 bag (MCAP storage, CDR samples written by `rosbags`);
  publish   publishes the nine files on DDS, one `rvc replay --type` process per topic (the
            simulated vehicle on a ROS 2 network), and waits for them;
  check     writes the bag and runs `rvc check BAG --topic NAME=TOPIC ... --sync merge
            --properties FILE [--dense]`, then prints each property's final verdict.

Examples:
  ./vehicle.py generate scenarios/drive.yaml --out /tmp/drive --bag /tmp/drive/bag
  ./vehicle.py check scenarios/fault-hazard-late.yaml --dense
  ./vehicle.py publish scenarios/emergency.yaml --rvc ../../build/release/rvc --speed 4
"""
from __future__ import annotations

import argparse
import json
import math
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile

import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_TOPICS = os.path.join(HERE, "topics.yaml")
DEFAULT_MSG_DIR = os.path.normpath(os.path.join(HERE, "..", "..", "src", "msg", "definitions"))
MSG_PACKAGES = ("autoware_auto_vehicle_msgs", "tier4_external_api_msgs")
WHEELBASE = 2.79  # m, Autoware's sample vehicle: yaw rate = v * tan(steering) / wheelbase

# The vehicle's state. Symbolic values are the constant names of the message that reports them.
DEFAULT_STATE = {
    "speed": 0.0,          # m/s, forward positive (VehicleStatus.twist.linear.x)
    "steering": 0.0,       # rad, left positive (SteeringReport.steering_tire_angle)
    "gear": "PARK",        # GearReport constant
    "turn": "DISABLE",     # TurnIndicatorsReport constant
    "hazard": "DISABLE",   # HazardLightsReport constant
    "mode": "MANUAL",      # ControlModeReport constant
    "engage": False,       # Engage.engage
    "emergency": False,    # Emergency.emergency
    "failsafe": "NORMAL",  # FailSafeState constant
    "status_gear": None,   # fault injection: GearShift constant VehicleStatus reports (None: follows gear)
}
NUMERIC = ("speed", "steering")
CONSTANT_OF = {  # state field -> the message type whose constants name its values
    "gear": "autoware_auto_vehicle_msgs/msg/GearReport",
    "turn": "autoware_auto_vehicle_msgs/msg/TurnIndicatorsReport",
    "hazard": "autoware_auto_vehicle_msgs/msg/HazardLightsReport",
    "mode": "autoware_auto_vehicle_msgs/msg/ControlModeReport",
    "failsafe": "tier4_external_api_msgs/msg/FailSafeState",
    "status_gear": "tier4_external_api_msgs/msg/GearShift",
}
# GearReport -> the GearShift that VehicleStatus reports for it
GEAR_SHIFT = {"NONE": "NONE", "NEUTRAL": "NEUTRAL", "PARK": "PARKING", "REVERSE": "REVERSE",
              "REVERSE_2": "REVERSE", "LOW": "LOW", "LOW_2": "LOW"}


class ScenarioError(Exception):
    pass


# ---------------------------------------------------------------------------------------------
# message definitions and constants

def msg_file(msg_dir: str, type_name: str) -> str:
    pkg, _, name = type_name.split("/")
    return os.path.join(msg_dir, pkg, "msg", name + ".msg")


def read_constants(msg_dir: str, type_name: str) -> dict[str, int]:
    """The integer constants of a .msg definition (`uint8 REVERSE = 20`)."""
    consts = {}
    with open(msg_file(msg_dir, type_name)) as f:
        for line in f:
            m = re.match(r"\s*u?int\d+\s+([A-Z][A-Z0-9_]*)\s*=\s*(-?\d+)", line.split("#")[0])
            if m:
                consts[m.group(1)] = int(m.group(2))
    return consts


def load_topics(path: str = DEFAULT_TOPICS) -> dict:
    with open(path) as f:
        doc = yaml.safe_load(f)
    for t in doc["topics"]:
        if set(t) != {"name", "topic", "type", "rate"}:
            raise ScenarioError(f"{path}: topic entry needs exactly name, topic, type, rate: {t}")
    return doc


# ---------------------------------------------------------------------------------------------
# scenarios

class Scenario:
    """A scenario file: the vehicle's state as a function of time (seconds from the epoch)."""

    def __init__(self, path: str, msg_dir: str = DEFAULT_MSG_DIR):
        self.path = path
        self.name = os.path.splitext(os.path.basename(path))[0]
        with open(path) as f:
            doc = yaml.safe_load(f)
        if not isinstance(doc, dict):
            raise ScenarioError(f"{path}: expected a mapping")
        known = {"description", "kind", "targets", "duration", "seed", "initial", "changes"}
        extra = set(doc) - known
        if extra:
            raise ScenarioError(f"{path}: unknown keys {sorted(extra)} (known: {sorted(known)})")
        self.description = doc.get("description", "")
        self.kind = doc.get("kind", "nominal")
        if self.kind not in ("nominal", "fault"):
            raise ScenarioError(f"{path}: kind must be nominal or fault")
        self.targets = list(doc.get("targets") or [])
        self.duration = float(doc["duration"])
        self.seed = doc.get("seed", 1)
        self.constants = {field: read_constants(msg_dir, t) for field, t in CONSTANT_OF.items()}
        initial = dict(DEFAULT_STATE)
        for key, value in (doc.get("initial") or {}).items():
            initial[key] = self._value(key, value, "initial")
        self.initial = initial
        # per field: sorted list of (at, ramp, value)
        self.segments: dict[str, list] = {k: [] for k in DEFAULT_STATE}
        last_at = -math.inf
        for i, change in enumerate(doc.get("changes") or []):
            where = f"changes[{i}]"
            change = dict(change)
            if "at" not in change:
                raise ScenarioError(f"{path}: {where} has no 'at'")
            at = float(change.pop("at"))
            if at < last_at:
                raise ScenarioError(f"{path}: {where}: changes must be in time order")
            if not 0 <= at <= self.duration:
                raise ScenarioError(f"{path}: {where}: at={at} outside [0, duration]")
            last_at = at
            ramp = float(change.pop("ramp", 0.0))
            if ramp and not any(k in NUMERIC for k in change):
                raise ScenarioError(f"{path}: {where}: 'ramp' applies to speed/steering only")
            if not change:
                raise ScenarioError(f"{path}: {where} changes nothing")
            for key, value in change.items():
                self.segments[key].append((at, ramp if key in NUMERIC else 0.0,
                                           self._value(key, value, where)))

    def _value(self, key, value, where):
        if key not in DEFAULT_STATE:
            raise ScenarioError(f"{self.path}: {where}: unknown state field '{key}' "
                                f"(known: {', '.join(DEFAULT_STATE)})")
        if key in NUMERIC:
            if not isinstance(value, (int, float)) or isinstance(value, bool):
                raise ScenarioError(f"{self.path}: {where}: {key} must be a number")
            return float(value)
        if key in ("engage", "emergency"):
            if not isinstance(value, bool):
                raise ScenarioError(f"{self.path}: {where}: {key} must be true or false")
            return value
        if value is None and key == "status_gear":
            return None
        if value not in self.constants[key]:
            raise ScenarioError(f"{self.path}: {where}: {key}: '{value}' is no constant of "
                                f"{CONSTANT_OF[key]} ({', '.join(self.constants[key])})")
        return value

    def field_at(self, key: str, t: float):
        value, segs = self.initial[key], self.segments[key]
        for i, (at, ramp, target) in enumerate(segs):
            if at > t:
                break
            if ramp > 0:
                start = value  # value reached when this change began
                if i + 1 < len(segs) and segs[i + 1][0] <= t:
                    # a later change started: the value it started from is where this ramp got to
                    frac = min(1.0, (segs[i + 1][0] - at) / ramp)
                else:
                    frac = min(1.0, (t - at) / ramp)
                value = start + (target - start) * frac
            else:
                value = target
        return value

    def state_at(self, t: float) -> dict:
        return {k: self.field_at(k, t) for k in DEFAULT_STATE}


# ---------------------------------------------------------------------------------------------
# messages

def stamp_of(ns: int) -> dict:
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def message(name: str, s: dict, stamp: dict, consts: dict) -> dict:
    """One message of topic `name` reporting vehicle state `s` (JSON as the .msg names the fields)."""
    c = lambda field: consts[field][s[field]]  # noqa: E731
    steering = round(s["steering"], 6)
    if name == "steer":
        return {"stamp": stamp, "steering_tire_angle": steering}
    if name == "gear":
        return {"stamp": stamp, "report": c("gear")}
    if name == "mode":
        return {"stamp": stamp, "mode": c("mode")}
    if name == "turn":
        return {"stamp": stamp, "report": c("turn")}
    if name == "hazard":
        return {"stamp": stamp, "report": c("hazard")}
    if name == "engage":
        return {"stamp": stamp, "engage": s["engage"]}
    if name == "failsafe":
        return {"stamp": stamp, "state": {"state": c("failsafe")}}
    if name == "emergency":
        return {"stamp": stamp, "emergency": s["emergency"]}
    if name == "status":
        shift = consts["status_gear"]
        gear_shift = s["status_gear"] or GEAR_SHIFT.get(s["gear"], "DRIVE")
        if s["hazard"] == "ENABLE":
            signal = 3  # TurnSignal.HAZARD
        else:
            signal = {"ENABLE_LEFT": 1, "ENABLE_RIGHT": 2}.get(s["turn"], 0)
        speed = round(s["speed"], 6)
        yaw = round(speed * math.tan(s["steering"]) / WHEELBASE, 6)
        return {"stamp": stamp, "status": {
            "twist": {"linear": {"x": speed, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": yaw}},
            "steering": {"data": steering},
            "turn_signal": {"data": signal},
            "gear_shift": {"data": shift[gear_shift]},
        }}
    raise ScenarioError(f"no message for topic '{name}'")


def generate(scenario: Scenario, topics: dict, rate_scale: float = 1.0, seed=None) -> dict:
    """Per topic name: a list of (stamp_ns, message dict), stamps on the topic's rate x rate_scale
    from `epoch`, each moved by seeded uniform jitter (at most 10% of the period, so stamps stay in
    order), sampled from the scenario at the stamp.

    Stamps are whole microseconds, distinct over all topics: rvc's merge takes messages whose
    stamps are equal as double seconds (about 0.24 us apart at today's epochs) as one event, and
    here every message is to be its own event (one step in discrete time)."""
    epoch_ns = int(topics.get("epoch", 1_700_000_000)) * 1_000_000_000
    seed = scenario.seed if seed is None else seed
    out, used = {}, set()
    for t in topics["topics"]:
        rate = float(t["rate"]) * rate_scale
        jitter_us = int(min(float(topics.get("jitter_ms", 3)) * 1e3, 0.1e6 / rate))
        rng = random.Random(f"{seed}:{scenario.name}:{t['name']}")
        msgs = []
        k = 0
        while k / rate < scenario.duration:
            offset = (round(k * 1e6 / rate) + jitter_us + rng.randint(-jitter_us, jitter_us)) * 1000
            while offset in used:  # taken by another topic: the next free microsecond
                offset += 1000
            used.add(offset)
            state = scenario.state_at(offset / 1e9)
            msgs.append((epoch_ns + offset, message(t["name"], state, stamp_of(epoch_ns + offset),
                                                    scenario.constants)))
            k += 1
        out[t["name"]] = msgs
    return out


def write_jsonl(messages: dict, out_dir: str) -> dict:
    os.makedirs(out_dir, exist_ok=True)
    paths = {}
    for name, msgs in messages.items():
        path = os.path.join(out_dir, f"{name}.jsonl")
        with open(path, "w") as f:
            for _, m in msgs:
                f.write(json.dumps(m, separators=(",", ":")) + "\n")
        paths[name] = path
    return paths


# ---------------------------------------------------------------------------------------------
# rosbag2 (MCAP) through rosbags

def typestore(msg_dir: str = DEFAULT_MSG_DIR):
    """A rosbags typestore with ROS 2 Humble's types plus the bundled Table-3 definitions."""
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg
    ts = get_typestore(Stores.ROS2_HUMBLE)
    types = {}
    for pkg in MSG_PACKAGES:
        folder = os.path.join(msg_dir, pkg, "msg")
        for fname in sorted(os.listdir(folder)):
            if fname.endswith(".msg"):
                with open(os.path.join(folder, fname)) as f:
                    types.update(get_types_from_msg(f.read(), f"{pkg}/msg/{fname[:-4]}"))
    ts.register(types)
    return ts


def to_rosbags(ts, type_name: str, value: dict):
    """A JSON message dict as an instance of the typestore's class (nested messages too)."""
    cls = ts.types[type_name]
    _, fields = ts.fielddefs[type_name]
    kwargs = {}
    for fname, (nodetype, detail) in fields:
        v = value[fname]
        if isinstance(v, dict):
            kwargs[fname] = to_rosbags(ts, detail, v)
        else:
            kwargs[fname] = v
    return cls(**kwargs)


def write_bag(messages: dict, topics: dict, bag_dir: str, msg_dir: str = DEFAULT_MSG_DIR) -> str:
    """A rosbag2 folder in MCAP storage (as `ros2 bag record -s mcap`), every message logged at its
    stamp, in stamp order. Returns the .mcap file's path."""
    from rosbags.rosbag2 import Writer
    from rosbags.rosbag2.enums import StoragePlugin
    ts = typestore(msg_dir)
    if os.path.exists(bag_dir):
        raise ScenarioError(f"{bag_dir} exists: rosbag2 writes a new folder")
    by_name = {t["name"]: t for t in topics["topics"]}
    with Writer(bag_dir, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conns = {name: w.add_connection(by_name[name]["topic"], by_name[name]["type"], typestore=ts)
                 for name in messages}
        events = sorted((ns, name, m) for name, msgs in messages.items() for ns, m in msgs)
        for ns, name, m in events:
            type_name = by_name[name]["type"]
            w.write(conns[name], ns, ts.serialize_cdr(to_rosbags(ts, type_name, m), type_name))
    bags = [f for f in os.listdir(bag_dir) if f.endswith(".mcap")]
    if len(bags) != 1:
        raise ScenarioError(f"{bag_dir}: expected one .mcap file, found {bags}")
    return os.path.join(bag_dir, bags[0])


# ---------------------------------------------------------------------------------------------
# rvc

def check_command(rvc: str, bag: str, topics: dict, properties: str, dense: bool) -> list[str]:
    cmd = [rvc, "check", bag]
    for t in topics["topics"]:
        cmd += ["--topic", f"{t['name']}={t['topic']}"]
    cmd += ["--sync", "merge", "--properties", properties]
    if dense:
        cmd.append("--dense")
    return cmd


def final_verdicts(stdout: str) -> dict:
    """Property -> (final value, time of the first false verdict or None) from rvc's verdict lines."""
    final, first_false = {}, {}
    for line in stdout.splitlines():
        if not line.strip():
            continue
        v = json.loads(line)
        final[v["property"]] = v["value"]
        if v["value"] is False and v["property"] not in first_false:
            first_false[v["property"]] = v["time"]
    return {p: (final[p], first_false.get(p)) for p in final}


def property_names(path: str) -> list[str]:
    with open(path) as f:
        doc = yaml.safe_load(f)
    if isinstance(doc, dict) and "properties" in doc:
        doc = doc["properties"]
    if isinstance(doc, dict):
        return list(doc)
    return [p["name"] for p in doc]


def cmd_generate(args, topics):
    scenario = Scenario(args.scenario, args.msg_dir)
    msgs = generate(scenario, topics, args.rate_scale, args.seed)
    if args.out:
        paths = write_jsonl(msgs, args.out)
        for name, path in paths.items():
            print(f"{path}: {len(msgs[name])} messages")
    if args.bag:
        print(f"{write_bag(msgs, topics, args.bag, args.msg_dir)}: "
              f"{sum(len(m) for m in msgs.values())} messages")
    if not args.out and not args.bag:
        print("nothing to do: give --out DIR and/or --bag DIR", file=sys.stderr)
        return 2
    return 0


def cmd_check(args, topics):
    scenario = Scenario(args.scenario, args.msg_dir)
    properties = args.properties or os.path.join(
        HERE, "properties-dense.yaml" if args.dense else "properties.yaml")
    work = args.work or tempfile.mkdtemp(prefix=f"rvc-{scenario.name}-")
    try:
        bag = write_bag(generate(scenario, topics, args.rate_scale, args.seed), topics,
                        os.path.join(work, "bag"), args.msg_dir)
        cmd = check_command(args.rvc, bag, topics, properties, args.dense)
        if not args.json:
            print("$ " + " ".join(cmd), file=sys.stderr)
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode not in (0, 1):
            sys.stderr.write(r.stderr)
            print(f"rvc check failed with exit status {r.returncode}", file=sys.stderr)
            return r.returncode
        verdicts = final_verdicts(r.stdout)
        names = property_names(properties)
        if args.json:
            print(json.dumps({p: "held" if verdicts[p][0] else "violated" for p in names}))
        else:
            print(f"scenario {scenario.name} ({scenario.kind}), {'dense' if args.dense else 'discrete'} time:")
            for p in names:
                value, first = verdicts.get(p, (None, None))
                text = {True: "held", False: "violated", None: "no verdict"}[value]
                if first is not None:
                    when = f"{first - topics.get('epoch', 0):.3f} s" if args.dense else f"step {first}"
                    text += f" (first false at {when})"
                print(f"  {p:28} {text}")
        return r.returncode
    finally:
        if not args.work:
            shutil.rmtree(work, ignore_errors=True)


def cmd_publish(args, topics):
    scenario = Scenario(args.scenario, args.msg_dir)
    work = args.work or tempfile.mkdtemp(prefix=f"rvc-{scenario.name}-")
    procs = []
    try:
        paths = write_jsonl(generate(scenario, topics, args.rate_scale, args.seed), work)
        for t in topics["topics"]:
            rate = float(t["rate"]) * args.rate_scale * args.speed
            cmd = [args.rvc, "replay", paths[t["name"]], "--to", f"dds:{t['topic']}", "--type", t["type"],
                   "--rate", f"{rate:g}", "--no-progress", "--wait-subscribers", str(args.wait_subscribers),
                   "--wait-timeout", f"{args.wait_timeout:g}", "--domain", str(args.domain)] + args.rvc_arg
            print("$ " + " ".join(cmd), file=sys.stderr)
            procs.append((t["name"], subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)))
        status = 0
        for name, p in procs:
            out, _ = p.communicate()
            summary = out.strip().splitlines()[-1] if out.strip() else ""
            print(f"{name}: exit {p.returncode} {summary}")
            status = status or p.returncode
        return status
    except KeyboardInterrupt:
        for _, p in procs:
            p.terminate()
        return 130
    finally:
        for _, p in procs:
            if p.poll() is None:
                p.kill()
        if not args.work:
            shutil.rmtree(work, ignore_errors=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("scenario", help="scenario YAML file (scenarios/*.yaml)")
    common.add_argument("--topics", default=DEFAULT_TOPICS, help="topics file (default: topics.yaml here)")
    common.add_argument("--msg-dir", default=DEFAULT_MSG_DIR,
                        help="folder of .msg definitions, PKG/msg/NAME.msg (default: rvc's bundled ones)")
    common.add_argument("--rate-scale", type=float, default=1.0, metavar="K",
                        help="multiply every topic's rate (stamps K times as dense; for load tests)")
    common.add_argument("--seed", default=None, help="jitter seed (default: the scenario's, else 1)")
    sub = ap.add_subparsers(dest="command", required=True)

    g = sub.add_parser("generate", parents=[common], help="write the nine JSON-lines files and/or a bag")
    g.add_argument("--out", help="folder for NAME.jsonl, one per topic")
    g.add_argument("--bag", help="write a rosbag2 MCAP bag into this (new) folder")

    c = sub.add_parser("check", parents=[common], help="write the bag and run rvc check on it")
    c.add_argument("--rvc", default="rvc", help="rvc binary (default: rvc on PATH)")
    c.add_argument("--dense", action="store_true", help="dense time (properties-dense.yaml)")
    c.add_argument("--properties", help="properties file (default: properties[-dense].yaml here)")
    c.add_argument("--work", help="keep the bag in this folder (default: a temporary one)")
    c.add_argument("--json", action="store_true", help="print one JSON object {property: held|violated}")

    p = sub.add_parser("publish", parents=[common], help="publish the topics on DDS with rvc replay")
    p.add_argument("--rvc", default="rvc", help="rvc binary (default: rvc on PATH)")
    p.add_argument("--speed", type=float, default=1.0,
                   help="wall-clock speed-up of publishing (stamps unchanged; default 1: real time)")
    p.add_argument("--domain", type=int, default=0, help="DDS domain id")
    p.add_argument("--wait-subscribers", type=int, default=1,
                   help="subscribers each topic waits for before publishing (rvc replay's option)")
    p.add_argument("--wait-timeout", type=float, default=30.0, help="seconds to wait for them")
    p.add_argument("--work", help="keep the JSON-lines files in this folder (default: a temporary one)")
    p.add_argument("--rvc-arg", action="append", default=[],
                   help="extra argument for every rvc replay (repeatable, e.g. --rvc-arg=--qos=ros2-default)")
    args = ap.parse_args(argv)
    try:
        topics = load_topics(args.topics)
        return {"generate": cmd_generate, "check": cmd_check, "publish": cmd_publish}[args.command](args, topics)
    except (ScenarioError, OSError, yaml.YAMLError) as e:
        print(f"vehicle.py: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
