"""Network settings of the baseline runner: *where* the two sides of a
measurement run and how they reach each other.

Every measurement has two sides: side "a" publishes (pub, ping, the DDS side
of a bridge) and side "b" subscribes (sub, pong). A setting says

  * how to start a program on a side           popen(side, argv, env, ...)
  * which address a side's listeners bind to   host(side)
  * how a DDS participant on a side is pinned  dds_flags(side), dds_xml(side)
  * whether both sides are one process         inproc
  * how to set up / tear down the network      __enter__ / __exit__

and nothing else: the systems (rvc perf over Zenoh or DDS, the DDS->Zenoh
bridge, ddsperf) are built only from these hooks, so a new setting (a Docker
bridge network, host networking, macvlan, a shared network namespace) is one
subclass registered with register_setting(); modules named settings_*.py next
to this file are imported by the runner, so they can register themselves
without touching the runner.

Network safety: nothing here touches a host interface. Loopback settings use
127.0.0.1 and interface lo; the netns setting creates two namespaces joined by
a veth pair whose ends are created directly inside them, with 10.203.0.x/30
addresses that exist only there, and removes everything on exit (also on
errors and SIGTERM, via the context manager).
"""
import os
import shutil
import subprocess
import tempfile

SETTINGS = {}


def register_setting(cls):
    """Class decorator: makes a setting selectable by its `name`."""
    SETTINGS[cls.name] = cls
    return cls


class Setting:
    name = "base"
    label = "base"
    description = ""
    inproc = False  # both sides are the same process (systems that cannot do that are skipped)

    def __init__(self, rvc):
        self.rvc = rvc
        self._tmp = None
        self._xml = {}

    # -- lifecycle --------------------------------------------------------
    def __enter__(self):
        self._tmp = tempfile.mkdtemp(prefix=f"rvc-baseline-{self.name}-")
        return self

    def __exit__(self, *exc):
        if self._tmp:
            shutil.rmtree(self._tmp, ignore_errors=True)
        return False

    # -- hooks ------------------------------------------------------------
    def argv(self, side, argv):
        """The command line that runs argv on a side (e.g. wrapped in ip netns exec)."""
        return list(argv)

    def popen(self, side, argv, env=None, stdout=None, stderr=None):
        full_env = dict(os.environ)
        full_env.update(env or {})
        return subprocess.Popen(self.argv(side, argv), env=full_env, stdout=stdout, stderr=stderr,
                                stdin=subprocess.DEVNULL, start_new_session=True)

    def host(self, side):
        """IPv4 address a listener on this side binds to (and the other side connects to)."""
        return "127.0.0.1"

    def dds_flags(self, side):
        """rvc DDS flags that pin a participant on this side to the setting's network."""
        return ["--dds-interface", "lo"]

    def dds_xml(self, side):
        """CycloneDDS XML file for non-rvc DDS programs (ddsperf) on this side: the
        configuration rvc itself would generate for dds_flags(side)."""
        if side not in self._xml:
            path = os.path.join(self._tmp, f"cyclonedds-{side}.xml")
            subprocess.run([self.rvc, "dds-config", *self.dds_flags(side), "--output", path], check=True,
                           stdout=subprocess.DEVNULL, timeout=30)
            self._xml[side] = path
        return self._xml[side]

    def describe(self):
        return self.description


@register_setting
class Inproc(Setting):
    name = "inproc"
    label = "in-process"
    description = ("publisher and subscriber (ping and pong) in one process: one Zenoh session / one DDS "
                   "participant, delivery without a network (ddsperf -L)")
    inproc = True


@register_setting
class Loopback(Setting):
    name = "loopback"
    label = "loopback"
    description = "two processes on one host over the loopback interface (Zenoh tcp/127.0.0.1, DDS pinned to lo)"


@register_setting
class Netns(Setting):
    """Two network namespaces joined by a veth pair, 10.203.0.1/30 <-> 10.203.0.2/30."""
    name = "netns"
    label = "netns+veth"
    description = ("two processes in two network namespaces (rvcA, rvcB) joined by a veth pair "
                   "(10.203.0.1/30 <-> 10.203.0.2/30), created and removed by the runner")
    NS = {"a": "rvcA", "b": "rvcB"}
    DEV = {"a": "rvcvA", "b": "rvcvB"}
    ADDR = {"a": "10.203.0.1", "b": "10.203.0.2"}

    @staticmethod
    def available():
        """(ok, reason): creating namespaces needs root and iproute2."""
        if shutil.which("ip") is None:
            return False, "iproute2 'ip' not found"
        if os.geteuid() != 0:
            return False, "needs root (ip netns add)"
        return True, ""

    @classmethod
    def _ip(cls, *args, check=True):
        return subprocess.run(["ip", *args], check=check, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                              text=True, timeout=30)

    @classmethod
    def existing(cls):
        out = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True, timeout=30).stdout
        names = {line.split()[0] for line in out.splitlines() if line.strip()}
        return sorted(names & set(cls.NS.values()))

    @classmethod
    def cleanup(cls):
        """Removes the namespaces (and with them the veth pair) if they exist."""
        for ns in cls.existing():
            cls._ip("netns", "del", ns, check=False)

    def __enter__(self):
        ok, why = self.available()
        if not ok:
            raise RuntimeError(f"netns setting unavailable: {why}")
        stale = self.existing()
        if stale:
            raise RuntimeError(f"network namespaces {stale} already exist (another run, or a killed one: "
                               f"bench/baseline/run --netns-cleanup removes them)")
        super().__enter__()
        self._created = True
        try:
            for side in "ab":
                self._ip("netns", "add", self.NS[side])
            # Both ends are created inside the namespaces: the host's own
            # interfaces and routes never change.
            self._ip("link", "add", self.DEV["a"], "netns", self.NS["a"], "type", "veth",
                     "peer", "name", self.DEV["b"], "netns", self.NS["b"])
            for side in "ab":
                ns = self.NS[side]
                self._ip("-n", ns, "addr", "add", self.ADDR[side] + "/30", "dev", self.DEV[side])
                self._ip("-n", ns, "link", "set", "lo", "up")
                self._ip("-n", ns, "link", "set", self.DEV[side], "up")
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def __exit__(self, *exc):
        if getattr(self, "_created", False):
            for side in "ab":
                self._ip("netns", "del", self.NS[side], check=False)
            self._created = False
        return super().__exit__(*exc)

    def argv(self, side, argv):
        return ["ip", "netns", "exec", self.NS[side], *argv]

    def host(self, side):
        return self.ADDR[side]

    def dds_flags(self, side):
        # Unicast discovery to both ends (a side's own address too, so that two
        # participants on one side, e.g. publisher and bridge, find each other).
        return ["--dds-interface", self.DEV[side], "--dds-peer", self.ADDR["a"], "--dds-peer", self.ADDR["b"]]
