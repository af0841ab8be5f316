"""CSV, plots and the markdown summary of a baseline run."""
import csv
import math
import os

from systems import ROW_FIELDS


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=ROW_FIELDS)
        w.writeheader()
        for r in rows:
            w.writerow(r)


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def num(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def human_size(n):
    n = int(n)
    if n >= 1 << 20 and n % (1 << 20) == 0:
        return f"{n >> 20} MiB"
    if n >= 1024 and n % 1024 == 0:
        return f"{n >> 10} KiB"
    return f"{n} B"


def human_rate(r):
    if r in ("max", "", None):
        return "max"
    r = float(r)
    return f"{r / 1000:g} kHz" if r >= 1000 else f"{r:g} Hz"


def fmt_mps(v):
    if v is None:
        return "–"
    if v >= 1e6:
        return f"{v / 1e6:.2f} M"
    if v >= 1e3:
        return f"{v / 1e3:.1f} k"
    return f"{v:.0f}"


def fmt_us(v):
    if v is None:
        return "–"
    if v >= 1000:
        return f"{v / 1000:.2f} ms"
    return f"{v:.1f} µs" if v < 100 else f"{v:.0f} µs"


def rate_key(r):
    return math.inf if r in ("max", "") else float(r)


def index(rows, kind):
    """{(setting, system, size, rate): row} for ok rows of one kind."""
    out = {}
    for r in rows:
        if r["kind"] == kind and str(r["ok"]) == "True":
            out[(r["setting"], r["system"], int(r["size"]), str(r["rate"]))] = r
    return out


# ---------------------------------------------------------------- plots

def legend(fig, axes):
    """One legend for the figure, with every line of every panel, below them."""
    seen = {}
    for row in axes:
        for ax in row:
            for h, l in zip(*ax.get_legend_handles_labels()):
                seen.setdefault(l, h)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    fig.legend(list(seen.values()), list(seen.keys()), loc="lower center", ncol=min(len(seen), 5), fontsize=8,
               frameon=False)


def md_table(w, head, rows):
    """A markdown table, first column as label, all columns right-aligned, then a blank line."""
    w("| " + " | ".join(head) + " |")
    w("|---:|" + "---:|" * (len(head) - 1))
    for cells in rows:
        w("| " + " | ".join(cells) + " |")
    w("")


def plot(rows, settings, systems, img_dir, prefix="baseline"):
    """PNG plots: throughput vs size and latency vs rate, one panel per
    network setting, one line per system. Returns the files written (none
    without matplotlib)."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return []
    os.makedirs(img_dir, exist_ok=True)
    colors = {"zenoh": "tab:blue", "dds": "tab:orange", "dds-batch": "tab:red", "dds-zenoh": "tab:purple",
              "ddsperf": "tab:green"}
    markers = {"zenoh": "o", "dds": "s", "dds-batch": "D", "dds-zenoh": "^", "ddsperf": "x"}
    files = []
    tput = index(rows, "throughput")
    lat = index(rows, "latency")
    used = [s for s in settings if any(k[0] == s.name for k in tput)]
    if used:
        fig, axes = plt.subplots(2, len(used), figsize=(5.2 * len(used), 8), squeeze=False)
        for col, st in enumerate(used):
            for sys in systems:
                pts = sorted((k[2], v) for k, v in tput.items() if k[0] == st.name and k[1] == sys.name)
                if not pts:
                    continue
                xs = [p[0] for p in pts]
                for rowi, field in enumerate(("msgs_per_s", "mbps")):
                    axes[rowi][col].plot(xs, [num(p[1][field]) for p in pts], marker=markers.get(sys.name, "."),
                                         color=colors.get(sys.name), label=sys.label)
            for rowi, ylabel in enumerate(("messages / s", "Mbit / s (payload)")):
                ax = axes[rowi][col]
                ax.set_xscale("log", base=4)
                ax.set_yscale("log")
                ax.grid(True, which="both", alpha=0.3)
                ax.set_xlabel("payload size (bytes)")
                ax.set_ylabel(ylabel)
                if rowi == 0:
                    ax.set_title(f"throughput, {st.label}")
        legend(fig, axes)
        path = os.path.join(img_dir, f"{prefix}-throughput.png")
        fig.savefig(path, dpi=90)
        plt.close(fig)
        files.append(path)
    used = [s for s in settings if any(k[0] == s.name for k in lat)]
    if used:
        fig, axes = plt.subplots(1, len(used), figsize=(5.2 * len(used), 4.6), squeeze=False)
        for col, st in enumerate(used):
            ax = axes[0][col]
            rates = sorted({k[3] for k in lat if k[0] == st.name}, key=rate_key)
            pos = {r: i for i, r in enumerate(rates)}
            for sys in systems:
                pts = sorted(((k[3], v) for k, v in lat.items() if k[0] == st.name and k[1] == sys.name),
                             key=lambda p: rate_key(p[0]))
                if not pts:
                    continue
                xs = [pos[p[0]] for p in pts]
                c = colors.get(sys.name)
                ax.plot(xs, [num(p[1]["p50_us"]) for p in pts], marker=markers.get(sys.name, "."), color=c,
                        label=f"{sys.label} p50")
                ax.plot(xs, [num(p[1]["p99_us"]) for p in pts], linestyle=":", color=c, alpha=0.8)
            ax.set_xticks(range(len(rates)))
            ax.set_xticklabels([human_rate(r) for r in rates])
            ax.set_yscale("log")
            ax.grid(True, which="both", alpha=0.3)
            ax.set_xlabel("round trips per second (max = next ping when the pong is back)")
            ax.set_ylabel("one-way latency, µs (solid p50, dotted p99)")
            ax.set_title(f"latency, {st.label}")
        legend(fig, axes)
        path = os.path.join(img_dir, f"{prefix}-latency.png")
        fig.savefig(path, dpi=90)
        plt.close(fig)
        files.append(path)
    return files


# ------------------------------------------------------------- markdown

def ratio(a, b):
    if a is None or b is None or b == 0:
        return None
    return a / b


def fmt_ratio(r):
    return "–" if r is None else f"{r:.2f}×"


def median(xs):
    xs = sorted(x for x in xs if x is not None)
    if not xs:
        return None
    n = len(xs)
    return xs[n // 2] if n % 2 else (xs[n // 2 - 1] + xs[n // 2]) / 2


def summary(rows, settings, labels):
    """Headline numbers, computed from the rows (so they always match the tables)."""
    tput = index(rows, "throughput")
    lat = index(rows, "latency")
    out = []
    for st in settings:
        sizes = sorted({k[2] for k in tput if k[0] == st.name and k[1] == "ddsperf"})
        if not sizes:
            continue

        def ratios(system, pick=lambda size: True):
            return [(size, ratio(num(tput[(st.name, system, size, "")]["msgs_per_s"]),
                                 num(tput[(st.name, "ddsperf", size, "")]["msgs_per_s"])))
                    for size in sizes if pick(size) and (st.name, system, size, "") in tput]

        parts = []
        for system in ("dds-batch", "dds"):
            rs = ratios(system)
            if rs:
                within = sum(1 for _, r in rs if r is not None and r >= 0.9)
                parts.append(f"{labels[system]} / ddsperf: median {fmt_ratio(median(r for _, r in rs))} "
                             f"(range {fmt_ratio(min(r for _, r in rs))} – {fmt_ratio(max(r for _, r in rs))}; "
                             f"within 10 % or better at {within} of {len(rs)} sizes)")
        rs = ratios("zenoh", lambda size: size <= 256)
        if rs:
            parts.append(f"Zenoh / ddsperf for messages ≤ 256 B: "
                         + ", ".join(f"{human_size(size)} {fmt_ratio(r)}" for size, r in rs)
                         + (" (target ≥ 2×: met)" if all(r is not None and r >= 2 for _, r in rs)
                            else " (target ≥ 2×: not met everywhere)"))
        if parts:
            out.append(f"**{st.label}** throughput: " + "; ".join(parts) + ".")
    for st in settings:
        parts = []
        for system in labels:
            pts = {k[3]: v for k, v in lat.items() if k[0] == st.name and k[1] == system}
            if not pts:
                continue
            cells = [f"{human_rate(rate)} {fmt_us(num(pts[rate]['p50_us']))}"
                     for rate in sorted(pts, key=rate_key) if rate in ("10", "1000", "max")]
            if cells:
                parts.append(f"{labels[system]}: " + ", ".join(cells))
        if parts:
            out.append(f"**{st.label}** latency p50 (10 Hz, 1 kHz, max): " + "; ".join(parts) + ".")
    return out


def markdown(rows, settings, systems, meta, images, notes):
    tput = index(rows, "throughput")
    lat = index(rows, "latency")
    sysnames = [s.name for s in systems]
    labels = {s.name: s.label for s in systems}
    out = []
    w = out.append
    w("# Transport baseline: rvc perf vs ddsperf\n")
    w("Generated by `bench/baseline/run` (see `docs/perf.md` for the tools and what each number means). "
      "Do not edit by hand: rerun the command below.\n")
    w("## How it was measured\n")
    w("```sh\n" + meta["command"] + "\n```\n")
    w("| | |\n|---|---|")
    for k in ("date", "cpu", "cores", "memory", "kernel", "load", "rvc", "zenoh", "cyclonedds", "duration"):
        if k in meta:
            w(f"| {k} | {meta[k]} |")
    w("")
    w("Network settings:\n")
    for st in settings:
        w(f"* **{st.label}** (`{st.name}`): {st.describe()}")
    w("")
    w("Systems:\n")
    w("* **rvc perf, Zenoh**: `rvc perf pub/sub --transport zenoh`, reliable, congestion control Block, "
      "peer to peer over TCP.")
    w("* **rvc perf, DDS**: `rvc perf pub/sub --transport dds --no-dds-write-batch` (rvc's CycloneDDS transport: "
      "reliable, keep-all, one packet per sample, what `rvc replay` did by default until 2026-11-27).")
    w("* **rvc perf, DDS + write batching**: the same with `--write-batch` (CycloneDDS `Internal/WriteBatch`, "
      "several samples per packet, which is what ddsperf does and what `rvc replay` and `rvc perf pub` now do by "
      "default); throughput only.")
    w("* **rvc DDS->Zenoh bridge**: `rvc perf pub --transport dds` -> `rvc bridge dds:… zenoh:…` -> "
      "`rvc perf sub --transport zenoh`; latency: DDS ping -> bridge -> Zenoh pong -> bridge -> DDS.")
    w("* **ddsperf**: CycloneDDS's `ddsperf` (Debian cyclonedds-tools), `pub`/`sub` and `ping`/`pong`, "
      "pinned with `CYCLONEDDS_URI` to the configuration rvc generates for the same interface.\n")

    w("## Summary\n")
    for line in summary(rows, settings, labels):
        w(f"* {line}")
    w("")
    # -- throughput tables
    w("## Throughput (messages/s, reliable, publisher as fast as possible)\n")
    for img in images:
        if "throughput" in img:
            w(f"![throughput vs size](img/{os.path.basename(img)})\n")
    for st in settings:
        sizes = sorted({k[2] for k in tput if k[0] == st.name})
        cols = [s for s in sysnames if any(k[0] == st.name and k[1] == s for k in tput)]
        if not sizes:
            continue
        w(f"### {st.label}\n")
        def tput_cell(r):
            return "–" if r is None else (f"{fmt_mps(num(r['msgs_per_s']))} ({num(r['mbps']):.0f} Mb/s)"
                                          + (f" **lost {r['lost']}**" if r["lost"] not in ("", "0", 0) else ""))
        md_table(w, ["size"] + [labels[c] for c in cols],
                 [[human_size(size)] + [tput_cell(tput.get((st.name, c, size, ""))) for c in cols] for size in sizes])
    # -- ratios
    w("## rvc perf / ddsperf\n")
    w("Throughput ratios (messages/s of rvc perf divided by ddsperf's at the same size and setting; "
      "targets from the issue: DDS within 10 % of ddsperf, Zenoh small messages ≥ 2×).\n")
    for st in settings:
        sizes = sorted({k[2] for k in tput if k[0] == st.name and k[1] == "ddsperf"})
        if not sizes:
            continue
        cols = [c for c in ("dds", "dds-batch", "zenoh", "dds-zenoh") if any(k[0] == st.name and k[1] == c
                                                                            for k in tput)]
        w(f"### {st.label}\n")
        def ratio_cell(c, size):
            d = num(tput[(st.name, "ddsperf", size, "")]["msgs_per_s"])
            r = tput.get((st.name, c, size, ""))
            return "–" if r is None else fmt_ratio(ratio(num(r["msgs_per_s"]), d))
        md_table(w, ["size"] + [labels[c] + " / ddsperf" for c in cols],
                 [[human_size(size)] + [ratio_cell(c, size) for c in cols] for size in sizes])
    # -- latency
    w("## Latency (one-way = round trip / 2)\n")
    for img in images:
        if "latency" in img:
            w(f"![latency vs rate](img/{os.path.basename(img)})\n")
    for st in settings:
        rates = sorted({k[3] for k in lat if k[0] == st.name}, key=rate_key)
        cols = [s for s in sysnames if any(k[0] == st.name and k[1] == s for k in lat)]
        if not rates:
            continue
        sizes = sorted({k[2] for k in lat if k[0] == st.name})
        w(f"### {st.label} ({', '.join(human_size(s) for s in sizes)} payload)\n")
        w("p50 / p99 / max per rate:\n")
        def lat_cell(c, rate):
            r = next((v for k, v in lat.items() if k[0] == st.name and k[1] == c and k[3] == rate), None)
            return "–" if r is None else f"{fmt_us(num(r['p50_us']))} / {fmt_us(num(r['p99_us']))} / {fmt_us(num(r['max_us']))}"
        md_table(w, ["rate"] + [labels[c] for c in cols],
                 [[human_rate(rate)] + [lat_cell(c, rate) for c in cols] for rate in rates])
    failed = [r for r in rows if str(r["ok"]) != "True"]
    if failed or notes:
        w("## Not measured / notes\n")
        for n in notes:
            w(f"* {n}")
        for r in failed:
            w(f"* {r['kind']} {r['setting']} {r['system']} size {r['size']} rate {r['rate'] or '-'}: {r['note']}")
        w("")
    return "\n".join(out) + "\n"
