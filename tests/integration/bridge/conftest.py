"""The real zenoh-bridge-ros2dds tier: rvc-ros2dds-bridge (tools/ros2dds-bridge, the crates.io
zenoh-plugin-ros2dds in a Zenoh router) between cyclonedds-Python and rvc. docs/zenoh.md, "The real
zenoh-bridge-ros2dds"."""
import os
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tests"))
sys.path.insert(0, os.path.join(ROOT, "tests", "integration", "participants"))
# fixtures (rvc) and hooks (skips fail under CI=true) shared by every pytest tier
from rvc_testlib import (BY_DESIGN, PLATFORM, pytest_make_collect_report, pytest_runtest_makereport,  # noqa: E402,F401
                         rvc, rvc_binary, transports_built)


@pytest.fixture(scope="session")
def bridge_bin():
    """The bridge binary: $RVC_ROS2DDS_BRIDGE (ctest passes what its build fixture made), else where
    scripts/build-ros2dds-bridge.sh puts it. Missing: a skip, which fails under CI=true."""
    path = os.environ.get("RVC_ROS2DDS_BRIDGE")
    if not path:
        r = subprocess.run(["bash", os.path.join(ROOT, "scripts", "build-ros2dds-bridge.sh"), "--path"],
                           capture_output=True, text=True)
        path = r.stdout.strip()
    if not path or not os.access(path, os.X_OK):
        pytest.skip(f"rvc-ros2dds-bridge not built ({path or 'no path'}): run scripts/build-ros2dds-bridge.sh")
    return path
