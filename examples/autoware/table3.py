#!/usr/bin/env python3
"""Table 3 of the paper redrawn: both deployments (examples/autoware/deploy.py), the nominal `drive`
scenario, at the paper's rates and at 10x and 100x them, side by side with the paper's numbers.

  python3 examples/autoware/table3.py [--scales 1,10,100] [--scenario drive]

Writes docs/autoware.md's table (between the table3 markers), docs/img/autoware-rates.png and
bench/results/autoware.jsonl. A benchmark, not a test (the container tier runs a short version).
"""
import argparse
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(ROOT, "bench"))
import deploy  # noqa: E402
from timescales_bench import write_marked  # noqa: E402


def render(results):
    out = []
    for scale in sorted({r["rate_scale"] for r in results}):
        rs = {r["setup"]: r for r in results if r["rate_scale"] == scale}
        out.append("**%gx the paper's rates**%s\n" % (scale, " (the paper's Table 3 beside it)" if scale == 1 else ""))
        head = "| topic | type | rate (Hz) |" + (" paper setup 1 | paper setup 2 |" if scale == 1 else "")
        head += "".join(" rvc setup %d: received/s (lost) |" % s for s in sorted(rs))
        out.append(head)
        out.append("|---|---|---:|" + ("---:|---:|" if scale == 1 else "") + "---:|" * len(rs))
        first = next(iter(rs.values()))
        for k, t in enumerate(first["topics"]):
            row = "| %s | %s | %g |" % (t["name"], t["type"].split("/")[-1], t["rate"])
            if scale == 1:
                p1, p2 = deploy.PAPER[t["name"]]
                row += " %.2f | %.2f |" % (p1, p2)
            for s in sorted(rs):
                tt = rs[s]["topics"][k]
                row += " %.2f (%d) |" % (tt["rate_received"], tt["sent"] - tt["received"] + tt["late"])
            out.append(row)
        out.append("")
        out.append("| | " + " | ".join("setup %d" % s for s in sorted(rs)) + " |")
        out.append("|---|" + "---:|" * len(rs))
        out.append("| messages sent / received / lost | " + " | ".join(
            "%d / %d / %d" % (rs[s]["sent"], rs[s]["received"], rs[s]["lost"]) for s in sorted(rs)) + " |")
        out.append("| synchronized sets (merge) per s | " + " | ".join("%.1f" % rs[s]["sets_per_s"] for s in sorted(rs)) + " |")
        out.append("| final verdicts equal expected.yaml | " + " | ".join(
            "yes" if rs[s]["verdicts_ok"] else "**no**" for s in sorted(rs)) + " |")
        services = sorted({svc for s in rs for svc in rs[s]["resources"]})
        for svc in services:
            cells = []
            for s in sorted(rs):
                r = rs[s]["resources"].get(svc)
                cells.append("%.1f %% / %.1f MB" % (r["cpu_mean_pct"], r["rss_max_mb"]) if r else "-")
            out.append("| %s: CPU mean / RSS max | %s |" % (svc, " | ".join(cells)))
        out.append("")
    return "\n".join(out)


def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ones = {r["setup"]: r for r in results if r["rate_scale"] == 1}
    if not ones:
        return
    names = [t["name"] for t in next(iter(ones.values()))["topics"]]
    x = range(len(names))
    w = 0.2
    fig, ax = plt.subplots(figsize=(9, 4))
    series = [("paper setup 1", [deploy.PAPER[n][0] for n in names]), ("paper setup 2", [deploy.PAPER[n][1] for n in names])]
    for s in sorted(ones):
        series.append(("rvc setup %d" % s, [t["rate_received"] for t in ones[s]["topics"]]))
    for i, (label, vals) in enumerate(series):
        ax.bar([v + (i - 1.5) * w for v in x], vals, w, label=label)
    ax.set_xticks(list(x))
    ax.set_xticklabels(names)
    ax.set_ylabel("messages/s received at the monitor")
    ax.set_title("Table 3: rate received per topic (nominal rates 25/10/5 Hz)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scales", default="1,10,100")
    ap.add_argument("--scenario", default="drive")
    ap.add_argument("--image", default=os.environ.get("RVC_IMAGE", "rvc:latest"))
    args = ap.parse_args()
    results = []
    for scale in [float(s) for s in args.scales.split(",")]:
        for setup in (1, 2):
            print("setup %d at %gx ..." % (setup, scale), flush=True)
            res = deploy.Deployment(setup, args.scenario, rate_scale=scale, image=args.image).run()
            print("  sent %d received %d lost %d verdicts %s" % (res["sent"], res["received"], res["lost"],
                                                                  "ok" if res["verdicts_ok"] else "DIFFER"), flush=True)
            results.append(res)
    os.makedirs(os.path.join(ROOT, "bench", "results"), exist_ok=True)
    with open(os.path.join(ROOT, "bench", "results", "autoware.jsonl"), "w") as f:
        for r in results:
            f.write(json.dumps({k: v for k, v in r.items() if k != "monitor_log"}) + "\n")
    md = render(results)
    print(md)
    plot(results, os.path.join(ROOT, "docs", "img", "autoware-rates.png"))
    write_marked(os.path.join(ROOT, "docs", "autoware.md"), "table3", md)


if __name__ == "__main__":
    main()
