#!/usr/bin/env python3
"""Liveness detection: how long after `rvc monitor` is SIGKILLed its readers see it gone.

  python3 bench/liveness_detect.py [RVC]     (default build/release/rvc)

- DDS: a cyclonedds-Python reader of the monitor's verdict topic reads its liveliness-changed
  status; the time from SIGKILL to alive_count 0, for --liveliness-lease 1 and 2 (3 runs each).
- Zenoh: a liveliness subscriber on rvc/monitors/**; the time from SIGKILL to the DELETE of the
  monitor's token (3 runs). The kernel closes the killed process's TCP links at once; a host that
  vanishes (no close) is seen only when Zenoh's own lease expires.
Loopback only: the loopback-pinned CycloneDDS XML of `rvc dds-config`, Zenoh on tcp/127.0.0.1
without scouting. Figures: docs/diagnostics.md.
"""
import os
import sys
import json
import random
import signal
import subprocess
import time
RVC = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build", "release", "rvc")
cfg = "/tmp/rvc_liveness_cdds.xml"
subprocess.run([RVC, "dds-config", "-o", cfg], check=True)
os.environ["CYCLONEDDS_URI"] = f"file://{cfg}"
from dataclasses import dataclass
from cyclonedds.idl import IdlStruct
from cyclonedds.domain import DomainParticipant
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.qos import Policy, Qos
from cyclonedds.util import duration
import zenoh

@dataclass
class String_(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    data: str

def wait(pred, limit=60):
    t = time.monotonic()
    while time.monotonic() - t < limit:
        if pred(): return True
        time.sleep(0.005)
    return False

def dds_trial(lease, domain):
    mon = subprocess.Popen([RVC, "monitor", "--spec", "{ok}", "--input", "dds:/m/in", "--output", "dds:/m/v",
                            "--liveliness-lease", str(lease), "--domain", str(domain)], stderr=subprocess.DEVNULL)
    dp = DomainParticipant(domain)
    r = DataReader(dp, Topic(dp, "rt/m/v", String_), qos=Qos(Policy.Reliability.Reliable(duration(seconds=1))))
    assert wait(lambda: r.get_liveliness_changed_status().alive_count == 1)
    time.sleep(0.5)
    t0 = time.monotonic(); mon.send_signal(signal.SIGKILL); mon.wait()
    assert wait(lambda: r.get_liveliness_changed_status().alive_count == 0)
    return time.monotonic() - t0

def zenoh_trial():
    port = random.randint(20000, 29999)
    ep = f"tcp/127.0.0.1:{port}"
    mon = subprocess.Popen([RVC, "monitor", "--spec", "{ok}", "--input", "zenoh:m/in", "--output", "file:/dev/null",
                            "--name", "meas", "--mode", "peer", "--listen", ep, "--no-multicast-scouting"],
                           stderr=subprocess.DEVNULL)
    time.sleep(0.5)
    conf = zenoh.Config(); conf.insert_json5("mode", '"peer"'); conf.insert_json5("connect/endpoints", json.dumps([ep]))
    conf.insert_json5("listen/endpoints", '["tcp/127.0.0.1:0"]'); conf.insert_json5("scouting/multicast/enabled", "false")
    s = zenoh.open(conf)
    ev = []
    sub = s.liveliness().declare_subscriber("rvc/monitors/**", lambda smp: ev.append(smp.kind), history=True)
    assert wait(lambda: zenoh.SampleKind.PUT in ev)
    t0 = time.monotonic(); mon.send_signal(signal.SIGKILL); mon.wait()
    assert wait(lambda: zenoh.SampleKind.DELETE in ev)
    dt = time.monotonic() - t0
    sub.undeclare(); s.close()
    return dt

for lease in (1, 2):
    print(f"dds lease {lease}s:", [round(dds_trial(lease, 60 + lease * 5 + i), 2) for i in range(3)])
print("zenoh token:", [round(zenoh_trial(), 3) for i in range(3)])
