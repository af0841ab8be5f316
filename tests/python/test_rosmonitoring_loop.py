"""The loop of ROSMonitoring's TL oracle, run against Reelay's package and rvc's: the monitor on
the ROS side sends each observed message as one JSON text; the oracle parses it, abstracts it
into the propositions the property reads, calls monitor.update() with them, and answers a JSON
text carrying the verdict ("true"/"false"; with condensed output an empty {} means the verdict
did not change, so the oracle repeats the last one). Both packages must give the same answers,
message for message, for discrete and dense properties."""
import json
import random

import pytest

reelay = pytest.importorskip("reelay")
import rvc  # noqa: E402

# A property file as the oracle loads it: the Rye pattern and the predicates over a message.
PROPERTIES = {
    "discrete": ("historically(({cmd_stop}) -> (once[0:3]({stopped})))", {
        "cmd_stop": lambda m: m.get("topic") == "/cmd" and m["data"] == "stop",
        "stopped": lambda m: m.get("topic") == "/odom" and abs(m["data"]) < 0.05,
    }),
    "dense": ("historically(({battery_low}) -> (once[0:2.5]({docking})))", {
        "battery_low": lambda m: m.get("topic") == "/battery" and m["data"] < 0.2,
        "docking": lambda m: m.get("topic") == "/mode" and m["data"] == "dock",
    }),
}


def abstract_message(message, predicates, dense):
    out = {name: bool(test(message)) for name, test in predicates.items()}
    if dense:
        out["time"] = message["time"]
    return out


def oracle(package, kind, events_json):
    pattern, predicates = PROPERTIES[kind]
    dense = kind == "dense"
    monitor = (package.dense_timed_monitor(pattern=pattern) if dense
               else package.discrete_timed_monitor(pattern=pattern))
    last, replies = "unknown", []
    for text in events_json:
        message = json.loads(text)
        result = monitor.update(abstract_message(message, predicates, dense))
        changes = result if dense else ([result] if result else [])
        if changes:
            last = "true" if changes[-1]["value"] else "false"
        replies.append(json.dumps({"time": message["time"], "topic": message["topic"], "verdict": last}))
    return replies


def events(rng, kind, n=300):
    """A robot's messages, one JSON text per message, as the ROS-side monitor sends them."""
    out, t = [], 0.0
    for _ in range(n):
        t += rng.choice([0.25, 0.5, 0.5, 1.0])
        if kind == "discrete":
            topic = rng.choice(["/cmd", "/odom", "/odom"])
            data = rng.choice(["go", "stop"]) if topic == "/cmd" else rng.choice([0.0, 0.01, 0.4, 1.2])
        else:
            topic = rng.choice(["/battery", "/mode"])
            data = rng.choice([0.1, 0.5, 0.9]) if topic == "/battery" else rng.choice(["dock", "explore"])
        out.append(json.dumps({"time": t, "topic": topic, "data": data}))
    return out


@pytest.mark.parametrize("kind", ["discrete", "dense"])
@pytest.mark.parametrize("seed", range(5))
def test_oracle_answers_as_with_reelay(kind, seed):
    trace = events(random.Random(seed), kind)
    ours, theirs = oracle(rvc, kind, trace), oracle(reelay, kind, trace)
    assert ours == theirs
    assert {json.loads(r)["verdict"] for r in ours} == {"true", "false"}  # the traces do violate
