"""Service introspection events live over DDS: a cyclonedds-Python participant (pinned to loopback)
publishes std_srvs/srv/SetBool_Event samples on rt/set_bool/_service_event under the DDS type name
rosidl gives them (std_srvs::srv::dds_::SetBool_Event_); `rvc echo --type std_srvs/srv/SetBool_Event`
reads them and `rvc calls --wall` pairs them: an answered call with the latency of its stamps, and a
request never answered reported at its deadline while the topic is still open (the system clock moves
time, no further event needed)."""
import json
import os
import select
import signal
import subprocess
import time

import pytest

from conftest import transports_built
from ros_idl_types import loopback_dds, ros_idl_types
from rvc_testlib import dds_matched
from test_python_peers import HANG_GUARD, wait_for


def set_bool_event_types():
    t = ros_idl_types()
    return t.Time_, t.ServiceEventInfo_, t.SetBool_Request_, t.SetBool_Response_, t.SetBool_Event_


def write_two_calls(writer):
    """Client 1's call (its request seen on both sides, answered 40 ms later) and client 2's request,
    never answered; the events' stamps are the system clock's. Returns the first request's stamp (ns)."""
    Time_, Info_, Req_, Resp_, Event_ = set_bool_event_types()
    now_ns = time.time_ns()

    def info(kind, ns, client, seq):
        return Info_(event_type=kind, stamp=Time_(sec=ns // 10**9, nanosec=ns % 10**9),
                     client_gid=[client] + [0] * 15, sequence_number=seq)
    writer.write(Event_(info=info(0, now_ns, 1, 1), request=[Req_(data=True)], response=[]))
    writer.write(Event_(info=info(1, now_ns + 1_000_000, 1, 1), request=[Req_(data=True)], response=[]))
    writer.write(Event_(info=info(2, now_ns + 40_000_000, 1, 1), request=[],
                        response=[Resp_(success=True, message="set")]))
    writer.write(Event_(info=info(0, now_ns + 100_000_000, 2, 1), request=[Req_(data=False)], response=[]))
    return now_ns


def read_line(proc, deadline_s=HANG_GUARD):
    end = time.time() + deadline_s
    while time.time() < end:
        ready, _, _ = select.select([proc.stdout], [], [], 0.1)
        if ready:
            return proc.stdout.readline()
    raise AssertionError("no line from rvc calls")


def read_lines(proc, n, deadline_s=HANG_GUARD):
    """n lines of proc's stdout, read from its descriptor (lines that come together stay apart from
    Python's buffer, which select would not see)."""
    data, end = b"", time.time() + deadline_s
    while data.count(b"\n") < n and time.time() < end:
        ready, _, _ = select.select([proc.stdout], [], [], 0.1)
        if ready:
            chunk = os.read(proc.stdout.fileno(), 65536)
            if not chunk:
                break
            data += chunk
    assert data.count(b"\n") >= n, f"only {data!r} from rvc"
    return data.decode().splitlines()[:n]


def test_service_events_over_dds_become_calls(rvc, tmp_path, monkeypatch):
    if "dds" not in transports_built(rvc):
        pytest.skip("rvc built without DDS")
    loopback_dds(rvc, tmp_path, monkeypatch)  # before any Python participant exists
    pytest.importorskip("cyclonedds")
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration
    Event_ = set_bool_event_types()[-1]
    domain = 150 + os.getpid() % 50
    echo = subprocess.Popen([rvc, "echo", "dds:/set_bool/_service_event", "--type", "std_srvs/srv/SetBool_Event",
                             "--domain", str(domain)], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    calls = subprocess.Popen([rvc, "calls", "--service-timeout", "2", "--wall"], stdin=echo.stdout,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    echo.stdout.close()
    try:
        dp = DomainParticipant(domain)
        qos = Qos(Policy.Reliability.Reliable(duration(seconds=30)), Policy.History.KeepAll,
                  Policy.Durability.Volatile)
        writer = DataWriter(dp, Topic(dp, "rt/set_bool/_service_event", Event_), qos=qos)
        wait_for(lambda: dds_matched(writer), "rvc echo to match the service event topic")
        now_ns = write_two_calls(writer)
        first = json.loads(read_line(calls))
        assert first["answered"] is True and first["latency"] == 0.04
        assert first["request"] == {"data": True} and first["response"] == {"success": True, "message": "set"}
        # client 2's request is never answered: made by the clock, with rvc echo still running
        second = json.loads(read_line(calls))
        assert echo.poll() is None
        assert second["answered"] is False and second["latency"] == 2 and second["request"] == {"data": False}
        assert second["request_time"] == (now_ns + 100_000_000) / 1e9
        echo.send_signal(signal.SIGINT)
        out, err = calls.communicate(timeout=HANG_GUARD)
        assert out == ""
        assert calls.returncode == 0, err
        assert "4 events: 2 calls (1 answered, 1 unanswered after 2s)" in err and "1 duplicate" in err, err
        echo.wait(timeout=HANG_GUARD)
    finally:
        for p in (echo, calls):
            if p.poll() is None:
                p.kill()


def test_monitor_calls_pairs_service_events_over_dds_and_settles_unanswered_on_its_clock(rvc, tmp_path, monkeypatch):
    """`rvc monitor --calls`: the same pairing inside the monitor, one command. An answered call is
    checked as it is answered; a request never answered is checked as answered:false when the monitor's
    clock (wall: the stamps are the system clock's) passes its deadline, with no further event."""
    if "dds" not in transports_built(rvc):
        pytest.skip("rvc built without DDS")
    loopback_dds(rvc, tmp_path, monkeypatch)  # before any Python participant exists
    pytest.importorskip("cyclonedds")
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration
    Event_ = set_bool_event_types()[-1]
    domain = 100 + os.getpid() % 50
    mon = subprocess.Popen([rvc, "monitor", "--input", "dds:/set_bool/_service_event", "--type",
                            "std_srvs/srv/SetBool_Event", "--calls", "--service-timeout", "1.5", "--all",
                            "--spec", "{answered} and {latency <= 0.1}", "--domain", str(domain)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        dp = DomainParticipant(domain)
        qos = Qos(Policy.Reliability.Reliable(duration(seconds=30)), Policy.History.KeepAll,
                  Policy.Durability.Volatile)
        writer = DataWriter(dp, Topic(dp, "rt/set_bool/_service_event", Event_), qos=qos)
        wait_for(lambda: dds_matched(writer), "rvc monitor to match the service event topic")
        now_ns = write_two_calls(writer)
        first = json.loads(read_line(mon))
        assert first["value"] is True
        second = json.loads(read_line(mon))  # client 2's call, made by the monitor's clock at its deadline
        assert second["value"] is False and mon.poll() is None
        mon.send_signal(signal.SIGINT)
        out, err = mon.communicate(timeout=HANG_GUARD)
        assert mon.returncode == 1, err
        counters = json.loads([l for l in err.splitlines() if l.startswith("{")][-1])
        # 4 events = 3 paired (2 calls) + 1 duplicate (the server's REQUEST_RECEIVED)
        assert counters["received"] == 4 and counters["checked"] == 2 and counters["rejected"] == 0
        assert counters["dropped"] == {"duplicate": 1}
        assert counters["calls"]["paired"] == 3 and counters["calls"]["unanswered"] == 1
    finally:
        if mon.poll() is None:
            mon.kill()


def test_monitor_calls_reads_the_request_and_reply_topics_of_a_service(rvc, tmp_path, monkeypatch):
    """`rvc monitor --calls --type std_srvs/srv/SetBool --input dds:/set_bool`: the calls themselves, as
    rmw_cyclonedds sends them on rq/set_boolRequest and rr/set_boolReply, each sample led by the 16-byte
    request header (uint64 client guid, int64 sequence number). cyclonedds-Python writes samples of that
    layout under the services' DDS type names; rvc pairs request and reply by the header. The guids' first
    bytes are no valid bool: a reader whose descriptor lacked the header members would have CycloneDDS drop
    every request (docs/services.md)."""
    if "dds" not in transports_built(rvc):
        pytest.skip("rvc built without DDS")
    loopback_dds(rvc, tmp_path, monkeypatch)  # before any Python participant exists
    pytest.importorskip("cyclonedds")
    from dataclasses import dataclass

    from cyclonedds.domain import DomainParticipant
    from cyclonedds.idl import IdlStruct
    from cyclonedds.idl.types import int64, uint64
    from cyclonedds.pub import DataWriter
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration

    @dataclass
    class Request_(IdlStruct, typename="std_srvs::srv::dds_::SetBool_Request_"):
        client_guid: uint64
        sequence_number: int64
        data: bool

    @dataclass
    class Reply_(IdlStruct, typename="std_srvs::srv::dds_::SetBool_Response_"):
        client_guid: uint64
        sequence_number: int64
        success: bool
        message: str

    domain = 50 + os.getpid() % 50
    # Samples are stamped when rvc's engine takes them: on a loaded machine a reply may come a second or
    # more after its request, so a 1 s timeout judged an answered call unanswered; 10 s leaves room for
    # that, and the never-answered request is still reported at its deadline, within read_lines' guard.
    mon = subprocess.Popen([rvc, "monitor", "--input", "dds:/set_bool", "--type", "std_srvs/srv/SetBool", "--calls",
                            "--service-timeout", "10", "--all", "--spec", "{answered} and {response.success}",
                            "--spec", "{request.data}", "--domain", str(domain)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        dp = DomainParticipant(domain)
        qos = Qos(Policy.Reliability.Reliable(duration(seconds=30)), Policy.History.KeepAll,
                  Policy.Durability.Volatile)
        requests = DataWriter(dp, Topic(dp, "rq/set_boolRequest", Request_), qos=qos)
        replies = DataWriter(dp, Topic(dp, "rr/set_boolReply", Reply_), qos=qos)
        wait_for(lambda: dds_matched(requests) and dds_matched(replies), "rvc monitor to match rq/ and rr/")
        g1, g2 = 0x0123_4567_89AB_CD42, 0xFEDC_BA98_7654_3207  # little-endian first bytes 0x42, 0x07
        requests.write(Request_(client_guid=g1, sequence_number=1, data=True))
        requests.write(Request_(client_guid=g2, sequence_number=1, data=False))  # another client, same number
        replies.write(Reply_(client_guid=g2, sequence_number=1, success=True, message="ok"))
        replies.write(Reply_(client_guid=g1, sequence_number=1, success=True, message="ok"))
        requests.write(Request_(client_guid=g1, sequence_number=2, data=True))  # never answered
        got = [json.loads(l) for l in read_lines(mon, 6)]  # 3 calls x 2 properties; the last at its deadline
        assert mon.poll() is None
        by = {p: [v["value"] for v in got if v["property"] == p] for p in ("p1", "p2")}
        assert by == {"p1": [True, True, False], "p2": [True, False, True]}, got
        mon.send_signal(signal.SIGINT)
        out, err = mon.communicate(timeout=HANG_GUARD)
        assert mon.returncode == 1, err
        counters = json.loads([l for l in err.splitlines() if l.startswith("{")][-1])
        assert counters["received"] == 5 and counters["checked"] == 3 and counters["rejected"] == 0
        assert counters["calls"] == {"events": 5, "paired": 5, "calls": 3, "answered": 2, "unanswered": 1,
                                     "pending_calls": 0}
        assert [i["received"] for i in counters["inputs"]] == [3, 2]
    finally:
        if mon.poll() is None:
            mon.kill()
