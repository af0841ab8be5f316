"""rvc perf, rvc bridge and bench/baseline/run --quick: sanity checks.

All traffic on loopback (Zenoh tcp/127.0.0.1 with multicast scouting off,
DDS pinned to lo by rvc's generated configuration) or inside the network
namespaces the runner creates and removes. Timeouts are hang guards; nothing
here asserts a speed.
"""
import csv
import json
import os
import shutil
import socket
import subprocess
import sys
import time

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
RVC = os.environ.get("RVC_BIN") or os.path.join(ROOT, "build/release/rvc")
RUNNER = os.path.join(ROOT, "bench/baseline/run")
RELIABLE_SYSTEMS = {"zenoh", "dds", "dds-batch", "dds-zenoh"}


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    p = s.getsockname()[1]
    s.close()
    return p if 20000 <= p < 30000 else 20000 + p % 10000


def last_json(text):
    lines = [l for l in text.splitlines() if l.strip().startswith("{")]
    assert lines, f"no JSON line in output:\n{text}"
    return json.loads(lines[-1])


def pair(b_argv, a_argv, ready="ready on", timeout=60):
    """Starts side b, waits for its ready line, runs side a; both JSON summaries."""
    b = subprocess.Popen(b_argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.time() + 20
        seen = ""
        while ready not in seen and time.time() < deadline:
            line = b.stderr.readline()
            if not line:
                break
            seen += line
        assert ready in seen, f"{b_argv[2]} not ready: {seen}"
        a = subprocess.run(a_argv, capture_output=True, text=True, timeout=timeout)
        out, err = b.communicate(timeout=timeout)
        return last_json(a.stdout), a.returncode, last_json(out), b.returncode
    finally:
        if b.poll() is None:
            b.kill()
            b.wait()


def transport_flags(transport, side, port, domain):
    if transport == "zenoh":
        if side == "b":
            return ["--listen", f"tcp/127.0.0.1:{port}", "--no-multicast-scouting"]
        return ["--connect", f"tcp/127.0.0.1:{port}", "--listen", "tcp/127.0.0.1:0", "--no-multicast-scouting"]
    return ["--domain", str(domain)]


def perf_pair(transport, domain, key, server, client, client_args):
    """`rvc perf SERVER` (side b, listening) and `rvc perf CLIENT` (side a) on one key."""
    port = free_port()
    return pair([RVC, "perf", server, "-t", transport, "--key", key] + transport_flags(transport, "b", port, domain),
                [RVC, "perf", client, "-t", transport, "--key", key] + client_args
                + transport_flags(transport, "a", port, domain))


@pytest.mark.parametrize("transport,domain", [("zenoh", 0), ("dds", 21)])
def test_pub_sub_counts_every_message(transport, domain):
    pub, prc, sub, src = perf_pair(transport, domain, "rvc_perf_t1", "sub", "pub", ["--size", "1k", "--duration", "1"])
    assert prc == 0 and src == 0
    for k in ("transport", "size", "msgs_per_s", "mbps", "lost", "sent", "received"):
        assert k in sub and k in pub
    assert sub["transport"] == transport and sub["size"] == 1024
    assert pub["sent"] > 0 and sub["received"] == pub["sent"] == sub["sent"]
    assert sub["lost"] == 0 and sub["eos"] is True and sub["msgs_per_s"] > 0


@pytest.mark.parametrize("transport,domain", [("zenoh", 0), ("dds", 22)])
def test_ping_pong_reports_latency(transport, domain):
    ping, prc, pong, qrc = perf_pair(transport, domain, "rvc_perf_t2", "pong", "ping", ["--rate", "200", "--duration", "1"])
    assert prc == 0 and qrc == 0
    for k in ("transport", "size", "rate", "count", "mean_us", "min_us", "p50_us", "p90_us", "p99_us", "max_us"):
        assert k in ping
    assert ping["rate"] == 200 and ping["count"] > 0 and ping["lost"] == 0
    assert 0 < ping["min_us"] <= ping["p50_us"] <= ping["p90_us"] <= ping["p99_us"] <= ping["max_us"]
    assert pong["echoed"] == ping["sent"]


def test_bridge_forwards_dds_to_zenoh():
    port, domain = free_port(), 23
    sub = subprocess.Popen([RVC, "perf", "sub", "-t", "zenoh", "--key", "rvc_perf_t3"]
                           + transport_flags("zenoh", "b", port, 0), stdout=subprocess.PIPE,
                           stderr=subprocess.DEVNULL, text=True)
    bridge = subprocess.Popen([RVC, "bridge", "dds:rvc_perf_t3", "zenoh:rvc_perf_t3", "--dds-type", "frame",
                               "--exit-on-eos", "--domain", str(domain)] + transport_flags("zenoh", "a", port, 0),
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        time.sleep(1.0)  # the bridge waits for the Zenoh subscriber, pub waits for the bridge's reader
        pub = subprocess.run([RVC, "perf", "pub", "-t", "dds", "--key", "rvc_perf_t3", "--size", "100",
                              "--rate", "2000", "--duration", "1", "--domain", str(domain)],
                             capture_output=True, text=True, timeout=60)
        assert pub.returncode == 0, pub.stderr
        b_out, _ = bridge.communicate(timeout=60)
        s_out, _ = sub.communicate(timeout=60)
    finally:
        for p in (sub, bridge):
            if p.poll() is None:
                p.kill()
                p.wait()
    sent = last_json(pub.stdout)["sent"]
    routes = last_json(b_out)["routes"]
    got = last_json(s_out)
    assert routes[0]["forwarded"] == sent and routes[0]["eos"] == 1
    assert got["received"] == sent and got["lost"] == 0 and got["eos"] is True


def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_quick_baseline_runs(tmp_path):
    r = subprocess.run([sys.executable, RUNNER, "--quick", "--rvc", RVC, "--out", str(tmp_path), "--no-docs"],
                       capture_output=True, text=True, timeout=400)
    assert r.returncode == 0, r.stdout + r.stderr
    rows = read_rows(tmp_path / "baseline.csv")
    assert (tmp_path / "baseline.md").exists()
    rvc_rows = [x for x in rows if x["system"] in RELIABLE_SYSTEMS]
    assert {x["system"] for x in rvc_rows} == RELIABLE_SYSTEMS
    assert {x["setting"] for x in rvc_rows} >= {"loopback", "inproc"}
    for x in rvc_rows:
        assert x["ok"] == "True", x
        if x["kind"] == "throughput":
            assert float(x["msgs_per_s"]) > 0 and int(x["received"]) > 0
            assert int(x["lost"]) == 0, x  # reliable
        else:
            assert int(x["count"]) > 0 and float(x["p50_us"]) > 0
    dds_rows = [x for x in rows if x["system"] == "ddsperf"]
    if shutil.which("ddsperf"):
        assert {x["kind"] for x in dds_rows} == {"throughput", "latency"}
        assert any(x["ok"] == "True" for x in dds_rows if x["kind"] == "throughput"), dds_rows
        assert any(x["ok"] == "True" for x in dds_rows if x["kind"] == "latency"), dds_rows
    else:
        assert not dds_rows


def netns_usable():
    if os.geteuid() != 0 or shutil.which("ip") is None:
        return False
    names = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True).stdout
    return "rvcA" not in names and "rvcB" not in names  # not while another run uses them


@pytest.mark.skipif(not netns_usable(), reason="needs root, iproute2 and free namespace names rvcA/rvcB")
def test_netns_setting_is_created_and_removed(tmp_path):
    r = subprocess.run([sys.executable, RUNNER, "--settings", "netns", "--systems", "zenoh,dds",
                        "--sizes", "1k", "--rates", "max", "--tput-seconds", "1", "--rvc", RVC,
                        "--out", str(tmp_path), "--no-docs"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    rows = read_rows(tmp_path / "baseline.csv")
    assert len(rows) == 4 and all(x["ok"] == "True" and x["setting"] == "netns" for x in rows), rows
    names = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True).stdout
    assert "rvcA" not in names and "rvcB" not in names


@pytest.mark.parametrize("argv,needle", [
    (["pub", "--rate", "fast"], "--rate"),
    (["pub", "--size", "0"], "--size"),
    (["pub", "--size", "1.5k7"], "--size"),
    (["pub", "--write-batch"], "--write-batch"),
    (["ping", "--duration", "0"], "--duration"),
    (["pub", "--transport", "mqtt"], "transport"),
])
def test_bad_options_are_usage_errors(argv, needle):
    r = subprocess.run([RVC, "perf", *argv, "--timeout", "1"], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2, r
    assert needle in r.stderr + r.stdout


def test_inproc_sizes_and_suffixes():
    r = subprocess.run([RVC, "perf", "pub", "--inproc", "-t", "zenoh", "--size", "64KiB", "--rate", "2k",
                        "--duration", "0.5", "--listen", "tcp/127.0.0.1:0", "--no-multicast-scouting"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    res = last_json(r.stdout)
    assert res["role"] == "inproc" and res["size"] == 65536
    assert res["received"] == res["sent"] > 0 and res["lost"] == 0
    assert res["sent"] <= 1001  # paced: 2 kHz for 0.5 s (a count, not a speed)
