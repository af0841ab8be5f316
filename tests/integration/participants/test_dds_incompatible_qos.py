"""A DDS publisher whose QoS rvc's reader cannot match is named (issue 25).

CycloneDDS never delivers such a publisher's samples, so `rvc monitor` used to end with only "nothing
was received ... exit 6". Now the requested-incompatible-QoS status is said on stderr as soon as
CycloneDDS reports it, once per policy, and repeated in the final "nothing was received" line. The
publisher is CycloneDDS's Python binding, on the loopback-pinned XML that `rvc dds-config` prints.
"""
import os
import subprocess
import threading
import time

import pytest

from conftest import transports_built

HANG_GUARD = 60


@pytest.fixture
def string_type(rvc, tmp_path, monkeypatch):
    if "dds" not in transports_built(rvc):
        pytest.fail("this rvc was built without DDS")
    cfg = tmp_path / "cyclonedds.xml"
    subprocess.run([rvc, "dds-config", "-o", str(cfg)], check=True)
    assert 'name="lo"' in cfg.read_text()
    monkeypatch.setenv("CYCLONEDDS_URI", f"file://{cfg}")  # before any Python participant exists
    from dataclasses import dataclass
    from cyclonedds.idl import IdlStruct

    @dataclass
    class String_(IdlStruct, typename="std_msgs::msg::dds_::String_"):
        data: str

    return String_


def writer_qos(kind):
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.util import duration
    if kind == "best-effort":
        return Qos(Policy.Reliability.BestEffort, Policy.History.KeepAll, Policy.Durability.Volatile)
    return Qos(Policy.Reliability.Reliable(duration(seconds=10)), Policy.History.KeepAll, Policy.Durability.Volatile)


@pytest.mark.parametrize("rvc_qos,writer,policy,hint", [
    ("reliable", "best-effort", "RELIABILITY", "rvc requests reliable"),
    ("transient-local", "volatile", "DURABILITY", "rvc requests transient-local"),
])
def test_incompatible_publisher_is_named(rvc, string_type, rvc_qos, writer, policy, hint):
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic
    domain = 60 + os.getpid() % 8  # topic names are unique too: other tests may share the domain
    topic = f"/rvc_qos/{policy.lower()}"
    mon = subprocess.Popen([rvc, "monitor", "--spec", "{p}", "--input", f"dds:{topic}", "--qos", rvc_qos,
                            "--domain", str(domain)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lines, said = [], threading.Event()

    def read_stderr():
        for line in mon.stderr:
            lines.append(line.rstrip("\n"))
            if "incompatible" in line:
                said.set()
    reader = threading.Thread(target=read_stderr, daemon=True)
    reader.start()
    try:
        dp = DomainParticipant(domain)
        w = DataWriter(dp, Topic(dp, "rt" + topic, string_type), qos=writer_qos(writer))
        # Said while the run goes on, before it ends, not only in the final report.
        assert said.wait(HANG_GUARD), lines
        assert mon.poll() is None, lines
        for i in range(5):
            w.write(string_type(data='{"p": true}'))
        time.sleep(0.5)
        for i in range(5):  # more samples, the same publisher: nothing more to say
            w.write(string_type(data='{"p": true}'))
        mon.terminate()  # SIGTERM: the run ends, with nothing received
        out = mon.stdout.read()
        mon.wait(timeout=HANG_GUARD)
        reader.join(timeout=HANG_GUARD)
    finally:
        if mon.poll() is None:
            mon.kill()
    assert mon.returncode == 6, lines
    assert out == ""
    now = [l for l in lines if l.startswith(f"rvc: dds:{topic}: a publisher's QoS is incompatible")]
    assert now == [f"rvc: dds:{topic}: a publisher's QoS is incompatible with rvc's reader: {policy} ({hint}; "
                   f"--qos {'best-effort' if policy == 'RELIABILITY' else 'volatile'} accepts a {writer} "
                   f"publisher); its messages are not received"], lines
    final = [l for l in lines if l.startswith("rvc: nothing was received")]
    assert len(final) == 1, lines
    assert final[0].endswith(f"nothing was checked; dds:{topic}: a publisher's QoS is incompatible with rvc's "
                             f"reader: {policy} ({hint}; --qos {'best-effort' if policy == 'RELIABILITY' else 'volatile'}"
                             f" accepts a {writer} publisher)"), final
