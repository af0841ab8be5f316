"""What the baseline measures: a *system* is one way of moving messages
(rvc perf over Zenoh, over DDS, through the DDS->Zenoh bridge, or ddsperf),
measured in a *setting* (settings.py) that says where its two sides run.

Each system has throughput(ctx, setting, size) and latency(ctx, setting,
size, rate), returning one result row (a dict). Processes are started only
through the setting's hooks, every wait is bounded, and every process is
killed if it outlives its bound.
"""
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import time

ROW_FIELDS = ["kind", "setting", "system", "size", "rate", "seconds", "msgs_per_s", "mbps", "lost", "sent",
              "received", "count", "mean_us", "min_us", "p50_us", "p90_us", "p99_us", "max_us", "ok", "note"]


class Ctx:
    """What every measurement shares: binaries, durations, log directory,
    DDS domain ids and Zenoh ports (never reused within a run)."""

    def __init__(self, rvc, ddsperf, logdir, tput_seconds, lat_seconds, ddsperf_tput_seconds, verbose=False):
        self.rvc, self.ddsperf, self.logdir = rvc, ddsperf, logdir
        self.tput_seconds, self.lat_seconds = tput_seconds, lat_seconds
        # rvc perf sub leaves the ramp-up out of msgs_per_s, as the runner
        # leaves ddsperf's partial first second out.
        self.tput_warmup = min(0.5, tput_seconds / 4)
        self.ddsperf_tput_seconds = ddsperf_tput_seconds
        self.verbose = verbose
        self._domain = 0
        self._n = 0
        os.makedirs(logdir, exist_ok=True)

    def domain(self):
        # 20..39: clear of the DDS test suites (40..49, 70..119, 150..229) and
        # of the Zenoh test ports (domain d uses UDP ports around 7400 + 250 d).
        self._domain += 1
        return 20 + self._domain % 20

    def port(self, setting):
        """A free TCP port for a Zenoh listener (loopback: checked free on 127.0.0.1;
        in fresh namespaces every port is free)."""
        for _ in range(200):
            p = 20000 + (os.getpid() * 7 + self._n * 13 + int(time.time() * 1000)) % 10000
            self._n += 1
            if setting.host("b") != "127.0.0.1":
                return p
            s = socket.socket()
            try:
                s.bind(("127.0.0.1", p))
                return p
            except OSError:
                continue
            finally:
                s.close()
        raise RuntimeError("no free port in 20000-29999")

    def log(self, name):
        self._n += 1
        return os.path.join(self.logdir, f"{self._n:04d}-{name}")


class Proc:
    """A started program with its stdout/stderr in log files."""

    def __init__(self, ctx, setting, side, argv, name, env=None):
        base = ctx.log(name)
        self.out_path, self.err_path = base + ".out", base + ".err"
        self.argv = argv
        self._out = open(self.out_path, "w")
        self._err = open(self.err_path, "w")
        self.p = setting.popen(side, argv, env=env, stdout=self._out, stderr=self._err)
        if ctx.verbose:
            print("   $", " ".join(setting.argv(side, argv)), flush=True)

    def text(self, which="out"):
        with open(self.out_path if which == "out" else self.err_path, errors="replace") as f:
            return f.read()

    def wait_text(self, pattern, timeout, which="err"):
        """Waits until the log matches pattern (a regex); False on timeout or exit."""
        rx = re.compile(pattern)
        deadline = time.time() + timeout
        while time.time() < deadline:
            if rx.search(self.text(which)):
                return True
            if self.p.poll() is not None:
                return bool(rx.search(self.text(which)))
            time.sleep(0.02)
        return False

    def wait(self, timeout):
        """Exit code, or None after killing the process on timeout."""
        try:
            return self.p.wait(timeout=max(timeout, 0.1))
        except subprocess.TimeoutExpired:
            self.kill()
            return None

    def stop(self, grace=3.0):
        """SIGTERM (programs print their summary), SIGKILL after grace."""
        if self.p.poll() is None:
            try:
                os.killpg(self.p.pid, signal.SIGTERM)
            except ProcessLookupError:
                pass
            return self.wait(grace)
        return self.p.returncode

    def kill(self):
        if self.p.poll() is None:
            try:
                os.killpg(self.p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            self.p.wait(timeout=10)

    def close(self):
        self.kill()
        self._out.close()
        self._err.close()

    def json(self):
        """The last JSON object line on stdout, or None."""
        for line in reversed(self.text().splitlines()):
            line = line.strip()
            if line.startswith("{"):
                try:
                    return json.loads(line)
                except ValueError:
                    return None
        return None


def row(kind, setting, system, size, rate=None, **kw):
    r = {f: "" for f in ROW_FIELDS}
    r.update(kind=kind, setting=setting.name, system=system, size=size, rate=rate if rate is not None else "",
             ok=False)
    r.update(kw)
    return r


def rate_arg(rate):
    return "max" if rate in (None, 0, "max") else str(rate)


def close_all(*procs):
    for p in procs:
        if p is not None:
            p.close()


def fail_note(*procs):
    """A short explanation from the logs of processes that failed."""
    notes = []
    for p in procs:
        if p is None:
            continue
        rc = p.p.poll()
        if rc not in (0, None):
            tail = [l for l in p.text("err").splitlines() if l.strip()][-1:] or [""]
            notes.append(f"{os.path.basename(p.argv[0])} exit {rc}: {tail[0][:160]}")
    return "; ".join(notes)


# ------------------------------------------------------------------ rvc perf

class RvcPerf:
    """rvc perf over one transport. `batch`: DDS publisher with --write-batch."""

    def __init__(self, name, label, transport, batch=False, latency=True):
        self.name, self.label, self.transport, self.batch = name, label, transport, batch
        self.do_latency = latency

    def supports(self, setting, kind):
        return kind == "throughput" or self.do_latency

    def flags(self, ctx, setting, side, port, domain):
        if self.transport == "zenoh":
            common = ["--no-multicast-scouting"]
            if setting.inproc:
                return common + ["--listen", "tcp/127.0.0.1:0"]
            if side == "b":
                return common + ["--listen", f"tcp/{setting.host('b')}:{port}"]
            return common + ["--listen", f"tcp/{setting.host('a')}:0", "--connect", f"tcp/{setting.host('b')}:{port}"]
        return ["--domain", str(domain), *setting.dds_flags(side)]

    def base(self, ctx, mode):
        return [ctx.rvc, "perf", mode, "--transport", self.transport, "--key", "rvc_perf"]

    def throughput(self, ctx, setting, size):
        port = ctx.port(setting) if self.transport == "zenoh" else 0
        dom = ctx.domain()
        secs = ctx.tput_seconds
        # rvc perf pub batches DDS writes by default (as rvc replay does): the unbatched series asks for one
        # packet per sample explicitly, so both regimes stay measured.
        pub_extra = ["--size", str(size), "--duration", str(secs)] + (
            ["--write-batch"] if self.batch else ["--no-dds-write-batch"] if self.transport == "dds" else [])
        sub = pub = None
        try:
            if setting.inproc:
                pub = Proc(ctx, setting, "a", self.base(ctx, "pub") + pub_extra +
                           ["--inproc", "--warmup", str(ctx.tput_warmup)] +
                           self.flags(ctx, setting, "a", port, dom), f"{self.name}-inproc")
                pub.wait(secs + 60)
                res = pub.json()
            else:
                sub = Proc(ctx, setting, "b", self.base(ctx, "sub") + ["--warmup", str(ctx.tput_warmup)] +
                           self.flags(ctx, setting, "b", port, dom), f"{self.name}-sub")
                if not sub.wait_text(r"ready on", 20):
                    return row("throughput", setting, self.name, size, note="subscriber not ready: " + fail_note(sub))
                pub = Proc(ctx, setting, "a", self.base(ctx, "pub") + pub_extra +
                           self.flags(ctx, setting, "a", port, dom), f"{self.name}-pub")
                pub.wait(secs + 60)
                sub.wait(15)
                res = sub.json()
            if not res or res.get("received", 0) == 0:
                return row("throughput", setting, self.name, size, note="no result: " + fail_note(sub, pub))
            return row("throughput", setting, self.name, size, seconds=res["seconds"],
                       msgs_per_s=res["msgs_per_s"], mbps=res["mbps"], lost=res["lost"], sent=res["sent"],
                       received=res["received"], ok=True)
        finally:
            close_all(sub, pub)

    def latency(self, ctx, setting, size, rate):
        port = ctx.port(setting) if self.transport == "zenoh" else 0
        dom = ctx.domain()
        secs = ctx.lat_seconds(rate)
        ping_extra = ["--size", str(size), "--rate", rate_arg(rate), "--duration", str(secs), "--warmup", "0.2"]
        pong = ping = None
        try:
            if setting.inproc:
                ping = Proc(ctx, setting, "a", self.base(ctx, "ping") + ping_extra + ["--inproc"] +
                            self.flags(ctx, setting, "a", port, dom), f"{self.name}-ping-inproc")
            else:
                pong = Proc(ctx, setting, "b", self.base(ctx, "pong") + self.flags(ctx, setting, "b", port, dom),
                            f"{self.name}-pong")
                if not pong.wait_text(r"ready on", 20):
                    return row("latency", setting, self.name, size, rate, note="pong not ready: " + fail_note(pong))
                ping = Proc(ctx, setting, "a", self.base(ctx, "ping") + ping_extra +
                            self.flags(ctx, setting, "a", port, dom), f"{self.name}-ping")
            ping.wait(secs + 60)
            if pong:
                pong.wait(10)
            return latency_row(setting, self.name, size, rate, ping.json(), fail_note(ping, pong))
        finally:
            close_all(pong, ping)


def latency_row(setting, system, size, rate, res, note):
    if not res or not res.get("count"):
        return row("latency", setting, system, size, rate, note="no result: " + note)
    return row("latency", setting, system, size, rate, count=res["count"], sent=res["sent"], lost=res["lost"],
               mean_us=res["mean_us"], min_us=res["min_us"], p50_us=res["p50_us"], p90_us=res["p90_us"],
               p99_us=res["p99_us"], max_us=res["max_us"], ok=True)


class RvcBridge:
    """DDS -> Zenoh through `rvc bridge`, which runs on side a next to the DDS
    publisher (DDS stays local to a side, Zenoh crosses the setting's
    network). Latency: DDS ping -> bridge -> Zenoh pong -> bridge -> DDS."""

    name, label = "dds-zenoh", "rvc DDS->Zenoh bridge"

    def supports(self, setting, kind):
        return not setting.inproc

    def bridge(self, ctx, setting, routes, port, dom, name):
        return Proc(ctx, setting, "a",
                    [ctx.rvc, "bridge", *routes, "--exit-on-eos", "--dds-type", "frame", "--domain", str(dom),
                     *setting.dds_flags("a"), "--no-multicast-scouting", "--listen", f"tcp/{setting.host('a')}:0",
                     "--connect", f"tcp/{setting.host('b')}:{port}"], name)

    def zenoh_b(self, setting, port):
        return ["--no-multicast-scouting", "--listen", f"tcp/{setting.host('b')}:{port}"]

    def throughput(self, ctx, setting, size):
        port, dom, secs = ctx.port(setting), ctx.domain(), ctx.tput_seconds
        sub = br = pub = None
        try:
            sub = Proc(ctx, setting, "b", [ctx.rvc, "perf", "sub", "--transport", "zenoh", "--key", "rvc_perf",
                                           "--warmup", str(ctx.tput_warmup), *self.zenoh_b(setting, port)],
                       "bridge-sub")
            if not sub.wait_text(r"ready on", 20):
                return row("throughput", setting, self.name, size, note="subscriber not ready: " + fail_note(sub))
            br = self.bridge(ctx, setting, ["dds:rvc_perf", "zenoh:rvc_perf"], port, dom, "bridge")
            if not br.wait_text(r"forwarding", 40):
                return row("throughput", setting, self.name, size, note="bridge not ready: " + fail_note(br))
            pub = Proc(ctx, setting, "a", [ctx.rvc, "perf", "pub", "--transport", "dds", "--key", "rvc_perf",
                                           "--size", str(size), "--duration", str(secs), "--domain", str(dom),
                                           *setting.dds_flags("a")], "bridge-pub")
            pub.wait(secs + 60)
            br.wait(20)
            sub.wait(15)
            res = sub.json()
            if not res or res.get("received", 0) == 0:
                return row("throughput", setting, self.name, size, note="no result: " + fail_note(sub, br, pub))
            return row("throughput", setting, self.name, size, seconds=res["seconds"],
                       msgs_per_s=res["msgs_per_s"], mbps=res["mbps"], lost=res["lost"], sent=res["sent"],
                       received=res["received"], ok=True)
        finally:
            close_all(pub, br, sub)

    def latency(self, ctx, setting, size, rate):
        port, dom, secs = ctx.port(setting), ctx.domain(), ctx.lat_seconds(rate)
        pong = ping = br = None
        try:
            pong = Proc(ctx, setting, "b", [ctx.rvc, "perf", "pong", "--transport", "zenoh", "--key", "rvc_perf",
                                            *self.zenoh_b(setting, port)], "bridge-pong")
            if not pong.wait_text(r"ready on", 20):
                return row("latency", setting, self.name, size, rate, note="pong not ready: " + fail_note(pong))
            ping = Proc(ctx, setting, "a", [ctx.rvc, "perf", "ping", "--transport", "dds", "--key", "rvc_perf",
                                            "--size", str(size), "--rate", rate_arg(rate), "--duration", str(secs),
                                            "--warmup", "0.2", "--domain", str(dom), *setting.dds_flags("a")],
                        "bridge-ping")
            br = self.bridge(ctx, setting, ["dds:rvc_perf/ping", "zenoh:rvc_perf/ping",
                                            "zenoh:rvc_perf/pong", "dds:rvc_perf/pong"], port, dom, "bridge2")
            ping.wait(secs + 60)
            br.wait(20)
            pong.wait(10)
            return latency_row(setting, self.name, size, rate, ping.json(), fail_note(ping, br, pong))
        finally:
            close_all(ping, br, pong)


# ------------------------------------------------------------------- ddsperf

_LINE_T = r"^\[\d+\]\s+(?P<t>[\d.]+)\s+"
SUB_RX = re.compile(_LINE_T + r"size (?P<size>\d+) total (?P<total>\d+) lost (?P<lost>\d+) delta (?P<delta>\d+) "
                    r"lost (?P<dlost>\d+) rate (?P<rate>[\d.]+) kS/s (?P<mbps>[\d.]+) Mb/s")
PING_RX = re.compile(_LINE_T + r"(?:\S+ )?size (?P<size>\d+) mean (?P<mean>[\d.]+)us min (?P<min>[\d.]+)us "
                     r"50% (?P<p50>[\d.]+)us 90% (?P<p90>[\d.]+)us 99% (?P<p99>[\d.]+)us max (?P<max>[\d.]+)us "
                     r"cnt (?P<cnt>\d+)")


def parse_ddsperf_sub(text):
    """Throughput from `ddsperf sub` output: the per-second lines
       [pid] T  size S total N lost L delta D lost l rate R kS/s M Mb/s (...)
    The first and the last interval that carried data are partial (the
    publisher started or stopped inside them) and are left out; the rate is
    the mean of the full ones (all intervals if there are fewer than three)."""
    lines = [m.groupdict() for m in map(SUB_RX.search, text.splitlines()) if m]
    data = [l for l in lines if int(l["delta"]) > 0]
    if not data:
        return None
    full = data[1:-1] if len(data) >= 3 else data
    t = [float(l["t"]) for l in lines]
    rates = [float(l["rate"]) * 1e3 for l in full]
    size = int(data[-1]["size"])
    mps = sum(rates) / len(rates)
    return {"size": size, "msgs_per_s": mps, "mbps": mps * size * 8 / 1e6, "received": int(data[-1]["total"]),
            "lost": int(data[-1]["lost"]), "intervals": len(full), "seconds": (t[-1] - t[0]) if t else 0}


def parse_ddsperf_ping(text):
    """Latency from `ddsperf ping` output: per-second lines
       [pid] T  host:pid size S mean Xus min Xus 50% Xus 90% Xus 99% Xus max Xus cnt N
    (one-way = round trip / 2, as rvc perf reports). The first interval
    (discovery, warm-up) is left out when there are more. Over the rest:
    mean weighted by count, min of mins, max of maxes, and for p50/p90/p99 the
    count-weighted median of the per-second percentiles (ddsperf prints no
    raw samples, so this approximates the percentiles of the whole run)."""
    lines = [m.groupdict() for m in map(PING_RX.search, text.splitlines()) if m]
    if not lines:
        return None
    if len(lines) > 1:
        lines = lines[1:]
    cnt = sum(int(l["cnt"]) for l in lines)
    if cnt == 0:
        return None

    def wmedian(key):
        pts = sorted((float(l[key]), int(l["cnt"])) for l in lines)
        acc = 0
        for v, c in pts:
            acc += c
            if acc * 2 >= cnt:
                return v
        return pts[-1][0]

    return {"count": cnt, "sent": cnt, "lost": 0, "size": int(lines[-1]["size"]),
            "mean_us": sum(float(l["mean"]) * int(l["cnt"]) for l in lines) / cnt,
            "min_us": min(float(l["min"]) for l in lines), "max_us": max(float(l["max"]) for l in lines),
            "p50_us": wmedian("p50"), "p90_us": wmedian("p90"), "p99_us": wmedian("p99")}


class DdsPerf:
    """CycloneDDS's own ddsperf (Debian cyclonedds-tools), pinned with
    CYCLONEDDS_URI to the XML rvc generates for the same interface.
    Type KS (seq, key, octet sequence): `size` counts its 12-byte fixed part,
    so sizes below 12 run as 12."""

    name, label = "ddsperf", "ddsperf (CycloneDDS)"

    def supports(self, setting, kind):
        return True

    def env(self, setting, side):
        return {"CYCLONEDDS_URI": "file://" + setting.dds_xml(side)}

    @staticmethod
    def size_arg(size):
        return str(max(size, 12))

    def throughput(self, ctx, setting, size):
        dom, secs = ctx.domain(), ctx.ddsperf_tput_seconds
        common = [ctx.ddsperf, "-i", str(dom)]
        sub = pub = None
        try:
            if setting.inproc:
                pub = Proc(ctx, setting, "a", common + ["-L", "-D", str(secs), "pub", "size", self.size_arg(size),
                                                        "sub"], "ddsperf-inproc", env=self.env(setting, "a"))
                pub.wait(secs + 30)
                res = parse_ddsperf_sub(pub.text())
            else:
                sub = Proc(ctx, setting, "b", common + ["-D", str(secs + 10), "sub"], "ddsperf-sub",
                           env=self.env(setting, "b"))
                if not sub.wait_text(r"new \(self\)", 20, which="out"):
                    return row("throughput", setting, self.name, size, note="ddsperf sub did not start: " +
                               fail_note(sub))
                pub = Proc(ctx, setting, "a", common + ["-D", str(secs), "pub", "size", self.size_arg(size)],
                           "ddsperf-pub", env=self.env(setting, "a"))
                pub.wait(secs + 30)
                time.sleep(1.2)  # one more statistics line after the publisher stopped
                sub.stop()
                res = parse_ddsperf_sub(sub.text())
            if not res:
                return row("throughput", setting, self.name, size, note="no ddsperf statistics: " +
                           fail_note(sub, pub))
            return row("throughput", setting, self.name, size, seconds=res["seconds"],
                       msgs_per_s=res["msgs_per_s"], mbps=res["mbps"], lost=res["lost"], received=res["received"],
                       ok=True, note=f"ddsperf size {res['size']}" if res["size"] != size else "")
        finally:
            close_all(sub, pub)

    def latency(self, ctx, setting, size, rate):
        dom, secs = ctx.domain(), ctx.lat_seconds(rate) + 1  # its first second is discarded
        spec = ["ping"] + ([] if rate_arg(rate) == "max" else [f"{rate}Hz"]) + ["size", self.size_arg(size)]
        common = [ctx.ddsperf, "-i", str(dom)]
        pong = ping = None
        try:
            if setting.inproc:
                ping = Proc(ctx, setting, "a", common + ["-L", "-D", str(secs)] + spec + ["pong"], "ddsperf-pingpong",
                            env=self.env(setting, "a"))
                ping.wait(secs + 30)
            else:
                pong = Proc(ctx, setting, "b", common + ["-D", str(secs + 10), "pong"], "ddsperf-pong",
                            env=self.env(setting, "b"))
                if not pong.wait_text(r"new \(self\)", 20, which="out"):
                    return row("latency", setting, self.name, size, rate, note="ddsperf pong did not start: " +
                               fail_note(pong))
                ping = Proc(ctx, setting, "a", common + ["-D", str(secs)] + spec, "ddsperf-ping",
                            env=self.env(setting, "a"))
                ping.wait(secs + 30)
                pong.stop()
            res = parse_ddsperf_ping(ping.text())
            return latency_row(setting, self.name, size, rate, res, fail_note(ping, pong))
        finally:
            close_all(pong, ping)


def all_systems(ddsperf_path):
    systems = [RvcPerf("zenoh", "rvc perf, Zenoh", "zenoh"),
               RvcPerf("dds", "rvc perf, DDS", "dds"),
               RvcPerf("dds-batch", "rvc perf, DDS + write batching", "dds", batch=True, latency=False),
               RvcBridge()]
    if ddsperf_path:
        systems.append(DdsPerf())
    return systems
