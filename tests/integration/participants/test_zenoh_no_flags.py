"""Issue 16: Zenoh with no flags. Two rvc processes started as the README
shows them (no --listen/--connect) find each other on one host, and so does an
eclipse-zenoh Python peer left at its own defaults.

rvc's default scouts by multicast on the loopback interface only. The Python
peer's defaults scout on its default interface, which on a real host is the
outer one: that peer runs in a network namespace of our own that holds only
`lo`, so its discovery cannot leave the machine (the project's network rule)."""
import json
import os
import subprocess
import uuid

import pytest

from conftest import transports_built


def need_zenoh(rvc):
    if "zenoh" not in transports_built(rvc):
        pytest.fail("this rvc was built without the Zenoh transport")


def trace(tmp_path, n):
    p = tmp_path / "t.jsonl"
    p.write_text("".join('{"i":%d,"p":%s}\n' % (i, "true" if i % 3 else "false") for i in range(n)))
    return p


def test_two_rvc_processes_with_no_flags(rvc, tmp_path):
    need_zenoh(rvc)
    key = f"rvc_test/noflags/{uuid.uuid4().hex[:8]}"  # runs on one host must not cross
    out = tmp_path / "v.jsonl"
    mon = subprocess.Popen([rvc, "monitor", "--all", "--spec", "{p}", "--input", f"zenoh:{key}",
                            "--output", f"file:{out}", "--exit-on-eos", "--idle-timeout", "60"],
                           stderr=subprocess.PIPE, text=True)
    rep = subprocess.run([rvc, "replay", str(trace(tmp_path, 500)), "--to", f"zenoh:{key}", "--wait-timeout", "20"],
                         capture_output=True, text=True, timeout=60)
    _, err = mon.communicate(timeout=60)
    assert rep.returncode == 0, rep.stderr
    stats = json.loads([l for l in err.splitlines() if l.startswith("{")][-1])
    assert (stats["received"], stats["checked"], stats["gaps"], stats["eos"]) == (500, 500, 0, True), err
    values = [json.loads(l)["value"] for l in out.read_text().splitlines()]
    assert values == [bool(i % 3) for i in range(500)]
    assert mon.returncode == 1  # p is false at every third message


PY_SUB = r"""
import json, sys, time, zenoh
got = []
with zenoh.open(zenoh.Config()) as s:          # eclipse-zenoh's own defaults
    s.declare_subscriber(sys.argv[1], lambda smp: got.append(smp.payload.to_string()))
    print("ready", flush=True)
    deadline = time.time() + 30
    while time.time() < deadline and len(got) < int(sys.argv[2]):
        time.sleep(0.02)
print(json.dumps(got), flush=True)
"""


@pytest.fixture
def netns():
    if os.geteuid() != 0:
        pytest.fail("needs root to create a network namespace (ip netns)")
    name = f"rvc16-{os.getpid()}-{uuid.uuid4().hex[:6]}"
    subprocess.run(["ip", "netns", "add", name], check=True)
    try:
        subprocess.run(["ip", "netns", "exec", name, "ip", "link", "set", "lo", "up"], check=True)
        yield ["ip", "netns", "exec", name]
    finally:
        subprocess.run(["ip", "netns", "del", name], check=False)


def test_python_peer_with_its_own_defaults(rvc, tmp_path, netns):
    need_zenoh(rvc)
    import zenoh  # noqa: F401  (eclipse-zenoh, installed by scripts/install-deps.sh)
    key = "rvc_test/pydefaults"
    sub = subprocess.Popen([*netns, "python3", "-c", PY_SUB, key, "200"], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True)
    assert sub.stdout.readline().strip() == "ready", sub.stderr.read()
    rep = subprocess.run([*netns, rvc, "replay", str(trace(tmp_path, 199)), "--to", f"zenoh:{key}",
                          "--wait-timeout", "20"], capture_output=True, text=True, timeout=60)
    out, err = sub.communicate(timeout=60)
    assert rep.returncode == 0, rep.stderr
    got = json.loads(out.strip().splitlines()[-1])
    # 199 messages, then the end-of-stream marker (an empty payload with rvc's attachment).
    assert got[:-1] == trace(tmp_path, 199).read_text().splitlines()
    assert got[-1] == ""


def test_monitor_refuses_to_read_its_own_verdicts(rvc):
    need_zenoh(rvc)
    r = subprocess.run([rvc, "monitor", "--spec", "{p}", "--input", "zenoh:loop/**", "--output", "zenoh:loop/verdicts"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and "refusing to monitor its own output" in r.stderr, r.stderr
    r = subprocess.run([rvc, "monitor", "--spec", "{p}", "--input", "zenoh:in/**", "--output", "zenoh:loop/verdicts",
                        "--stats-output", "zenoh:in/stats", "--idle-timeout", "0.1"],
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and "'zenoh:in/stats'" in r.stderr, r.stderr
