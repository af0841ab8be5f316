"""ROS 2 services: the types of a .srv (pkg/srv/Name_Request, _Response, _Event) and service
introspection events, read from ROS 2's own test bag (tests/data/ros2-bags/services_mcap, recorded by
rosbag2: its schema for /test_service1/_service_event is the .srv text), checked against rosbags'
CDR reader (the types registered from the same .srv text and rosidl's event layout); and `rvc calls`,
which pairs the events into calls, against hand-computed traces and the bag's own stamps.
"""
import json
import os
import pathlib
import subprocess

import pytest

rosbags_typesys = pytest.importorskip("rosbags.typesys")
mcap_reader = pytest.importorskip("mcap.reader")
Stores, get_typestore, get_types_from_msg = (rosbags_typesys.Stores, rosbags_typesys.get_typestore,
                                              rosbags_typesys.get_types_from_msg)

BAGS = pathlib.Path(__file__).resolve().parent.parent / "data" / "ros2-bags"
SERVICE_BAG = BAGS / "services_mcap" / "bag_with_topics_and_service_events.mcap"
EVENT = "test_msgs/srv/BasicTypes_Event"


def run(args, stdin=None, check=None):
    r = subprocess.run(args, input=stdin, capture_output=True, text=True, timeout=120)
    if check is not None:
        assert r.returncode == check, r.stderr
    return r


def bag_events():
    """(topic, schema text, raw CDR) of every service event of the bag, in the bag's order."""
    out = []
    with open(SERVICE_BAG, "rb") as f:
        for schema, channel, message in mcap_reader.make_reader(f).iter_messages():
            if channel.topic.endswith("/_service_event"):
                assert schema.name == EVENT and schema.encoding == "ros2msg"
                out.append((channel.topic, schema.data.decode(), bytes(message.data)))
    return out


def rosbags_store(srv_text):
    """rosbags' Jazzy store with the service's types, under msg names (rosbags renames pkg/srv/X types; the
    wire format does not depend on the name). The event's fields are rosidl's: info, request[<=1],
    response[<=1]."""
    ts = get_typestore(Stores.ROS2_JAZZY)
    request, response = srv_text.split("\n---\n")
    ts.register(get_types_from_msg(request, "test_msgs/msg/BasicTypes_Request"))
    ts.register(get_types_from_msg(response, "test_msgs/msg/BasicTypes_Response"))
    ts.register(get_types_from_msg("service_msgs/msg/ServiceEventInfo info\n"
                                   "test_msgs/msg/BasicTypes_Request[<=1] request\n"
                                   "test_msgs/msg/BasicTypes_Response[<=1] response\n", "test_msgs/msg/BasicTypes_Event"))
    return ts


def plain(value):
    """A rosbags value as the JSON rvc prints."""
    if hasattr(value, "__dataclass_fields__"):
        return {k: plain(getattr(value, k)) for k in value.__dataclass_fields__
                if not k.isupper() and k != "__msgtype__"}
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, list):
        return [plain(v) for v in value]
    return value


@pytest.mark.needs_rust
def test_the_bags_service_events_decode_as_rosbags_reads_them(rvc, tmp_path):
    events = bag_events()
    assert len(events) == 8
    srv_text = events[0][1]
    ts = rosbags_store(srv_text)
    expected = [plain(ts.deserialize_cdr(raw, "test_msgs/msg/BasicTypes_Event")) for _, _, raw in events]
    # the .srv, where --msg-path finds a service: DIR/test_msgs/srv/BasicTypes.srv
    (tmp_path / "test_msgs" / "srv").mkdir(parents=True)
    (tmp_path / "test_msgs" / "srv" / "BasicTypes.srv").write_text(srv_text)
    out = run([rvc, "msg", "decode", "--type", EVENT, "--msg-path", str(tmp_path)],
              stdin="".join(raw.hex() + "\n" for _, _, raw in events), check=0).stdout
    got = [json.loads(line) for line in out.splitlines()]
    assert got == expected
    assert [g["info"]["event_type"] for g in got] == [0, 3] * 4  # REQUEST_SENT, RESPONSE_RECEIVED
    # the DDS type name form and the encoder: the same bytes back
    again = run([rvc, "msg", "encode", "--type", "test_msgs::srv::dds_::BasicTypes_Event_", "--msg-path", str(tmp_path)],
                stdin=out, check=0).stdout.split()
    assert [bytes.fromhex(h) for h in again] == [raw for _, _, raw in events]
    # Request and Response alone
    req = ts.serialize_cdr(ts.deserialize_cdr(events[0][2], "test_msgs/msg/BasicTypes_Event").request[0],
                           "test_msgs/msg/BasicTypes_Request")
    r = run([rvc, "msg", "decode", "--type", "test_msgs/srv/BasicTypes_Request", "--msg-path", str(tmp_path)],
            stdin=bytes(req).hex() + "\n", check=0)
    assert json.loads(r.stdout) == expected[0]["request"][0]


@pytest.mark.needs_rust
def test_rvc_check_reads_a_service_event_topic_of_a_bag(rvc):
    # the command of issue 28, which failed with "not a message type name: 'test_msgs/srv/BasicTypes_Event'"
    events = bag_events()
    ts = rosbags_store(events[0][1])
    service1 = [ts.deserialize_cdr(raw, "test_msgs/msg/BasicTypes_Event") for topic, _, raw in events
                if topic == "/test_service1/_service_event"]
    r = run([rvc, "check", str(SERVICE_BAG), "--topic", "/test_service1/_service_event", "--all",
             "--spec", "{info.event_type == RESPONSE_RECEIVED}"])
    assert r.returncode in (0, 1), r.stderr
    verdicts = [json.loads(l)["value"] for l in r.stdout.splitlines()]
    assert verdicts == [e.info.event_type == 3 for e in service1]
    r = run([rvc, "check", str(SERVICE_BAG), "--topic", "/test_service1/_service_event",
             "--spec", "historically({info.sequence_number >= 1} and {info.client_gid[15] == 3})"])
    assert r.returncode == 0, r.stderr
    # dense time: each event at its info.stamp
    r = run([rvc, "check", str(SERVICE_BAG), "--topic", "/test_service1/_service_event", "--dense", "--all",
             "--spec", "{info.event_type == REQUEST_SENT}"], check=1)
    verdicts = [json.loads(l) for l in r.stdout.splitlines()]
    stamps = [e.info.stamp.sec + e.info.stamp.nanosec / 1e9 for e in service1]
    for e, stamp in zip(service1, stamps):
        at = [v for v in verdicts if abs(v["time"] - stamp) < 1e-6]
        assert at and at[0]["value"] == (e.info.event_type == 0), (stamp, verdicts)
    r = run([rvc, "check", str(SERVICE_BAG), "--topic", "/test_service1/_service_event",
             "--spec", "{request[0].nope == 1}"])
    assert r.returncode == 2 and "nope" in r.stderr


def event_line(kind, ms, client, seq, request=None, response=None):
    gid = [client] + [0] * 15
    return json.dumps({"info": {"event_type": kind, "stamp": {"sec": ms // 1000, "nanosec": (ms % 1000) * 10**6},
                                "client_gid": gid, "sequence_number": seq},
                       "request": [request] if request else [], "response": [response] if response else []})


def test_calls_pair_requests_and_responses_into_verdicts(rvc):
    # Hand-computed: timeout 0.5 s; property: every call answered within 100 ms with success.
    lines = [
        event_line(0, 1000, 1, 1, {"data": True}),
        event_line(0, 1010, 2, 1, {"data": False}),           # another client, the same sequence number
        event_line(3, 1040, 2, 1, None, {"success": True, "message": ""}),   # answered in 30 ms, before client 1
        event_line(3, 1080, 1, 1, None, {"success": True, "message": ""}),   # 80 ms
        event_line(0, 2000, 1, 2, {"data": True}),
        event_line(3, 2300, 1, 2, None, {"success": True, "message": ""}),   # late: 300 ms
        event_line(0, 3000, 1, 3, {"data": True}),
        event_line(3, 3050, 1, 3, None, {"success": False, "message": "no"}),  # in time, failed
        event_line(0, 4000, 1, 4, {"data": True}),            # never answered
        event_line(0, 5000, 1, 5, {"data": True}),
        event_line(3, 5020, 1, 5, None, {"success": True, "message": ""}),
    ]
    r = run([rvc, "calls", "--service-timeout", "0.5"], stdin="\n".join(lines) + "\n", check=0)
    calls = [json.loads(l) for l in r.stdout.splitlines()]
    assert [(c["request_time"], c["answered"], round(c["latency"], 9)) for c in calls] == [
        (1.0, True, 0.08), (1.01, True, 0.03), (2.0, True, 0.3), (3.0, True, 0.05), (4.0, False, 0.5),
        (5.0, True, 0.02)]
    assert calls[0]["request"] == {"data": True} and calls[1]["request"] == {"data": False}
    assert "6 calls (5 answered, 1 unanswered after 0.5s)" in r.stderr, r.stderr
    spec = "{answered} and {latency <= 0.1} and {response.success}"
    chk = run([rvc, "check", "--all", "--spec", spec, "-"], stdin=r.stdout)
    verdicts = [json.loads(l)["value"] for l in chk.stdout.splitlines()]
    # call 5 (unanswered) keeps call 4's response.success (a missing field keeps its value), but answered is false
    assert verdicts == [True, True, False, False, False, True], chk.stdout
    assert chk.returncode == 1


def test_calls_refuse_lines_that_are_no_event(rvc):
    r = run([rvc, "calls"], stdin='{"data": 1}\n')
    assert r.returncode == 3
    assert "line 1: no field 'info'" in r.stderr and "no call was made" in r.stderr


@pytest.mark.needs_rust
def test_calls_of_the_bag_have_the_latencies_of_its_stamps(rvc, tmp_path):
    events = bag_events()
    srv_text = events[0][1]
    (tmp_path / "test_msgs" / "srv").mkdir(parents=True)
    (tmp_path / "test_msgs" / "srv" / "BasicTypes.srv").write_text(srv_text)
    ts = rosbags_store(srv_text)
    for topic in ("/test_service1/_service_event", "/test_service2/_service_event"):
        raws = [raw for t, _, raw in events if t == topic]
        decoded = run([rvc, "msg", "decode", "--type", EVENT, "--msg-path", str(tmp_path)],
                      stdin="".join(r.hex() + "\n" for r in raws), check=0).stdout
        calls = [json.loads(l) for l in run([rvc, "calls"], stdin=decoded, check=0).stdout.splitlines()]
        ev = [ts.deserialize_cdr(r, "test_msgs/msg/BasicTypes_Event") for r in raws]
        ns = lambda e: e.info.stamp.sec * 10**9 + e.info.stamp.nanosec  # noqa: E731
        want = [(ns(q) / 1e9, (ns(a) - ns(q)) / 1e9) for q, a in zip(ev[0::2], ev[1::2])]
        assert [(c["request_time"], c["latency"]) for c in calls] == want
        assert all(c["answered"] for c in calls)


def reference_calls(events, timeout_ns):
    """The pairing as docs/services.md states it, written again here: (request ns, answered, latency ns)
    of each call in the order rvc writes them. events: (kind, stamp ns, client, seq) in input order."""
    now = None
    calls, open_, made = [], {}, set()   # calls: [req_ns, arrival, answered, resp_ns, decided]

    def decide():
        for c in calls:
            if not c[4] and c[0] + timeout_ns <= now:
                c[4] = True
    for i, (kind, ns, client, seq) in enumerate(events):
        now = ns if now is None else max(now, ns)
        decide()
        key = (client, seq)
        if kind <= 1:
            if key in open_ or key in made:
                continue
            c = [ns, i, False, None, False]
            calls.append(c)
            open_[key] = c
        else:
            c = open_.get(key)
            if c is None or c[2] or c[4]:
                continue
            c[2], c[3], c[4] = True, ns, True
            made.add(key)
    out = []
    for c in sorted(calls, key=lambda c: (c[0], c[1])):
        if not c[4]:
            break  # undecided at the end: this and every later call stay pending
        out.append((c[0], c[2], c[3] - c[0] if c[2] else timeout_ns))
    return out


def test_calls_agree_with_the_stated_rule_on_random_traces(rvc):
    import random
    rng = random.Random(28)
    timeout_ns = 200_000_000
    for trial in range(40):
        events, seqs = [], {1: 0, 2: 0}
        t = 1_700_000_000 * 10**9
        for _ in range(rng.randint(1, 12)):
            t += rng.randint(0, 150_000_000)
            client = rng.choice([1, 2])
            seqs[client] += 1
            seq = seqs[client]
            events.append((0, t, client, seq))
            if rng.random() < 0.3:
                events.append((1, t + rng.randint(0, 5_000_000), client, seq))  # the server's side too
            if rng.random() < 0.8:
                answer = t + rng.randint(0, 300_000_000)  # some after the 200 ms deadline
                events.append((3, answer, client, seq))
                if rng.random() < 0.3:
                    events.append((2, answer - rng.randint(0, 1_000_000), client, seq))
        events.sort(key=lambda e: e[1] + rng.randint(-20_000_000, 20_000_000))  # recorded a little out of order
        lines = [event_line(k, 0, c, s) for k, _, c, s in events]
        lines = [json.loads(line) for line in lines]
        for line, (_, ns, _, _) in zip(lines, events):
            line["info"]["stamp"] = {"sec": ns // 10**9, "nanosec": ns % 10**9}
        r = run([rvc, "calls", "--service-timeout", "0.2"], stdin="".join(json.dumps(l) + "\n" for l in lines))
        got = [json.loads(l) for l in r.stdout.splitlines()]
        want = reference_calls(events, timeout_ns)
        # request_time is seconds as a double: exact to ~0.2 us at today's epoch; latency is exact
        assert len(got) == len(want), (trial, events, got)
        for g, (q, a, lat) in zip(got, want):
            assert abs(g["request_time"] * 1e9 - q) < 1000 and g["answered"] == a, (trial, events, g)
            assert round(g["latency"] * 1e9) == lat, (trial, events, g)
        times = [g["time"] for g in got]
        assert all(b > a for a, b in zip(times, times[1:])) and all(g["time"] >= g["request_time"] for g in got)


def hand_trace_with_extras():
    """The trace of test_calls_pair_requests_and_responses_into_verdicts plus one event of each kind that
    makes no call: the server's duplicate response, a response to no request, a line that is no event,
    and a last request still within its timeout when the input ends."""
    ok = {"success": True, "message": ""}
    return [
        event_line(0, 1000, 1, 1, {"data": True}),
        event_line(0, 1010, 2, 1, {"data": False}),
        event_line(3, 1040, 2, 1, None, ok),
        event_line(3, 1080, 1, 1, None, ok),
        event_line(2, 1079, 1, 1, None, ok),                  # duplicate: the server's side of call (1, 1)
        event_line(3, 1500, 7, 9, None, ok),                  # orphan: no request seen
        '{"data": 1}',                                        # rejected: no service event
        event_line(0, 2000, 1, 2, {"data": True}),
        event_line(3, 2300, 1, 2, None, ok),
        event_line(0, 3000, 1, 3, {"data": True}),
        event_line(3, 3050, 1, 3, None, {"success": False, "message": "no"}),
        event_line(0, 4000, 1, 4, {"data": True}),            # never answered
        event_line(0, 5000, 1, 5, {"data": True}),
        event_line(3, 5020, 1, 5, None, ok),
        event_line(0, 5100, 1, 6, {"data": True}),            # pending: the input ends within its timeout
    ]


def test_monitor_calls_agrees_with_the_calls_pipe_and_counts_every_event(rvc, tmp_path):
    trace = tmp_path / "events.jsonl"
    trace.write_text("\n".join(hand_trace_with_extras()) + "\n")
    spec = "{answered} and {latency <= 0.1} and {response.success}"
    piped = run([rvc, "calls", "--service-timeout", "0.5", str(trace)])
    want = run([rvc, "check", "--all", "--spec", spec, "-"], stdin=piped.stdout)
    r = run([rvc, "monitor", "--input", f"file:{trace}", "--calls", "--service-timeout", "0.5", "--all",
             "--spec", spec])
    got = [json.loads(l)["value"] for l in r.stdout.splitlines()]
    assert got == [json.loads(l)["value"] for l in want.stdout.splitlines()]
    assert got == [True, True, False, False, False, True]  # hand-computed, as the pipe test's
    # violated (1) wins over the rejected line (3), as in the pipe's check
    assert r.returncode == 1 == want.returncode, r.stderr
    counters = json.loads([l for l in r.stderr.splitlines() if l.startswith("{")][-1])
    # 15 events = 11 paired into 6 calls (5 answered: 2 events each, 1 unanswered) + 1 rejected
    #   + dropped: 1 duplicate, 1 orphan, 1 pending
    assert counters["received"] == 15 and counters["checked"] == 6 and counters["rejected"] == 1
    assert counters["dropped"] == {"duplicate": 1, "orphan": 1, "pending": 1}
    assert counters["calls"] == {"events": 15, "paired": 11, "calls": 6, "answered": 5, "unanswered": 1,
                                 "pending_calls": 1}
    assert "line 7" not in r.stderr and "service event 7: no field 'info'" in r.stderr


def test_monitor_calls_settles_a_late_request_by_a_later_events_stamp(rvc, tmp_path):
    # Hand-computed, timeout 0.2 s: call 1 unanswered (its deadline 1.2 passes at the 2.0 event), call 2 answered.
    trace = tmp_path / "events.jsonl"
    trace.write_text("\n".join([event_line(0, 1000, 1, 1, {"data": True}), event_line(0, 2000, 1, 2, {"data": True}),
                                event_line(3, 2010, 1, 2, None, {"success": True, "message": ""})]) + "\n")
    r = run([rvc, "monitor", "--input", f"file:{trace}", "--calls", "--service-timeout", "0.2", "--all", "--dense",
             "--spec", "{answered}"], check=1)
    # dense: false at call 1 (the timeline's start: its first call); true from call 2; the file's end
    # ticks at the events' clock, 2.01 (the pipe's check ends at its last call, 2.0)
    assert [(json.loads(l)["time"], json.loads(l)["value"]) for l in r.stdout.splitlines()] == [
        (1, False), (2, True), (2.01, True)]


@pytest.mark.needs_rust
@pytest.mark.parametrize("topic", ["/test_service1/_service_event", "/test_service2/_service_event"])
@pytest.mark.parametrize("dense", [False, True])
def test_check_calls_on_the_bag_agrees_with_the_calls_pipe(rvc, tmp_path, topic, dense):
    events = bag_events()
    (tmp_path / "test_msgs" / "srv").mkdir(parents=True)
    (tmp_path / "test_msgs" / "srv" / "BasicTypes.srv").write_text(events[0][1])
    raws = [raw for t, _, raw in events if t == topic]
    decoded = run([rvc, "msg", "decode", "--type", EVENT, "--msg-path", str(tmp_path)],
                  stdin="".join(r.hex() + "\n" for r in raws), check=0).stdout
    calls = run([rvc, "calls"], stdin=decoded, check=0).stdout
    lat = sorted(json.loads(l)["latency"] for l in calls.splitlines())
    # a bound between the two latencies: one call holds, the other not
    spec = f"{{answered}} and {{latency <= {(lat[0] + lat[-1]) / 2!r}}}"
    extra = ["--dense"] if dense else []
    want = run([rvc, "check", "--all", "--spec", spec, *extra, "-"], stdin=calls)
    got = run([rvc, "check", str(SERVICE_BAG), "--topic", topic, "--calls", "--all", "--stats", "--spec", spec,
               *extra])
    # dense: the bag's clock also ticks at the recording's end (one verdict more, the last call's value held)
    assert got.stdout.startswith(want.stdout) and want.stdout.count("\n") >= 1
    extra = got.stdout[len(want.stdout):].splitlines()
    assert extra == [] if not dense else len(extra) <= 1
    assert all(json.loads(l)["value"] == json.loads(want.stdout.splitlines()[-1])["value"] for l in extra)
    assert got.returncode == want.returncode, got.stderr
    counters = json.loads([l for l in got.stderr.splitlines() if l.startswith("{")][-1])
    assert counters["received"] == len(raws) and counters["checked"] == len(calls.splitlines())
    assert counters["calls"]["paired"] + counters["rejected"] == len(raws) and counters["dropped"] == {}


def test_calls_flag_usage_errors(rvc, tmp_path):
    trace = tmp_path / "t.jsonl"
    trace.write_text(event_line(0, 1000, 1, 1) + "\n")
    r = run([rvc, "check", "--calls", "--spec", "{answered}", str(trace)], check=2)
    assert "rvc calls" in r.stderr
    r = run([rvc, "monitor", "--calls", "--input", "a=file:x", "--input", "b=file:y", "--spec", "{a.x}"], check=2)
    assert "one --input" in r.stderr


def test_a_call_never_checked_is_not_a_clean_pass(rvc, tmp_path):
    """Every call checked held, but one request's call was never decided when the input ended (its
    deadline lies past the last event) and one response answered no request seen: those events were
    not checked, so the run is exit 3 (docs/services.md), not 0. Hand-computed; timeout 10 s."""
    ok = [event_line(0, 1000, 1, 1, {"data": True}), event_line(3, 1010, 1, 1, None, {"success": True, "message": ""})]
    pending = [event_line(0, 2000, 1, 2, {"data": True})]
    orphan = [event_line(3, 3000, 2, 9, None, {"success": True, "message": ""})]
    for extra, reason in [([], None), (pending, "pending"), (orphan, "orphan")]:
        trace = tmp_path / "events.jsonl"
        trace.unlink(missing_ok=True)
        trace.write_text("\n".join(ok + extra) + "\n")
        r = run([rvc, "monitor", "--input", f"file:{trace}", "--calls", "--service-timeout", "10",
                 "--spec", "{answered}"])
        counters = json.loads([l for l in r.stderr.splitlines() if l.startswith("{")][-1])
        assert counters["checked"] == 1, r.stderr
        if reason is None:
            assert r.returncode == 0 and counters["dropped"] == {}, r.stderr
        else:
            assert r.returncode == 3 and counters["dropped"] == {reason: 1}, r.stderr


@pytest.mark.needs_rust
def test_calls_on_a_topic_that_is_no_service_event_is_refused_naming_its_type(rvc):
    """--calls on the bag's /test_topic1 (test_msgs/msg/Strings): refused at the start (exit 2), saying
    the topic's type is no service event type; before, every message was rejected (exit 6) and the
    bag's definition was blamed ("if that definition is wrong or cut short ...")."""
    for args in ([rvc, "check", str(SERVICE_BAG)], [rvc, "monitor", "--input", f"bag:{SERVICE_BAG}"]):
        r = run(args + ["--topic", "/test_topic1", "--calls", "--spec", "{answered}"], check=2)
        assert "topic /test_topic1 is test_msgs/msg/Strings, not a service event type" in r.stderr, r.stderr
        assert "definition" not in r.stderr and r.stdout == ""
    r = run([rvc, "monitor", "--input", "dds:/chatter", "--type", "std_msgs/msg/String", "--calls",
             "--spec", "{answered}"], check=2)
    assert "std_msgs/msg/String is not a service type" in r.stderr, r.stderr
