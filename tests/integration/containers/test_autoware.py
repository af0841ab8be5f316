"""The Autoware case study's two deployments in containers (examples/autoware, issue 13), short:
one fault scenario published 4x faster than its stamps (stamps, and so verdicts, unchanged).
- setup 1: the simulated vehicle (nine `rvc replay --type` publishers) and the RV container on one
  DDS network;
- setup 2: vehicle and a DDS->Zenoh bridge (the nine topics only, keys as zenoh-bridge-ros2dds
  names them) on host A's network, a Zenoh router on both networks, the RV container on host B's.
Oracle: the verdicts written down in examples/autoware/expected.yaml; every message the vehicle
sent is received and checked (0 lost, none dropped late by the synchronizer), and in setup 2 the
bridge forwarded exactly what was sent.
"""
import importlib.util
import os
import subprocess
import sys

import pytest

from test_containers import IMAGE, ROOT, docker, image  # noqa: F401 (fixtures)

_spec = importlib.util.spec_from_file_location("aw_deploy", os.path.join(ROOT, "examples", "autoware", "deploy.py"))
aw = importlib.util.module_from_spec(_spec)
sys.modules["aw_deploy"] = aw
_spec.loader.exec_module(aw)


@pytest.mark.parametrize("setup", [1, 2])
def test_autoware_setup(image, setup):  # noqa: F811
    d = aw.Deployment(setup, "fault-hazard-late", dense=(setup == 2), speed=4, image=IMAGE)
    res = d.run(timeout=300)
    left = subprocess.run(["docker", "ps", "-aq", "--filter", "label=com.docker.compose.project=" + d.project],
                          capture_output=True, text=True).stdout.split()
    assert not left, "containers left behind: %s" % left
    info = res["monitor_log"]
    assert res["verdicts"] == res["expected"], info
    assert res["monitor_exit"] == 1, info  # the fault scenario violates its property
    expected_sent = sum(d.sent_expected.values())
    assert res["sent"] == expected_sent and res["received"] == expected_sent, (res["topics"], info)
    assert res["lost"] == 0 and res["rejected"] == 0, (res["topics"], info)
    assert res["sets"] > 0
    if setup == 2:
        routes = res["bridge"]["routes"]
        assert len(routes) == 9
        assert sum(r["forwarded"] for r in routes) == expected_sent
    print("\nsetup %d: %d messages, %d sets, resources %s" % (setup, res["received"], res["sets"], res["resources"]))
