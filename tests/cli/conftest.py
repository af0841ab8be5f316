import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
# fixtures (rvc) and hooks (skips fail under CI=true) shared by every pytest tier
from rvc_testlib import (BY_DESIGN, PLATFORM, pytest_make_collect_report, pytest_runtest_makereport,  # noqa: E402,F401
                         rvc, rvc_binary, transports_built)


# Tests that read a ROS 2 bag or use a zenoh: endpoint need rvc's Rust library (the MCAP reader, the
# Zenoh transport); the sanitizer tiers build rvc without it (RVC_WITH_ZENOH=OFF) and set
# RVC_NO_RUST=1, which deselects exactly these tests (counted as deselected, never passed or skipped).
def pytest_configure(config):
    config.addinivalue_line("markers", "needs_rust: reads a ROS 2 bag or uses Zenoh: needs rvc's Rust library")


def pytest_collection_modifyitems(config, items):
    if not os.environ.get("RVC_NO_RUST"):
        return
    dropped = [i for i in items if i.get_closest_marker("needs_rust")]
    if dropped:
        config.hook.pytest_deselected(items=dropped)
        items[:] = [i for i in items if not i.get_closest_marker("needs_rust")]
