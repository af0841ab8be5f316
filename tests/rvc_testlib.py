"""Shared by every pytest tier (each conftest.py imports it): finding the rvc binary, the
transports it was built with, and visible skips.

Visible skips: under CI (CI=true) a skipped test fails, because a missing oracle (reelay,
eclipse-zenoh, cyclonedds, Docker) must never read as a pass. Two kinds of skip stay skips,
and say so in their reason:
  "[platform] ..."  the machine cannot do it at all (this kernel has no ipvlan);
  "[by design] ..." the case is covered elsewhere and named there.
Outside CI a skip stays a skip, so a developer without Docker can still run the rest.
"""
from __future__ import annotations

import os
import shutil
import subprocess

import pytest

PLATFORM = "[platform]"
BY_DESIGN = "[by design]"


def in_ci() -> bool:
    return os.environ.get("CI", "").strip().lower() in ("1", "true", "yes")


def rvc_binary() -> str:
    path = os.environ.get("RVC_BIN")
    if path:
        return path
    root = os.path.dirname(os.path.abspath(__file__))
    for preset in ("release", "core", "debug"):
        candidate = os.path.join(root, "..", "build", preset, "rvc")
        if os.path.exists(candidate):
            return os.path.abspath(candidate)
    found = shutil.which("rvc")
    if found:
        return found
    pytest.exit("rvc binary not found: build first or set RVC_BIN", returncode=2)


@pytest.fixture(scope="session")
def rvc():
    return rvc_binary()


def transports_built(rvc: str) -> list[str]:
    """Transports compiled into this rvc (from `rvc monitor --help`)."""
    out = subprocess.run([rvc, "monitor", "--help"], capture_output=True, text=True).stdout
    found = []
    if "--domain" in out:
        found.append("dds")
    if "--connect" in out:
        found.append("zenoh")
    return found


def _skip_reason(report) -> str:
    lr = report.longrepr
    if isinstance(lr, tuple) and len(lr) == 3:
        return str(lr[2])
    return str(lr)


def skip_allowed_in_ci(reason: str) -> bool:
    reason = reason.removeprefix("Skipped: ").strip()
    return reason.startswith(PLATFORM) or reason.startswith(BY_DESIGN)


def _fail_hidden_skip(report) -> None:
    if not in_ci() or not report.skipped or hasattr(report, "wasxfail"):
        return
    reason = _skip_reason(report)
    if skip_allowed_in_ci(reason):
        return
    report.outcome = "failed"
    report.longrepr = ("CI=true: a skipped test is a failure (its oracle or dependency is missing; "
                       "scripts/install-deps.sh installs it). Skip reason: " + reason)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    _fail_hidden_skip(outcome.get_result())


@pytest.hookimpl(hookwrapper=True)
def pytest_make_collect_report(collector):
    # a module-level pytest.importorskip skips the whole module at collection
    outcome = yield
    _fail_hidden_skip(outcome.get_result())


def dds_matched(entity) -> int:
    """How many peers a cyclonedds-Python DataWriter or DataReader has matched now.

    Reads the PUBLICATION/SUBSCRIPTION_MATCHED status, one call. cyclonedds-Python's
    get_matched_subscriptions() asks for the count, allocates, then asks again: a peer that
    matches between the two calls makes it index past its array (IndexError, seen in CI).
    """
    if hasattr(entity, "get_publication_matched_status"):
        return int(entity.get_publication_matched_status().current_count)
    return int(entity.get_subscription_matched_status().current_count)


def write_mcap_bag(path, topic, type_name, schema_text, samples):
    """One topic of CDR samples (bytes) in an MCAP file, as a ROS 2 recorder writes it, with the
    `mcap` package as the independent writer; log times 0, 1, 2, ... ns."""
    from mcap.writer import Writer
    with open(path, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2", library="rvc tests")
        sid = w.register_schema(name=type_name, encoding="ros2msg", data=schema_text.encode())
        cid = w.register_channel(topic=topic, message_encoding="cdr", schema_id=sid)
        for k, data in enumerate(samples):
            w.add_message(channel_id=cid, log_time=k, publish_time=k, sequence=k, data=bytes(data))
        w.finish()
    return str(path)


def memory_capped(mib: int) -> dict:
    """subprocess.run keywords that cap a child rvc's memory at `mib` MiB, so an over-allocation fails
    the run: an address-space limit (RLIMIT_AS), or, for an AddressSanitizer build (whose shadow memory
    needs terabytes of address space), ASan's own caps on resident memory and on one allocation."""
    asan = os.environ.get("ASAN_OPTIONS")
    if asan is not None:
        env = dict(os.environ, ASAN_OPTIONS=f"{asan}:hard_rss_limit_mb={mib}:max_allocation_size_mb={mib}")
        return {"env": env}
    import resource
    limit = mib << 20
    return {"preexec_fn": lambda: resource.setrlimit(resource.RLIMIT_AS, (limit, limit))}
