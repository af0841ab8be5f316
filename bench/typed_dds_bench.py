#!/usr/bin/env python3
"""Typed DDS input: can `rvc monitor` keep up with what a DDS publisher sends? Side by side in one run.

  python3 bench/typed_dds_bench.py [--sizes 32,64,128,256] [--seconds 3] [--reps 2]

The publisher is ddsperf itself (`ddsperf pub size S`, as fast as it can, reliable, one sample per
write, CycloneDDS batching packets as it does), on its topic DDSPerfRDataKS of type KeyedSeq. The same
publisher feeds, in turn:
- ddsperf's own subscriber (`ddsperf sub`, takes and drops each sample): the reference rate;
- `rvc monitor --type KeyedSeq` (the type read from bench/ddsperf/ddsperf_types.idl), decoding each
  sample's fields and checking a property over them.
A reliable publisher goes no faster than its reader, so samples received in the run / seconds is the
reader's throughput. Then a loss check: `rvc replay --type KeyedSeq` sends N samples to both readers at
once, after both have matched; each must receive all N, and ddsperf's sub counts no sequence gap.

Writes bench/results/typed_dds.jsonl and the table into docs/performance.md between the typed-dds
markers. A benchmark, not a test. DDS pinned to lo (the XML of `rvc dds-config`) for every process.
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from timescales_bench import machine, write_marked  # noqa: E402

IDL = os.path.join(ROOT, "bench", "ddsperf", "ddsperf_types.idl")
SPEC = "historically({keyval == 0} && {seq >= 0})"
DOMAIN = "23"


def ddsperf_sub_total(out):
    totals = [int(m.group(1)) for m in re.finditer(r"size \d+ total (\d+) lost (\d+)", out)]
    lost = [int(m.group(2)) for m in re.finditer(r"size \d+ total (\d+) lost (\d+)", out)]
    return (totals[-1] if totals else 0), (lost[-1] if lost else 0)


class Run:
    def __init__(self, rvc, ddsperf, cfg, tmp):
        self.rvc, self.ddsperf, self.tmp = rvc, ddsperf, tmp
        self.env = dict(os.environ, CYCLONEDDS_URI=f"file://{cfg}")

    def start_ddsperf_sub(self, seconds):
        # Output to a file, not a pipe: ddsperf complains on every sample of a writer that is not a
        # ddsperf participant (rvc replay), and a full pipe would stall its reader.
        out = open(os.path.join(self.tmp, "ddsperf-sub.txt"), "w+")
        p = subprocess.Popen([self.ddsperf, "-i", DOMAIN, "-D", str(seconds + 3), "sub"], env=self.env,
                             stdout=out, stderr=subprocess.STDOUT, text=True)
        p.out = out
        return p

    @staticmethod
    def sub_output(p):
        p.wait(timeout=60)
        p.out.seek(0)
        text = p.out.read()
        p.out.close()
        return text

    def start_monitor(self):
        stats = os.path.join(self.tmp, "stats.json")
        if os.path.exists(stats):
            os.remove(stats)
        p = subprocess.Popen([self.rvc, "monitor", "--input", "dds:DDSPerfRDataKS", "--no-ros2-names", "--type",
                              "KeyedSeq", "--msg-path", IDL, "--domain", DOMAIN, "--spec", SPEC, "--idle-timeout", "4",
                              "--output", "file:/dev/null", "--stats-output", f"file:{stats}"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        p.stats = stats
        # subscribed once it says what it monitors
        line = p.stderr.readline()
        assert "rvc monitor:" in line, line
        return p

    def publish(self, size, seconds):
        time.sleep(0.5)  # discovery
        subprocess.run([self.ddsperf, "-i", DOMAIN, "-D", str(seconds), "pub", "size", str(size)], env=self.env,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True, timeout=seconds + 30)

    def monitor_result(self, p):
        _, err = p.communicate(timeout=60)
        with open(p.stats) as f:
            s = json.loads(f.read().splitlines()[-1])
        assert s["rejected"] == 0 and s["violations"] == 0, (s, err)
        return s["received"]

    def ddsperf_rate(self, size, seconds):
        sub = self.start_ddsperf_sub(seconds)
        self.publish(size, seconds)
        total, lost = ddsperf_sub_total(self.sub_output(sub))
        return total / seconds, lost

    def rvc_rate(self, size, seconds):
        mon = self.start_monitor()
        self.publish(size, seconds)
        return self.monitor_result(mon) / seconds

    def loss_check(self, size, count):
        """ddsperf starts writing before it has matched its readers, so the first samples reach a reader
        or not by a race. For the loss check the publisher is `rvc replay --type KeyedSeq
        --wait-subscribers 2`, which writes nothing before both readers have matched: then each reader
        must receive every sample, and ddsperf's sub checks the sequence numbers."""
        trace = os.path.join(self.tmp, "keyed.jsonl")
        baggage = json.dumps(list(range(size - 12)))
        with open(trace, "w") as f:
            for k in range(count):
                f.write('{"seq":%d,"keyval":0,"baggage":%s}\n' % (k, baggage))
        sub = self.start_ddsperf_sub(30)
        mon = self.start_monitor()
        rep = subprocess.run([self.rvc, "replay", trace, "--to", "dds:DDSPerfRDataKS", "--no-ros2-names", "--type",
                        "KeyedSeq", "--msg-path", IDL, "--domain", DOMAIN, "--rate", "max", "--dds-write-batch",
                        "--wait-subscribers", "2", "--no-progress"], timeout=120,
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if rep.returncode != 0:
            sys.exit(f"rvc replay failed ({rep.returncode}): {rep.stderr}")
        got = self.monitor_result(mon)
        time.sleep(1.5)  # ddsperf prints its counts once a second
        sub.terminate()
        total, lost = ddsperf_sub_total(self.sub_output(sub))
        return total, lost, got


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rvc", default=os.path.join(ROOT, "build", "release", "rvc"))
    ap.add_argument("--sizes", default="32,64,128,256")
    ap.add_argument("--seconds", type=int, default=3)
    ap.add_argument("--reps", type=int, default=2)
    ap.add_argument("--loss-count", type=int, default=200000, help="samples of the loss check")
    ap.add_argument("--no-docs", action="store_true", help="do not update docs/performance.md")
    args = ap.parse_args()
    ddsperf = shutil.which("ddsperf")
    if not ddsperf:
        sys.exit("ddsperf missing (Debian cyclonedds-tools)")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        cfg = os.path.join(tmp, "lo.xml")
        subprocess.run([args.rvc, "dds-config", "-o", cfg], check=True)
        run = Run(args.rvc, ddsperf, cfg, tmp)
        for size in [int(s) for s in args.sizes.split(",")]:
            ref, mine, ddsperf_lost = [], [], 0
            for rep in range(args.reps):  # alternate, so drift on the machine hits both alike
                r, lost = run.ddsperf_rate(size, args.seconds)
                ref.append(r)
                ddsperf_lost += lost
                mine.append(run.rvc_rate(size, args.seconds))
                print(f"size {size} B rep {rep + 1}: ddsperf sub {r / 1e3:.0f} kS/s, rvc monitor "
                      f"{mine[-1] / 1e3:.0f} kS/s", flush=True)
            total, lost, got = run.loss_check(size, args.loss_count)
            print(f"size {size} B loss check, {args.loss_count} samples: ddsperf sub {total} (lost {lost}), "
                  f"rvc monitor {got}", flush=True)
            ref_best, mine_best = max(ref), max(mine)
            rows.append({"size": size, "ddsperf_sub_per_s": ref_best, "rvc_monitor_per_s": mine_best,
                         "ratio": mine_best / ref_best, "both_ddsperf": total, "both_rvc": got,
                         "lost": lost + (args.loss_count - total) + (args.loss_count - got), "sent": args.loss_count, "seconds": args.seconds, "reps": args.reps})
    os.makedirs(os.path.join(ROOT, "bench", "results"), exist_ok=True)
    with open(os.path.join(ROOT, "bench", "results", "typed_dds.jsonl"), "w") as f:
        for r in rows:
            f.write(json.dumps(r) + "\n")
    md = render(rows, args)
    print(md)
    if not args.no_docs:
        write_marked(os.path.join(ROOT, "docs", "performance.md"), "typed-dds", md)


def render(rows, args):
    out = [f"Machine: {machine()}. Publisher: `ddsperf pub size S` for {args.seconds} s, best of {args.reps} "
           "alternating runs per reader; samples/s = samples the reader received / seconds.", "",
           "| sample size | ddsperf sub (kS/s) | rvc monitor --type (kS/s) | rvc / ddsperf | loss check: sent / ddsperf "
           "sub / rvc monitor received | lost |", "|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        out.append(f"| {r['size']} B | {r['ddsperf_sub_per_s'] / 1e3:.0f} | {r['rvc_monitor_per_s'] / 1e3:.0f} | "
                   f"{r['ratio']:.2f} | {r['sent']} / {r['both_ddsperf']} / {r['both_rvc']} | {r['lost']} |")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    main()
