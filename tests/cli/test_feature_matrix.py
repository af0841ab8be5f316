"""Every input kind x feature combination is supported or refused at start with a reason (issue 36).

Input kinds: a JSON-lines file, stdin, a ROS 2 bag (sqlite3 and MCAP, written with rosbags) with one
topic and with two synchronized topics, `rvc monitor --input file:` with one and two inputs and
`--input bag:`. Features: bounded future (`eventually[0:1]`), `--instances-by`, `--dense`,
`--robustness`, data references (`exists`), `--explain`, `--clock off` (dense). Every subset of the
features on every input kind is one cell:

- supported (exit 0 or 1): its verdicts equal those of the same data as one JSON-lines file checked by
  `rvc check` with the same features (the two topics as `{"a": ...}` / `{"b": ...}` lines merged by
  stamp, which is what merge synchronization does: each message an event, the other's fields hold);
- or refused (exit 2) before any verdict, on stderr in user terms: a line naming one of the options
  or inputs involved, and no internal name (the end-of-stream marker atom, C++ exception text).

Any other outcome (a crash, exit 3/5/6, verdicts and then exit 2, a message leaking an internal
name) fails the cell. 
"""
from __future__ import annotations

import itertools
import json
import subprocess

import pytest

FEATURES = ["future", "instances", "dense", "robustness", "data", "explain", "clock"]
INPUTS = ["jsonl", "stdin", "db3", "mcap", "db3_sync", "mcap_sync", "monitor_file", "monitor_sync", "monitor_bag",
          "monitor_bag_sync"]
BAGS = ("db3", "mcap", "db3_sync", "mcap_sync", "monitor_bag", "monitor_bag_sync")
SYNCED = ("db3_sync", "mcap_sync", "monitor_sync", "monitor_bag_sync")
TYPE = "rvc_fm/msg/Sample"
DEFINITION = "builtin_interfaces/Time stamp\nstring id\nbool p\nfloat64 x\n"
# Two topics, /a and /b, of the same type; /b half a second after /a. (stamp, id, p, x)
ROWS = {
    "a": [(0, "k1", False, 0.0), (1, "k2", True, 3.0), (2, "k1", True, 1.0), (3, "k2", False, 2.5),
          (4, "k1", False, 0.5), (5, "k2", True, 4.0)],
    "b": [(0.5, "k1", True, 2.0), (1.5, "k1", False, 0.0), (2.5, "k2", True, 3.5), (3.5, "k2", False, 1.0)],
}
# Words a refusal may name its reason with (the options and inputs of the cell, in user terms).
WORDS = {
    "future": ["eventually", "future", "next", "always", "until"],
    "instances": ["--instances-by", "instance"],
    "dense": ["--dense", "dense"],
    "robustness": ["--robustness", "robustness"],
    "data": ["exists", "forall", "data reference"],
    "explain": ["--explain"],
    "clock": ["--clock"],
    "sync": ["several", "--topic", "synchron", "inputs", "--input"],
    "bag": ["bag", "typed", "--topic", "ros 2"],
    "stdin": ["stdin", "-"],
}
INTERNAL = ["rvc-end-of-stream", "std::", "what()", "terminate", "basic_", "Assertion", "Segmentation", "bad_alloc",
            "invalid_argument", "out_of_range", "free()", "AddressSanitizer"]


def cells():
    for kind in INPUTS:
        for n in range(len(FEATURES) + 1):
            for feats in itertools.combinations(FEATURES, n):
                if "clock" in feats and "dense" not in feats:
                    continue  # discrete time has no clock: --clock changes nothing there (docs/cli.md)
                yield kind, frozenset(feats)


def cell_id(kind, feats):
    return kind + ":" + ("+".join(f for f in FEATURES if f in feats) or "plain")


# Cells refused with a future operator whatever the input (docs/semantics.md). The two bugs this
# matrix found (bounded future on typed single-topic input, --instances-by with bounded future) are
# fixed (issue 36): no cell is expected to fail.
BLOCKED = {"data", "explain"}
KNOWN = []


def params():
    out = []
    for kind, feats in cells():
        marks = [pytest.mark.xfail(strict=True, reason=why) for pred, why in KNOWN if pred(kind, feats)][:1]
        if kind in BAGS:
            marks.append(pytest.mark.needs_rust)  # rosbags' MCAP; the sqlite3 reader is C++, but one gate
        out.append(pytest.param(kind, feats, id=cell_id(kind, feats), marks=marks))
    return out


# ---- the data, written once per module ----

@pytest.fixture(scope="module")
def data(tmp_path_factory):
    d = tmp_path_factory.mktemp("matrix")
    msg = lambda s, i, p, x: {"time": s, "stamp": {"sec": int(s), "nanosec": int(round((s % 1) * 1e9))},
                              "id": i, "p": p, "x": x}
    single = d / "a.jsonl"
    single.write_text("".join(json.dumps(msg(*r)) + "\n" for r in ROWS["a"]))
    for name in ("a", "b"):
        (d / f"in_{name}.jsonl").write_text("".join(json.dumps(msg(*r)) + "\n" for r in ROWS[name]))
    merged = sorted([(r[0], name, r) for name in ("a", "b") for r in ROWS[name]])
    (d / "merged.jsonl").write_text("".join(json.dumps({"time": s, name: msg(*r)}) + "\n" for s, name, r in merged))
    by_key = {}
    for key in sorted({r[1] for r in ROWS["a"]}):
        by_key[key] = d / f"key_{key}.jsonl"
        by_key[key].write_text("".join(json.dumps(msg(*r)) + "\n" for r in ROWS["a"] if r[1] == key))
    bags = {}
    try:
        bags = write_bags(d)
    except ImportError:
        pass
    return {"dir": d, "single": single, "merged": d / "merged.jsonl", "by_key": by_key, "bags": bags}


def write_bags(d):
    from rosbags.rosbag2 import Writer
    from rosbags.rosbag2.enums import StoragePlugin
    from rosbags.typesys import Stores, get_typestore
    from rosbags.typesys.msg import get_types_from_msg
    ts = get_typestore(Stores.ROS2_HUMBLE)
    ts.register(get_types_from_msg(DEFINITION, TYPE))
    Sample, Time = ts.types[TYPE], ts.types["builtin_interfaces/msg/Time"]
    out = {}
    for plugin, name, ext in ((StoragePlugin.SQLITE3, "db3", "db3"), (StoragePlugin.MCAP, "mcap", "mcap")):
        folder = d / f"bag_{name}"
        with Writer(folder, version=9, storage_plugin=plugin) as w:
            conns = {t: w.add_connection(f"/{t}", TYPE, typestore=ts) for t in ("a", "b")}
            for s, t, (_, i, p, x) in sorted((r[0], t, r) for t in ("a", "b") for r in ROWS[t]):
                m = Sample(stamp=Time(sec=int(s), nanosec=int(round((s % 1) * 1e9))), id=i, p=p, x=x)
                w.write(conns[t], int(round(s * 1e9)) + 10**9, ts.serialize_cdr(m, TYPE))  # log time 1 s later
        out[name] = str(next(folder.glob(f"*.{ext}")))
    return out


# ---- one cell ----

def spec_of(feats, prefix=""):
    f = lambda name: prefix + name
    body = f"{{{f('p')}}} or {{{f('x')} > 2}}"
    if "future" in feats:
        body = f"eventually[0:1] ({body})"
    if "data" in feats:
        body = f"exists[v]. ({{{f('id')}: *v}} and ({body}))"
    return f"historically ({body})" if "future" not in feats else body


def options(feats, sync=False, bag=False):
    """The cell's options (a bag's dense time is its stamp; JSON's the "time" field)."""
    args = []
    if "dense" in feats:
        args.append("--dense")
        if not bag and not sync:
            args += ["--time-field", "time"]
    if "robustness" in feats:
        args.append("--robustness")
    if "explain" in feats:
        args.append("--explain")
    if "clock" in feats:
        args += ["--clock", "off"]
    if "instances" in feats:
        args += ["--instances-by", "a.id" if sync else "id"]
    return args


def command(rvc, kind, feats, data):
    """argv and stdin of the cell, and the JSON-lines reference it must equal (None: no equivalent)."""
    sync = kind in ("db3_sync", "mcap_sync", "monitor_sync")
    bag = kind in BAGS
    spec = spec_of(feats, "a." if sync else "")
    opts = options(feats, sync, bag)
    stdin = None
    if kind == "jsonl":
        argv = [rvc, "check", str(data["single"])]
    elif kind == "stdin":
        argv, stdin = [rvc, "check", "-"], data["single"].read_text()
    elif kind in ("db3", "mcap"):
        argv = [rvc, "check", data["bags"][kind], "--topic", "/a"]
    elif kind in ("db3_sync", "mcap_sync"):
        argv = [rvc, "check", data["bags"][kind.split("_")[0]], "--topic", "a=/a", "--topic", "b=/b"]
    elif kind == "monitor_file":
        argv = [rvc, "monitor", "--input", f"file:{data['single']}"]
    elif kind == "monitor_sync":
        argv = [rvc, "monitor", "--input", f"a=file:{data['dir'] / 'in_a.jsonl'}",
                "--input", f"b=file:{data['dir'] / 'in_b.jsonl'}"]
    elif kind == "monitor_bag":
        argv = [rvc, "monitor", "--input", f"bag:{data['bags']['mcap']}", "--topic", "/a"]
    else:  # monitor_bag_sync
        argv = [rvc, "monitor", "--input", f"bag:{data['bags']['db3']}", "--topic", "a=/a", "--topic", "b=/b"]
    argv += ["--spec", spec] + opts
    ref_input = data["merged"] if sync else data["single"]
    plain = feats - {"instances"}
    if "instances" not in feats:
        refs = [([rvc, "check", str(ref_input), "--spec", spec] + options(plain), None)]
    elif sync:
        refs = None  # a merged line lacks the other input's key: no JSON-lines equivalent
    else:  # each key's messages alone, checked as a trace of their own (docs/semantics.md, instances)
        refs = [([rvc, "check", str(path), "--spec", spec] + options(plain), {"id": key})
                for key, path in data["by_key"].items()]
    return argv, stdin, refs


def run(argv, stdin=None):
    return subprocess.run(argv, input=stdin, capture_output=True, text=True, timeout=60)


def verdicts(stdout):
    out = []
    for line in stdout.splitlines():
        v = json.loads(line)
        out.append((v["property"], v["time"], v["value"], json.dumps(v.get("instance"), sort_keys=True),
                    v.get("known_at")))
    return sorted(out, key=json.dumps)


def assert_clean_refusal(proc, kind, feats, extra=()):
    err = proc.stderr
    assert proc.returncode == 2, f"exit {proc.returncode}\nstdout: {proc.stdout[:400]}\nstderr: {err[:800]}"
    assert proc.stdout.strip() == "", f"refused after verdicts:\n{proc.stdout[:400]}"
    assert err.strip(), "refused without a word"
    for word in INTERNAL:
        assert word not in err, f"internal name {word!r} in the refusal: {err}"
    words = [w for f in feats for w in WORDS[f]] + list(extra)
    if kind in SYNCED:
        words += WORDS["sync"]
    if kind in BAGS:
        words += WORDS["bag"]
    assert any(w.lower() in err.lower() for w in words), f"the refusal names none of {words}: {err}"


@pytest.mark.parametrize("kind,feats", params())
def test_cell(rvc, data, kind, feats):
    if kind in BAGS and not data["bags"]:
        pytest.skip("rosbags is not installed (scripts/install-deps.sh)")
    argv, stdin, refs = command(rvc, kind, feats, data)
    proc = run(argv, stdin)
    if proc.returncode == 2:
        assert_clean_refusal(proc, kind, feats)
        return
    assert proc.returncode in (0, 1), f"exit {proc.returncode}\n{' '.join(argv)}\nstderr: {proc.stderr[:800]}"
    for word in INTERNAL:
        assert word not in proc.stderr, proc.stderr
    got = verdicts(proc.stdout)
    assert got, "no verdicts"
    if refs is None:
        return
    want, status = [], 0
    for ref, instance in refs:
        r = run(ref)
        assert r.returncode in (0, 1), r.stderr  # the reference is a supported JSON-lines run
        status = max(status, r.returncode)
        want += [(n, t, v, json.dumps(instance, sort_keys=True), k) for n, t, v, _, k in verdicts(r.stdout)]
    want = sorted(want, key=json.dumps)
    assert got == want, f"{' '.join(argv)}\n differs from the JSON-lines run(s) {[' '.join(r) for r, _ in refs]}"
    assert proc.returncode == status


def test_monitor_type_on_a_file_input_is_refused_in_user_terms(rvc, data):
    proc = run([rvc, "monitor", "--input", f"file:{data['single']}", "--type", "std_msgs/msg/Bool", "--spec", "{data}"])
    assert_clean_refusal(proc, "monitor_file", frozenset(), extra=["--type"])


@pytest.mark.needs_rust
def test_monitor_bag_refuses_a_spec_before_announcing_the_run(rvc, data):
    """As for a file: input, a spec refused whatever the input ends `monitor --input bag:` before the
    "rvc monitor: 1 property on ..." line, so the refusal is the first thing said."""
    if not data["bags"]:
        pytest.skip("rosbags is not installed (scripts/install-deps.sh)")
    for spec in ("exists[v]. ({id: *v} and eventually[0:1]{p})", "once[0:2 {p}"):
        proc = run([rvc, "monitor", "--input", f"bag:{data['bags']['mcap']}", "--topic", "/a", "--spec", spec])
        assert_clean_refusal(proc, "monitor_bag", frozenset({"future"}), extra=["spec error"])
        assert proc.stderr.startswith("rvc: spec error"), proc.stderr
