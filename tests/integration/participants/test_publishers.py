"""Loss accounting per publisher: two `rvc replay` on one topic into one
`rvc monitor` are not each other's duplicates, and a replay run again against
a running monitor is a publisher restart, not lost or duplicated messages.
Over DDS (publication handles) and Zenoh (rvc's publisher id attachment)."""
import json
import os
import signal
import subprocess
import time
import uuid

import pytest

from conftest import transports_built

_domain = [180 + (os.getpid() % 15) * 3]


def net(rvc, transport):
    if transport not in transports_built(rvc):
        pytest.fail(f"this rvc was built without the {transport} transport")
    if transport == "dds":
        _domain[0] += 1
        return "dds:/rvc_test/pubs", ["--domain", str(_domain[0] % 230)]
    return f"zenoh:rvc_test/pubs/{uuid.uuid4().hex[:8]}", []  # default discovery on lo


def final_stats(stderr):
    return json.loads([l for l in stderr.splitlines() if l.startswith("{")][-1])


def write_trace(tmp_path, name, n):
    p = tmp_path / name
    p.write_text('{"p":true}\n' * n)
    return str(p)


@pytest.mark.parametrize("transport", ["dds", "zenoh"])
def test_two_publishers_on_one_topic(rvc, tmp_path, transport):
    topic, flags = net(rvc, transport)
    # --publishers 2: the second replay may be discovered only after the first
    # has ended (seen in CI under ASan); without it the run ends at the first marker.
    mon = subprocess.Popen([rvc, "monitor", "--spec", "{p}", "--input", topic, "--exit-on-eos", "--publishers", "2",
                            "--idle-timeout", "60", "--output", f"file:{tmp_path / 'v'}", *flags], stderr=subprocess.PIPE, text=True)
    reps = [subprocess.Popen([rvc, "replay", write_trace(tmp_path, f"t{i}.jsonl", 300 + i), "--to", topic,
                              "--rate", "3000", "--wait-timeout", "20", *flags],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for i in range(2)]
    for r in reps:
        _, err = r.communicate(timeout=60)
        assert r.returncode == 0, err
    _, err = mon.communicate(timeout=60)
    s = final_stats(err)
    # Ends only after both end-of-stream markers: every message checked.
    assert (s["received"], s["checked"], s["gaps"], s["duplicates"]) == (601, 601, 0, 0), err
    assert (s["publishers"], s["publisher_restarts"], s["eos"]) == (2, 0, True), err
    assert mon.returncode == 0, err


@pytest.mark.parametrize("transport", ["dds", "zenoh"])
def test_publisher_run_again_is_a_restart(rvc, tmp_path, transport):
    topic, flags = net(rvc, transport)
    mon = subprocess.Popen([rvc, "monitor", "--spec", "{p}", "--input", topic, "--output",
                            f"file:{tmp_path / 'v'}", *flags], stderr=subprocess.PIPE, text=True)
    trace = write_trace(tmp_path, "t.jsonl", 50)
    for _ in range(2):
        r = subprocess.run([rvc, "replay", trace, "--to", topic, "--wait-timeout", "20", *flags],
                           capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, r.stderr
    time.sleep(1)
    mon.send_signal(signal.SIGTERM)
    _, err = mon.communicate(timeout=30)
    s = final_stats(err)
    assert (s["received"], s["gaps"], s["duplicates"], s["publisher_restarts"]) == (100, 0, 0, 1), err
    assert mon.returncode == 0, err  # not 4 (lost): the restart is reported, nothing was lost


def test_publishers_flag_waits_for_the_others(rvc, tmp_path):
    """One publisher ended, two expected: the run is not over at its marker;
    the idle timeout then ends it as incomplete (exit 6), every message checked."""
    topic, flags = net(rvc, "dds")
    mon = subprocess.Popen([rvc, "monitor", "--spec", "{p}", "--input", topic, "--exit-on-eos", "--publishers", "2",
                            "--idle-timeout", "3", "--output", f"file:{tmp_path / 'v'}", *flags],
                           stderr=subprocess.PIPE, text=True)
    r = subprocess.run([rvc, "replay", write_trace(tmp_path, "t.jsonl", 40), "--to", topic, "--wait-timeout", "20",
                        *flags], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    _, err = mon.communicate(timeout=60)
    s = final_stats(err)
    assert (s["received"], s["checked"], s["publishers"]) == (40, 40, 1), err
    assert "before the publisher's end-of-stream marker" in err
    assert mon.returncode == 6, err
