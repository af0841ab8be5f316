import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
# fixtures (rvc) and hooks (skips fail under CI=true) shared by every pytest tier
from rvc_testlib import (BY_DESIGN, PLATFORM, pytest_make_collect_report, pytest_runtest_makereport,  # noqa: E402,F401
                         rvc, rvc_binary, transports_built)


# Tests that read a ROS 2 bag need the MCAP reader, which lives in the Rust library; the sanitizer
# tiers build rvc without it (RVC_WITH_ZENOH=OFF) and set RVC_NO_MCAP=1, which deselects exactly
# these tests (named in the run's summary as deselected, never as passed or skipped).
def pytest_configure(config):
    config.addinivalue_line("markers", "needs_mcap: reads a ROS 2 bag (MCAP): needs rvc's Rust library")


def pytest_collection_modifyitems(config, items):
    if not os.environ.get("RVC_NO_MCAP"):
        return
    dropped = [i for i in items if i.get_closest_marker("needs_mcap")]
    if dropped:
        config.hook.pytest_deselected(items=dropped)
        items[:] = [i for i in items if not i.get_closest_marker("needs_mcap")]
