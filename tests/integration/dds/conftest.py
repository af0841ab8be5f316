"""Fixtures for the dds: transport interop tests (Python cyclonedds + rosbags).

Network safety: before any cyclonedds participant exists, CYCLONEDDS_URI is
pointed at the loopback-only configuration that rvc itself generates
(`rvc_dds_probe config`), and the file is checked to name only `lo`. The C++
probe creates its domain from the same generated XML in-process.
"""
from __future__ import annotations

import atexit
import itertools
import os
import re
import subprocess
import tempfile
import uuid
from dataclasses import dataclass
from pathlib import Path

import pytest

import sys

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
# hooks shared by every pytest tier: a skip fails under CI=true
from rvc_testlib import pytest_make_collect_report, pytest_runtest_makereport  # noqa: E402,F401

PROBE = os.environ.get("RVC_DDS_PROBE")
HANG_GUARD_S = 60  # only guards against hangs; no test asserts on timing


def _loopback_config() -> str:
    if not PROBE or not Path(PROBE).is_file():
        raise RuntimeError("set RVC_DDS_PROBE to the built rvc_dds_probe (ctest does this)")
    path = Path(tempfile.gettempdir()) / f"rvc_dds_pytest_{os.getpid()}.xml"
    subprocess.run([PROBE, "config", "--output", str(path)], check=True, timeout=HANG_GUARD_S)
    xml = path.read_text()
    names = re.findall(r'<NetworkInterface[^>]*name="([^"]*)"', xml)
    if names != ["lo"] or "<AllowMulticast>false</AllowMulticast>" not in xml:
        raise RuntimeError(f"generated config is not loopback-only:\n{xml}")
    return str(path)


# Set at import, i.e. before any test module creates a DomainParticipant.
CONFIG_FILE = _loopback_config()
atexit.register(lambda: Path(CONFIG_FILE).unlink(missing_ok=True))
os.environ["CYCLONEDDS_URI"] = "file://" + CONFIG_FILE

# Distinct domain ids for the tests of one run (C++ tests use 40..49).
_domains = itertools.count(70)


@pytest.fixture
def domain() -> int:
    d = next(_domains)
    assert d < 120, "out of test domain ids"
    return d


@pytest.fixture
def topic() -> str:
    return "/rvc_py/t" + uuid.uuid4().hex[:12]


@pytest.fixture
def probe() -> str:
    return PROBE


@dataclass
class ProbeFrame:
    seq: int
    eos: bool
    payload: bytes


def parse_probe_output(text: str):
    """Frames and counters printed by `rvc_dds_probe sub`."""
    import json

    frames, counters = [], None
    for line in text.splitlines():
        if not line.startswith("{"):
            continue
        obj = json.loads(line)
        if "counters" in obj:
            counters = obj["counters"]
        else:
            frames.append(ProbeFrame(obj["seq"], obj["eos"], bytes.fromhex(obj["payload_hex"])))
    return frames, counters


def start_probe_sub(topic: str, domain: int, *extra: str) -> subprocess.Popen:
    proc = subprocess.Popen(
        [PROBE, "sub", topic, "--domain", str(domain), "--timeout-ms", str(HANG_GUARD_S * 1000), *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    ready = proc.stdout.readline()
    assert ready.startswith("READY "), f"probe did not start: {ready!r} {proc.stderr.read() if proc.poll() is not None else ''}"
    return proc


# Sockets ------------------------------------------------------------------


def _hex_ip(h: str) -> str:
    import ipaddress
    import struct

    raw = bytes.fromhex(h)
    if len(raw) == 4:
        return str(ipaddress.IPv4Address(struct.pack("<I", struct.unpack(">I", raw)[0])))
    words = [struct.pack("<I", struct.unpack(">I", raw[i : i + 4])[0]) for i in range(0, 16, 4)]
    return str(ipaddress.IPv6Address(b"".join(words)))


def process_sockets(pid: int):
    """[(table, local_ip, local_port, remote_ip, remote_port)] of a process's inet sockets."""
    inodes = set()
    for fd in Path(f"/proc/{pid}/fd").iterdir():
        try:
            target = os.readlink(fd)
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(target[8:-1])
    out = []
    for table in ("udp", "udp6", "tcp", "tcp6"):
        lines = Path(f"/proc/{pid}/net/{table}").read_text().splitlines()[1:]
        for line in lines:
            cols = line.split()
            if cols[9] not in inodes:
                continue
            lip, lport = cols[1].split(":")
            rip, rport = cols[2].split(":")
            out.append((table, _hex_ip(lip), int(lport, 16), _hex_ip(rip), int(rport, 16)))
    return out
