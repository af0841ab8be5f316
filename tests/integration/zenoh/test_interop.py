"""Interop between rvc's C++ Zenoh transport and the Python binding.

Run through run_interop.py (ctest: zenoh.python_interop), or directly:
    RVC_ZENOH_PROBE=build/.../rvc_zenoh_probe python3 -m pytest -q test_interop.py

Network safety: every session here uses explicit tcp/127.0.0.1 endpoints
with multicast scouting disabled; nothing is sent beyond loopback. Timeouts
only guard against hangs; no test asserts on elapsed time.
"""
import os
import queue
import random
import socket
import struct
import subprocess
import threading
import time
import uuid

import pytest

zenoh = pytest.importorskip("zenoh")

PROBE = os.environ.get("RVC_ZENOH_PROBE", "")
HANG_GUARD = 60.0  # seconds; a bound on waiting, never an assertion on speed

pytestmark = pytest.mark.skipif(not PROBE, reason="RVC_ZENOH_PROBE not set")


# ---- helpers ---------------------------------------------------------------

def free_port() -> int:
    """A free port on 127.0.0.1 from 20000-29999 (below the ephemeral range,
    so outgoing connections cannot take it before we use it)."""
    for _ in range(200):
        port = random.randint(20000, 29999)
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    with socket.socket() as s:  # fall back to a kernel-chosen port
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def ep(port: int) -> str:
    return f"tcp/127.0.0.1:{port}"


def unique_key(name: str) -> str:
    return f"rvc/interop/{name}/{uuid.uuid4().hex[:8]}"


def py_session(mode="peer", listen=(), connect=()):
    conf = zenoh.Config()
    conf.insert_json5("mode", f'"{mode}"')
    if mode == "client":
        listen = ()
    elif not listen:
        listen = ("tcp/127.0.0.1:0",)  # Zenoh's default would be every interface
    conf.insert_json5("listen/endpoints", str(list(listen)).replace("'", '"'))
    conf.insert_json5("connect/endpoints", str(list(connect)).replace("'", '"'))
    conf.insert_json5("scouting/multicast/enabled", "false")
    return zenoh.open(conf)


def rvc_attachment(seq: int, eos: bool = False) -> bytes:
    """The documented rvc attachment: u64 LE seq + flags byte (bit 0 = EOS)."""
    return struct.pack("<QB", seq, 1 if eos else 0)


def matching(pub) -> bool:
    status = pub.matching_status
    status = status() if callable(status) else status
    return bool(getattr(status, "matching", status))


def wait_matching(pub):
    deadline = time.monotonic() + HANG_GUARD
    while not matching(pub):
        assert time.monotonic() < deadline, "no subscriber matched"
        time.sleep(0.01)


class Probe:
    """A running rvc_zenoh_probe with line-by-line access to its output."""

    def __init__(self, *args):
        self.proc = subprocess.Popen(
            [PROBE, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.out: "queue.Queue[str | None]" = queue.Queue()
        self.err: "queue.Queue[str | None]" = queue.Queue()
        for stream, q in ((self.proc.stdout, self.out), (self.proc.stderr, self.err)):
            threading.Thread(target=self._pump, args=(stream, q), daemon=True).start()

    @staticmethod
    def _pump(stream, q):
        for line in stream:
            q.put(line.rstrip("\n"))
        q.put(None)

    def expect(self, prefix: str, stream: str = "out") -> str:
        q = self.out if stream == "out" else self.err
        seen = []
        while True:
            try:
                line = q.get(timeout=HANG_GUARD)
            except queue.Empty:
                pytest.fail(f"probe printed no '{prefix}' line; saw {seen}")
            if line is None:
                pytest.fail(f"probe ended before '{prefix}' (rc={self.proc.wait()}); saw {seen}")
            if line.startswith(prefix):
                return line
            seen.append(line)

    def lines_until_exit(self) -> list:
        rc = self.proc.wait(timeout=HANG_GUARD)
        lines = []
        while (line := self.out.get(timeout=HANG_GUARD)) is not None:
            lines.append(line)
        assert rc == 0, f"probe exited {rc}: {lines}"
        return lines

    def stop(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=HANG_GUARD)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        return self.proc.returncode


@pytest.fixture
def probes():
    started = []

    def start(*args):
        p = Probe(*args)
        started.append(p)
        return p

    yield start
    for p in started:
        p.stop()


@pytest.fixture
def router(probes):
    """A C++ router (`rvc_zenoh_probe router`) on a free loopback port."""
    port = free_port()
    r = probes("router", "--listen", ep(port))
    r.expect("rvc router:", stream="err")
    yield port
    assert r.stop() == 0, "router did not stop cleanly on SIGTERM"


class Collector:
    def __init__(self):
        self.samples = []
        self.eos = threading.Event()
        self.lock = threading.Lock()

    def __call__(self, sample):
        att = sample.attachment
        att = att.to_bytes() if att is not None else None
        with self.lock:
            self.samples.append((sample.payload.to_bytes(), att))
        if att is not None and len(att) >= 9 and att[8] & 1:
            self.eos.set()

    def wait_eos(self):
        assert self.eos.wait(HANG_GUARD), f"no EOS; got {len(self.samples)} samples"
        with self.lock:
            return list(self.samples)


def publish_from_python(session, key, n, plain=2):
    """n numbered samples with rvc attachments, `plain` without any, then EOS."""
    pub = session.declare_publisher(key, congestion_control=zenoh.CongestionControl.BLOCK)
    wait_matching(pub)
    for i in range(1, n + 1):
        pub.put(f"py-{i}".encode(), attachment=rvc_attachment(i))
    for i in range(plain):
        pub.put(b'{"plain":%d}' % i)
    pub.put(b"", attachment=rvc_attachment(n, eos=True))
    return pub


def check_probe_sub_output(lines, n, plain=2):
    data = [ln.split(" ") for ln in lines if ln.startswith("DATA")]
    eos = [ln for ln in lines if ln.startswith("EOS")]
    assert len(data) == n + plain
    for i, (_, seq, hexpayload) in enumerate(data[:n], start=1):
        assert int(seq) == i
        assert bytes.fromhex(hexpayload) == f"py-{i}".encode()
    for i, (_, seq, hexpayload) in enumerate(data[n:]):
        assert int(seq) == 0  # no attachment: unknown seq
        assert bytes.fromhex(hexpayload) == b'{"plain":%d}' % i
    assert eos == [f"EOS {n}"]


def check_python_received(samples, n, prefix="msg-"):
    assert len(samples) == n + 1
    publishers = set()
    for i, (payload, att) in enumerate(samples[:n], start=1):
        assert payload == f"{prefix}{i}".encode()
        assert att is not None and len(att) == 17  # seq, flags, publisher id (docs/zenoh.md)
        seq, flags, publisher = struct.unpack("<QBQ", att)
        assert (seq, flags) == (i, 0)
        publishers.add(publisher)
    payload, att = samples[n]
    assert payload == b""
    seq, flags, publisher = struct.unpack("<QBQ", att)
    assert (seq, flags) == (n, 1)
    publishers.add(publisher)
    assert len(publishers) == 1 and 0 not in publishers  # one rvc sink, one nonzero id


# ---- peer to peer ------------------------------------------------------------

def test_python_pub_to_cpp_sub_peer(probes):
    port, key, n = free_port(), unique_key("py2cpp"), 200
    sub = probes("sub", "--key", key, "--listen", ep(port))
    sub.expect("READY")
    session = py_session(connect=[ep(port)])
    try:
        publish_from_python(session, key, n)
        check_probe_sub_output(sub.lines_until_exit(), n)
    finally:
        session.close()


def test_cpp_pub_to_python_sub_peer(probes):
    port, key, n = free_port(), unique_key("cpp2py"), 200
    session = py_session(listen=[ep(port)])
    try:
        got = Collector()
        session.declare_subscriber(key, got)
        pub = probes("pub", "--key", key, "--count", str(n), "--connect", ep(port))
        pub.lines_until_exit()
        check_python_received(got.wait_eos(), n)
    finally:
        session.close()


def test_cpp_pub_without_seq_to_python(probes):
    port, key = free_port(), unique_key("noseq")
    session = py_session(listen=[ep(port)])
    try:
        got = Collector()
        session.declare_subscriber(key, got)
        pub = probes("pub", "--key", key, "--count", "3", "--no-seq", "--connect", ep(port))
        pub.lines_until_exit()
        samples = got.wait_eos()
        assert [p for p, _ in samples[:3]] == [b"msg-1", b"msg-2", b"msg-3"]
        assert all(a is None for _, a in samples[:3])
    finally:
        session.close()


def test_python_subscribers_announce_for_wait_n(probes):
    """Python subscribers that declare the documented liveliness token are
    counted by the C++ publisher waiting for two subscribers."""
    port, key, n = free_port(), unique_key("announce"), 20
    session = py_session(listen=[ep(port)])
    try:
        got = [Collector(), Collector()]
        subs, tokens = [], []
        pub = probes("pub", "--key", key, "--count", str(n), "--wait", "2",
                     "--connect", ep(port))
        for i, c in enumerate(got):
            subs.append(session.declare_subscriber(key, c))
            tokens.append(session.liveliness().declare_token(f"rvc/subscribers/py-{i}/{key}"))
        pub.lines_until_exit()
        for c in got:
            check_python_received(c.wait_eos(), n)
    finally:
        session.close()


# ---- through the C++ router, everyone in client mode -------------------------

def test_python_client_pub_to_cpp_client_sub_via_router(probes, router):
    key, n = unique_key("routed-py2cpp"), 100
    sub = probes("sub", "--key", key, "--mode", "client", "--connect", ep(router))
    sub.expect("READY")
    session = py_session(mode="client", connect=[ep(router)])
    try:
        publish_from_python(session, key, n)
        check_probe_sub_output(sub.lines_until_exit(), n)
    finally:
        session.close()


def test_cpp_client_pub_to_python_client_sub_via_router(probes, router):
    key, n = unique_key("routed-cpp2py"), 100
    session = py_session(mode="client", connect=[ep(router)])
    try:
        got = Collector()
        session.declare_subscriber(key, got)
        pub = probes("pub", "--key", key, "--count", str(n), "--prefix", "r-",
                     "--mode", "client", "--connect", ep(router))
        pub.lines_until_exit()
        check_python_received(got.wait_eos(), n, prefix="r-")
    finally:
        session.close()


def test_probe_fails_without_router():
    """A client with nowhere to connect must fail, not hang or go multicast."""
    port = free_port()  # nothing listens here
    proc = subprocess.run(
        [PROBE, "sub", "--key", "rvc/x", "--mode", "client", "--connect", ep(port),
         "--timeout", "5"],
        capture_output=True, text=True, timeout=HANG_GUARD)
    assert proc.returncode == 1, proc
    assert "zenoh" in proc.stderr
