"""rvc replay -> (Zenoh | DDS) -> rvc monitor, between processes on loopback.

Oracle: `rvc check` on the same file (itself checked against Reelay by the
differential tier). Every run uses its own DDS domain / Zenoh port, so tests
can run in parallel. Nothing leaves loopback: DDS participants pin `lo`,
Zenoh uses explicit tcp/127.0.0.1 endpoints with multicast scouting off.
"""
import json
import os
import socket
import subprocess
import threading

import pytest

from conftest import transports_built

FAMILIES = ["AbsentAQ", "AbsentBQR", "AbsentBR", "AlwaysAQ", "AlwaysBQR",
            "AlwaysBR", "RecurBQR", "RecurGLB", "RespondBQR", "RespondGLB"]
_domain = [20 + (os.getpid() % 50) * 3]


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


class Net:
    """Endpoint URIs and flags for one isolated monitor/replay pair."""

    def __init__(self, transport, via_router=False):
        self.transport = transport
        self.router = None
        if transport == "dds":
            _domain[0] += 1
            d = str(_domain[0] % 230)
            self.topic = "dds:/rvc_test/in"
            self.out_topic = "dds:/rvc_test/verdicts"
            self.monitor_flags = ["--domain", d]
            self.replay_flags = ["--domain", d]
        else:
            port = free_port()
            self.topic = "zenoh:rvc_test/in"
            self.out_topic = "zenoh:rvc_test/verdicts"
            if via_router:
                self.router_port = port
                ep = f"tcp/127.0.0.1:{port}"
                self.monitor_flags = ["--mode", "client", "--connect", ep, "--no-multicast-scouting"]
                self.replay_flags = ["--mode", "client", "--connect", ep, "--no-multicast-scouting"]
            else:
                ep = f"tcp/127.0.0.1:{port}"
                self.monitor_flags = ["--mode", "peer", "--listen", ep, "--no-multicast-scouting"]
                self.replay_flags = ["--mode", "peer", "--connect", ep, "--no-multicast-scouting"]

    def start_router(self, rvc):
        self.router = subprocess.Popen([rvc, "router", "--listen", f"tcp/127.0.0.1:{self.router_port}",
                                        "--no-multicast-scouting"], stderr=subprocess.PIPE, text=True)

    def stop(self):
        if self.router:
            self.router.terminate()
            self.router.wait(timeout=10)


def monitor_and_replay(rvc, net, trace, spec_args, verdict_file, timeout=300, replay_args=()):
    mon = subprocess.Popen([rvc, "monitor", *spec_args, "--input", net.topic, "--output", f"file:{verdict_file}",
                            "--exit-on-eos", *net.monitor_flags], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True)
    rep = subprocess.run([rvc, "replay", trace, "--to", net.topic, "--wait-timeout", "20", *replay_args,
                          *net.replay_flags], capture_output=True, text=True, timeout=timeout)
    out, err = mon.communicate(timeout=timeout)
    assert rep.returncode == 0, rep.stderr
    stats = json.loads([l for l in err.splitlines() if l.startswith("{")][-1])
    return mon.returncode, stats, json.loads(rep.stdout.strip().splitlines()[-1]), err


def transports(rvc_path):
    return transports_built(rvc_path)


def pytest_generate_tests(metafunc):
    if "transport" in metafunc.fixturenames:
        from conftest import rvc_binary
        metafunc.parametrize("transport", transports_built(rvc_binary()) or ["none"])


def check_local(rvc, spec, trace):
    return subprocess.run([rvc, "check", "--all", "--spec", spec, trace], capture_output=True, text=True).stdout


@pytest.mark.parametrize("family", FAMILIES)
def test_verdicts_over_network_equal_check(rvc, tmp_path, transport, family):
    if transport == "none":
        pytest.skip("no network transport built")
    trace = str(tmp_path / "trace.jsonl")
    subprocess.run([rvc, "timescales", family, "--ubound", "100", "--duration", "20000", "--seed", "5", "-o", trace],
                   check=True)
    # flip some values so verdicts change along the trace
    lines = open(trace).read().splitlines()
    for i in range(137, len(lines), 997):
        e = json.loads(lines[i])
        e["p"] = not e["p"]
        lines[i] = json.dumps(e)
    open(trace, "w").write("\n".join(lines) + "\n")
    spec = subprocess.run([rvc, "timescales", family, "--ubound", "100", "--formula"], capture_output=True,
                          text=True, check=True).stdout.strip()
    net = Net(transport)
    out = tmp_path / "verdicts.jsonl"
    rc, stats, sent, _ = monitor_and_replay(rvc, net, trace, ["--all", "--spec", spec], out)
    assert sent["sent"] == 20000
    assert stats["received"] == 20000 and stats["checked"] == 20000
    assert stats["gaps"] == 0 and stats["duplicates"] == 0 and stats["rejected"] == 0
    assert out.read_text() == check_local(rvc, spec, trace)


def test_million_messages_at_max_rate_lose_nothing(rvc, tmp_path, transport):
    if transport == "none":
        pytest.skip("no network transport built")
    steps = int(os.environ.get("RVC_LOSS_TEST_MESSAGES", "1000000"))
    trace = str(tmp_path / "big.jsonl")
    subprocess.run([rvc, "timescales", "RespondGLB", "--ubound", "1000", "--duration", str(steps), "--seed", "2",
                    "-o", trace], check=True)
    spec = subprocess.run([rvc, "timescales", "RespondGLB", "--ubound", "1000", "--formula"], capture_output=True,
                          text=True, check=True).stdout.strip()
    net = Net(transport)
    rc, stats, sent, err = monitor_and_replay(rvc, net, trace, ["--spec", spec], tmp_path / "v.jsonl", timeout=600,
                                              replay_args=["--rate", "max"])
    assert sent["sent"] == steps
    assert stats["received"] == steps, err
    assert stats["checked"] == steps
    assert stats["gaps"] == 0 and stats["duplicates"] == 0 and stats["last_seq"] == steps
    assert rc == 0


def test_bad_payloads_are_counted_and_nothing_valid_is_lost(rvc, tmp_path, transport):
    if transport == "none":
        pytest.skip("no network transport built")
    good = [{"p": i % 3 != 0} for i in range(50)]
    lines = [json.dumps(e) for e in good]
    bad_at = {5: "not json", 17: '{"p": tru', 30: "[1,2,3]", 44: '{"p": "yes"}'}
    payloads = []
    for i, l in enumerate(lines):
        if i in bad_at:
            payloads.append(bad_at[i])
        payloads.append(l)
    trace = tmp_path / "mixed.jsonl"
    trace.write_text("\n".join(payloads) + "\n")
    clean = tmp_path / "clean.jsonl"
    clean.write_text("\n".join(lines) + "\n")
    net = Net(transport)
    out = tmp_path / "v.jsonl"
    rc, stats, sent, err = monitor_and_replay(rvc, net, str(trace), ["--all", "--spec", "once[:2]{p}"], out)
    assert stats["received"] == len(payloads)
    assert stats["rejected"] == 3                       # the wrong-typed one is a warning, not a reject
    assert stats["checked"] == len(payloads) - 3
    # sequence numbers of the bad messages are named (1-based seq = position + 1)
    seqs = [i + 1 + sorted(bad_at).index(i) for i in sorted(bad_at)]
    for s in seqs[:3]:
        assert f"seq {s}" in err
    assert "keeps its previous value" in err
    # every valid message was checked: the verdicts equal `rvc check` on the
    # valid messages, where the wrong-typed one is a step that keeps p's value
    expected = []
    for i, l in enumerate(lines):
        if i == 44:
            expected.append(json.dumps({"p": good[i - 1]["p"]}))
        expected.append(l)
    exp = tmp_path / "expected.jsonl"
    exp.write_text("\n".join(expected) + "\n")
    assert out.read_text() == check_local(rvc, "once[:2]{p}", str(exp))
    assert rc == 1  # once[:2]{p} fails at step 0 (p false); a violation outranks rejects


def test_verdicts_reach_a_second_monitor(rvc, tmp_path, transport):
    """Verdicts published on a topic are ordinary messages: a second rvc checks them."""
    if transport == "none":
        pytest.skip("no network transport built")
    if transport == "zenoh":
        pytest.skip("[by design] Zenoh verdict topics read by a second subscriber: covered by test_python_peers.py")
    trace = tmp_path / "t.jsonl"
    trace.write_text("".join(json.dumps({"p": i % 4 != 0}) + "\n" for i in range(40)))
    net = Net(transport)
    verdicts_seen = tmp_path / "seen.jsonl"
    # second monitor: reads verdict messages and checks a property over them
    second = subprocess.Popen([rvc, "monitor", "--all", "--spec", "{value} or not {value}", "--input", net.out_topic,
                               "--output", f"file:{verdicts_seen}", "--exit-on-eos", *net.monitor_flags],
                              stderr=subprocess.PIPE, text=True)
    # --wait-subscribers: without it the first verdicts could go out before
    # the second monitor's reader matched (volatile QoS), losing its EOS.
    first = subprocess.Popen([rvc, "monitor", "--all", "--spec", "{p}", "--input", net.topic,
                              "--output", net.out_topic, "--exit-on-eos", "--wait-subscribers", "1",
                              "--wait-timeout", "30", *net.monitor_flags],
                             stderr=subprocess.PIPE, text=True)
    rep = subprocess.run([rvc, "replay", str(trace), "--to", net.topic, *net.replay_flags], capture_output=True,
                         text=True, timeout=60)
    assert rep.returncode == 0, rep.stderr
    first.wait(timeout=60)
    second.wait(timeout=60)
    lines = verdicts_seen.read_text().splitlines()
    assert len(lines) == 40 and all(json.loads(l)["value"] is True for l in lines)
