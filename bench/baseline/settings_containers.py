"""Container network settings for the baseline runner (paper Fig. 4: throughput and latency per
container network mode). Registered on import by bench/baseline/run:

  bench/baseline/run --settings docker-bridge,docker-host,docker-macvlan,docker-shared
  (docker-ipvlan is listed but skipped where the kernel has no ipvlan)

Each side ("a": publisher/ping/bridge, "b": subscriber/pong) is one long-lived container of the
rvc image (deploy/docker, RVC_IMAGE, default rvc:latest) running `sleep infinity`; programs run
in it with `docker exec` through a small wrapper that forwards SIGTERM/SIGINT to the program
inside (docker exec itself forwards no signal), so the runner's stop() still makes them print
their summary. argv[0] equal to the runner's rvc binary becomes the image's `rvc`; other
absolute paths (ddsperf) are bind-mounted read-only from the host at the same path, and so is
the setting's temporary directory (CycloneDDS XML for ddsperf).

Networks (as in deploy/compose, via deploy/compose/rvc_compose.py):
  docker-bridge   internal Docker bridge network, explicit /24 from 172.28.0.0/17
  docker-host     host network stack: loopback addresses only (127.0.0.1, DDS on lo)
  docker-macvlan  macvlan network whose parent is a veth pair created here (never a host NIC)
  docker-ipvlan   ipvlan L2 on such a veth (skipped with the reason where unsupported)
  docker-shared   side b joins side a's namespace, which has only lo (network none)
Everything (containers, network, veth) is removed on exit, also on errors and SIGTERM.
"""
import importlib.util
import os
import shutil
import subprocess
import sys

from settings import Setting, register_setting

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
_spec = importlib.util.spec_from_file_location("rvc_compose", os.path.join(ROOT, "deploy", "compose", "rvc_compose.py"))
rc = sys.modules.get("rvc_compose")
if rc is None:
    rc = importlib.util.module_from_spec(_spec)
    sys.modules["rvc_compose"] = rc
    _spec.loader.exec_module(rc)

IMAGE = os.environ.get("RVC_IMAGE", "rvc:latest")
# The containers run `sleep infinity` and the programs through `sh -c`: the image with a shell
# (deploy/docker/build.sh makes it beside IMAGE; its rvc is the same binary).
DEBUG_IMAGE = rc.debug_image(IMAGE)

# docker exec forwards no signals: run the program in its own session and forward TERM/INT to
# the process inside the container (its pid is written to /tmp/rvcpid.<wrapper pid> there).
WRAPPER = r'''#!/bin/bash
# dexec CONTAINER [-e K=V]... -- ARGV...
c=$1; shift
envs=()
while [ "$#" -gt 0 ] && [ "$1" != "--" ]; do envs+=("$1"); shift; done
shift
tag=$$
setsid docker exec "${envs[@]}" "$c" sh -c 'echo $$ >/tmp/rvcpid.'"$tag"'; exec "$@"' sh "$@" </dev/null &
child=$!
fwd() { docker exec "$c" sh -c "kill -$1 \$(cat /tmp/rvcpid.$tag 2>/dev/null) 2>/dev/null" >/dev/null 2>&1; }
trap 'fwd TERM' TERM
trap 'fwd INT' INT
while :; do
  wait "$child"; rc=$?
  kill -0 "$child" 2>/dev/null || break
done
exit "$rc"
'''


class ContainerSetting(Setting):
    mode = None
    inproc = False

    @classmethod
    def available(cls):
        why = rc.docker_available()
        if why:
            return False, why
        if subprocess.run(["docker", "image", "inspect", DEBUG_IMAGE], capture_output=True).returncode != 0:
            return False, "image %s not built (deploy/docker/build.sh)" % DEBUG_IMAGE
        why = rc.mode_support().get(cls.mode)
        if why:
            return False, why
        return True, ""

    def __enter__(self):
        super().__enter__()
        self.names = {s: "rvcbl%d%s" % (os.getpid(), s) for s in "ab"}
        self.network, self.links, self.ip = None, [], {"a": "127.0.0.1", "b": "127.0.0.1"}
        self.wrapper = os.path.join(self._tmp, "dexec")
        with open(self.wrapper, "w") as f:
            f.write(WRAPPER)
        os.chmod(self.wrapper, 0o755)
        os.chmod(self._tmp, 0o755)
        try:
            self._start()
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def _docker(self, *args):
        r = subprocess.run(["docker", *args], capture_output=True, text=True, timeout=120)
        if r.returncode != 0:
            raise RuntimeError("docker %s: %s" % (args[0], r.stderr.strip()[-500:]))
        return r.stdout.strip()

    def _net_args(self, side):
        if self.mode == "host":
            return ["--network", "host"]
        if self.mode == "shared":
            return ["--network", "none"] if side == "a" else ["--network", "container:" + self.names["a"]]
        return ["--network", self.network, "--ip", self.ip[side]]

    def _start(self):
        if self.mode in ("bridge", "macvlan", "ipvlan"):
            subnet = rc.pick_subnet()
            hosts = list(subnet.hosts())
            self.ip = {"a": str(hosts[9]), "b": str(hosts[10])}
            self.network = "rvcbl%d" % os.getpid()
            opts = ["--subnet", str(subnet)]
            if self.mode == "bridge":
                opts += ["--driver", "bridge", "--internal"]
            else:
                parent = ("rvcmv%d" if self.mode == "macvlan" else "rvciv%d") % subnet.network_address.packed[2]
                if rc.link_exists(parent):
                    raise RuntimeError("link %s already exists" % parent)
                subprocess.run(["ip", "link", "add", parent, "type", "veth", "peer", "name", parent + "p"],
                               check=True, capture_output=True)
                self.links.append(parent)
                for n in (parent, parent + "p"):
                    subprocess.run(["ip", "link", "set", n, "up"], check=True, capture_output=True)
                opts += ["--driver", self.mode, "-o", "parent=" + parent]
                opts += ["-o", "macvlan_mode=bridge"] if self.mode == "macvlan" else ["-o", "ipvlan_mode=l2"]
            self._docker("network", "create", *opts, self.network)
        mounts = ["-v", "%s:%s" % (self._tmp, self._tmp)]
        ddsperf = shutil.which("ddsperf")
        if ddsperf:
            mounts += ["-v", "%s:%s:ro" % (ddsperf, ddsperf)]
        for side in "ab":
            self._docker("run", "-d", "--name", self.names[side], *self._net_args(side), *mounts,
                         "--entrypoint", "sleep", DEBUG_IMAGE, "infinity")

    def __exit__(self, *exc):
        for side in "ab":
            subprocess.run(["docker", "rm", "-f", self.names.get(side, "")], capture_output=True)
        if self.network:
            subprocess.run(["docker", "network", "rm", self.network], capture_output=True)
            self.network = None
        for link in self.links:
            subprocess.run(["ip", "link", "del", link], capture_output=True)
        self.links = []
        return super().__exit__(*exc)

    def _map(self, argv):
        if argv and os.path.abspath(argv[0]) == os.path.abspath(self.rvc):
            return ["rvc"] + list(argv[1:])
        return list(argv)

    def argv(self, side, argv, env=None):
        envs = []
        for k, v in (env or {}).items():
            envs += ["-e", "%s=%s" % (k, v)]
        return [self.wrapper, self.names[side], *envs, "--", *self._map(argv)]

    def popen(self, side, argv, env=None, stdout=None, stderr=None):
        return subprocess.Popen(self.argv(side, argv, env), stdout=stdout, stderr=stderr,
                                stdin=subprocess.DEVNULL, start_new_session=True)

    def host(self, side):
        return self.ip[side]

    def dds_flags(self, side):
        if self.mode in ("host", "shared"):
            return ["--dds-interface", "lo"]
        return ["--dds-interface", self.ip[side], "--dds-peer", self.ip["a"], "--dds-peer", self.ip["b"]]


def _make(mode, label, description):
    cls = type("Docker" + mode.capitalize(), (ContainerSetting,),
               {"name": "docker-" + mode, "label": label, "description": description, "mode": mode})
    return register_setting(cls)


_make("bridge", "docker bridge", "one rvc container per side on an internal Docker bridge network (explicit /24)")
_make("host", "docker host", "one rvc container per side, host network stack, loopback endpoints")
_make("macvlan", "docker macvlan", "one rvc container per side on a macvlan network parented on a veth created here")
_make("ipvlan", "docker ipvlan", "one rvc container per side on an ipvlan (L2) network parented on a veth created here")
_make("shared", "docker shared netns", "two rvc containers sharing one network namespace (only lo)")
