"""The "no silent loss" oracle shared by tests/cli/test_no_silent_loss.py (files, bags) and
tests/integration/participants/test_no_silent_loss_live.py (Zenoh, DDS, typed, synced): random JSON
traces with bad lines, and what rvc must count for them, worked out here in Python."""
import json


def counters(stderr):
    return json.loads([line for line in stderr.splitlines() if line.startswith('{"input"')][-1])


def assert_accounted(c, exit_code, what):
    dropped = sum(c["dropped"].values())
    assert c["received"] == c["checked"] + c["rejected"] + dropped, (what, c)
    lost = dropped if "sync" not in c or c["sync"]["policy"] == "merge" else c["dropped"].get("late", 0)
    if c["checked"] == 0:
        want = 6
    elif c["rejected"] or lost:
        want = 3
    else:
        want = 0
    assert exit_code == want, (what, exit_code, c)


BAD = ['{"x": 1', "not json", "[1, 2]", '{"x": }']


def random_lines(rng, n, t0=0.0, go_back=0.1, repeat=0.05, blank=True):
    """JSON lines with x >= 0 and a time; some bad, some without time, some going back or repeating."""
    lines, t = [], t0
    for _ in range(n):
        r = rng.random()
        if r < 0.08:
            lines.append(rng.choice(BAD))
            continue
        row = {"x": rng.randint(0, 9)}
        if rng.random() < 0.3:
            row["junk"] = {"deep": [rng.random(), "s"], "flag": rng.random() < 0.5}
        if r < 0.12:
            pass  # no time
        elif r < 0.12 + go_back:
            row["time"] = max(0.0, t - rng.choice([0.5, 1.5, 3.0]))
        elif r < 0.12 + go_back + repeat:
            row["time"] = t
        else:
            t += rng.choice([0.25, 1.0, 2.0])
            row["time"] = t
        lines.append(json.dumps(row))
    if blank and rng.random() < 0.5:
        lines.insert(rng.randrange(len(lines) + 1), "   ")  # blank: no message at all
    return lines


def as_object(line):
    try:
        v = json.loads(line)
    except ValueError:
        return None
    return v if isinstance(v, dict) else None


def oracle_single(lines, dense):
    """(received, checked, rejected) of one file read by `rvc check`."""
    received = checked = 0
    last = None
    for line in lines:
        if not line.strip():
            continue
        received += 1
        v = as_object(line)
        if v is None:
            continue
        if dense:
            t = v.get("time")
            if not isinstance(t, (int, float)) or t < 0 or (last is not None and not t > last):
                continue
            last = t
        checked += 1
    return received, checked, received - checked


def oracle_merge(files):
    """(received, checked, rejected, replaced) of files merged by stamp: a file's line is rejected
    when it is no object, has no time or goes back; of one file's messages at one stamp only the
    last is checked (the others are replaced)."""
    received = rejected = replaced = 0
    for lines in files:
        last = None
        prev_t = None
        for line in lines:
            if not line.strip():
                continue
            received += 1
            v = as_object(line)
            t = v.get("time") if v is not None else None
            if not isinstance(t, (int, float)) or t < 0 or (last is not None and t < last):
                rejected += 1
                continue
            if prev_t == t:
                replaced += 1
            prev_t = last = t
    return received, received - rejected - replaced, rejected, replaced


def rejected_without_time(lines):
    """Lines a synchronized input rejects whatever the order: no object, or no usable time."""
    n = 0
    for line in lines:
        if not line.strip():
            continue
        v = as_object(line)
        t = v.get("time") if v is not None else None
        n += not isinstance(t, (int, float)) or t < 0
    return n
