"""Containers (deploy/): the rvc image and the paper's architectures in Docker.

Builds the image with deploy/docker/build.sh (BuildKit cache, or reuses the layers), then runs
architecture (a) — rvc replay in one container, rvc monitor in another — over Zenoh and over DDS
in the bridge and host network modes (plus the shared-namespace and macvlan modes, and ipvlan
where the kernel has it), on a small Timescales trace. Oracle: `rvc check --all` on the same
file, run inside the same image. Every run must lose nothing, and `compose down` must leave no
container, network or veth behind.

Skipped, with the reason, where Docker cannot run at all (scripts/docker-setup.sh failed); under
CI=true that skip is a failure (tests/rvc_testlib.py). A mode the kernel lacks (ipvlan here) is a
"[platform]" skip, allowed everywhere.
All traffic stays inside networks created here (internal bridge network, veth-parented macvlan)
or on loopback (host and shared modes); see deploy/compose/rvc_compose.py.
"""
import importlib.util
import json
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
_spec = importlib.util.spec_from_file_location("rvc_compose", os.path.join(ROOT, "deploy", "compose", "rvc_compose.py"))
rc = importlib.util.module_from_spec(_spec)
sys.modules["rvc_compose"] = rc
_spec.loader.exec_module(rc)

IMAGE = os.environ.get("RVC_IMAGE", "rvc:latest")
FAMILY, BOUND, STEPS = "AlwaysBQR", 10, 20000


def run(cmd, timeout=600, **kw):
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, **kw)


@pytest.fixture(scope="session")
def docker():
    r = run([os.path.join(ROOT, "scripts", "docker-setup.sh")], timeout=900)
    if r.returncode != 0:
        pytest.skip("Docker cannot run on this machine: " + (r.stderr.strip().splitlines() or ["?"])[-1])
    return True


def host_zenoh_lib():
    """The Zenoh staticlib of the host build that made RVC_BIN, if any: the image reuses it instead
    of compiling the crate a second time (RVC_IMAGE_ZENOH=source forces the full in-image build)."""
    if os.environ.get("RVC_IMAGE_ZENOH") == "source" or not os.environ.get("RVC_BIN"):
        return None
    lib = os.environ.get("RVC_ZENOH_LIB")  # set by tests/CMakeLists.txt: where this build put it
    if lib:
        return lib if os.path.isfile(lib) else None
    lib = os.path.join(os.path.dirname(os.environ["RVC_BIN"]), "src", "transport", "zenoh", "librvc_zenoh.a")
    return lib if os.path.isfile(lib) else None


@pytest.fixture(scope="session")
def image(docker):
    cmd = [os.path.join(ROOT, "deploy", "docker", "build.sh"), "--tag", IMAGE]
    if host_zenoh_lib():
        cmd += ["--zenoh-lib", host_zenoh_lib()]
    r = run(cmd, timeout=3600)
    assert r.returncode == 0, "image build failed:\n" + r.stdout[-4000:] + r.stderr[-4000:]
    info = json.loads(r.stdout.strip().splitlines()[-1])
    print("\nimage:", json.dumps(info))
    return info


def in_image(*args, volumes=(), timeout=300):
    cmd = ["docker", "run", "--rm", "--network", "none"]
    for v in volumes:
        cmd += ["-v", v]
    return run(cmd + [IMAGE] + list(args), timeout=timeout)


@pytest.fixture(scope="session")
def data(image, tmp_path_factory):
    """A Timescales trace with some flipped values (so verdicts change), its property and the
    verdicts of `rvc check --all` inside the image."""
    d = tmp_path_factory.mktemp("containers-data")
    os.chmod(d, 0o755)
    gen = in_image("timescales", FAMILY, "--ubound", str(BOUND), "--duration", str(STEPS), "--seed", "1")
    assert gen.returncode == 0, gen.stderr
    lines = gen.stdout.splitlines()
    assert len(lines) == STEPS
    for i in range(137, len(lines), 997):
        e = json.loads(lines[i])
        e["p"] = not e["p"]
        lines[i] = json.dumps(e, separators=(",", ":"))
    (d / "trace.jsonl").write_text("\n".join(lines) + "\n")
    spec = in_image("timescales", FAMILY, "--ubound", str(BOUND), "--formula").stdout.strip()
    assert spec
    (d / "props.yaml").write_text("properties:\n  - name: p1\n    spec: %s\n" % json.dumps(spec))
    for f in ("trace.jsonl", "props.yaml"):
        os.chmod(d / f, 0o644)
    chk = in_image("check", "--properties", "/data/props.yaml", "--all", "/data/trace.jsonl",
                   volumes=["%s:/data:ro" % d])
    assert chk.returncode in (0, 1), chk.stderr
    assert len(chk.stdout.splitlines()) == STEPS
    return {"dir": d, "trace": str(d / "trace.jsonl"), "props": str(d / "props.yaml"),
            "expected": chk.stdout, "check_exit": chk.returncode}


@pytest.fixture(scope="session")
def support(docker):
    return rc.mode_support()


def test_image_is_small_non_root_with_healthcheck(image, tmp_path):
    cfg = json.loads(run(["docker", "image", "inspect", IMAGE]).stdout)[0]["Config"]
    assert cfg["Entrypoint"] == ["rvc"]
    assert cfg["User"] == "rvc"
    # exec form: the health check needs no shell (the image has none)
    assert cfg["Healthcheck"]["Test"] == ["CMD", "rvc", "--version"]
    size_mb = image["size_bytes"] / 1e6
    print("\nruntime image %s: %.1f MB (target <= 50 MB); %s: %.1f MB" % (
        IMAGE, size_mb, image["debug_image"], image["debug_size_bytes"] / 1e6))
    assert image["size_bytes"] <= 50e6, "runtime image is %.1f MB (target <= 50 MB)" % size_mb
    # FROM scratch: nothing but rvc and its libraries; the -debug image adds a shell
    no_sh = run(["docker", "run", "--rm", "--network", "none", "--entrypoint", "/bin/sh", IMAGE, "-c", "true"])
    assert no_sh.returncode != 0
    dbg = run(["docker", "run", "--rm", "--network", "none", "--entrypoint", "/bin/sh", image["debug_image"],
               "-c", "rvc --version"])
    assert dbg.returncode == 0 and dbg.stdout.startswith("rvc "), dbg.stderr
    # the user the container runs as: the owner of a file rvc writes (uid 10001 from the image's
    # /etc/passwd), and its home /data is the working directory
    out = tmp_path / "out"
    out.mkdir()
    os.chmod(out, 0o777)
    w = in_image("timescales", FAMILY, "--ubound", "10", "--duration", "5", "-o", "/out/t.jsonl",
                 volumes=["%s:/out" % out])
    assert w.returncode == 0, w.stderr
    assert os.stat(out / "t.jsonl").st_uid == 10001
    assert cfg["WorkingDir"] == "/data"
    helptext = in_image("--help").stdout
    for sub in ("check", "monitor", "replay", "router", "bridge", "timescales"):
        assert "\n  %s " % sub in helptext, sub
    assert in_image("--version").stdout.startswith("rvc ")
    # the libraries rvc loads only when a feature needs them are in the image too: a DDS endpoint
    # (CycloneDDS: the monitor waits for a message, ends by its idle timeout, exit 6) and a
    # PostgreSQL store (libpq's own error text for a port nothing listens on).
    dds = in_image("monitor", "--spec", "{p}", "--input", "dds:/rvc_image/lazy", "--idle-timeout", "0.3")
    assert dds.returncode == 6 and "nothing was received" in dds.stderr, dds.stderr
    pg = in_image("check", "--spec", "{p}", "/dev/null", "-o", "postgresql://127.0.0.1:1/x", "--db-wait", "0",
                  "--spool", "/tmp/s.spool")
    assert "Connection refused" in pg.stderr, pg.stderr


def deploy_and_check(data, arch, transport, mode, tmp_path, support):
    if support.get(mode):
        reason = support[mode]
        tag = "[platform] " if reason.startswith("[platform]") else ""
        pytest.skip("%s%s mode unavailable: %s" % (tag, mode, reason.removeprefix("[platform] ")))
    out = tmp_path / "out"
    d = rc.Deployment(arch=arch, transport=transport, mode=mode, trace=data["trace"], properties=data["props"],
                      image=IMAGE, monitor_flags="--all", out_dir=str(out))
    try:
        res = d.run(timeout=300)
    except rc.Unsupported as e:
        pytest.skip(str(e))
    finally:
        left = d.leftovers() if d.compose else {}
    assert left == {"containers": [], "networks": [], "links": []} or not left, "compose down left %s" % left
    info = "monitor log:\n%s\nreplay log:\n%s" % (res.get("monitor_log"), res.get("replay_log"))
    mon, rep = res["monitor"], res["replay"]
    assert mon and rep, info
    assert rep["sent"] == STEPS, info
    assert mon["received"] == STEPS and mon["checked"] == STEPS, info
    assert mon["gaps"] == 0 and mon["duplicates"] == 0 and mon["rejected"] == 0 and mon["eos"], info
    assert res["lost"] == 0
    assert res["monitor_exit"] == data["check_exit"], info
    got = (out / "verdicts.jsonl").read_text()
    assert got == data["expected"]
    print("\n%s %s %s: %.3f s first publish -> last verdict" % (arch, transport, mode, res["seconds"]))
    return res


@pytest.mark.parametrize("mode", ["bridge", "host", "shared", "macvlan", "ipvlan"])
@pytest.mark.parametrize("transport", ["zenoh", "dds"])
def test_architecture_a(data, transport, mode, tmp_path, support):
    deploy_and_check(data, "a", transport, mode, tmp_path, support)


@pytest.mark.parametrize("arch,transport,mode", [("c", "dds-zenoh", "bridge"), ("b", "zenoh", "bridge"),
                                                 ("d", "dds-zenoh", "shared")])
def test_multi_participant_architectures(data, arch, transport, mode, tmp_path, support):
    deploy_and_check(data, arch, transport if arch == "b" else "zenoh", mode, tmp_path, support)


def test_compose_files_valid_for_every_arch_and_mode(docker, tmp_path):
    compose = rc.compose_command()
    for arch in rc.ARCHS:
        for mode in rc.MODES:
            d = rc.Deployment(arch=arch, transport="dds", mode=mode, trace=str(tmp_path / "t.jsonl"),
                              spec="{p}", out_dir=str(tmp_path), project="rvcconfigcheck")
            d.compose = compose
            d.plan(subnet=rc.ipaddress.ip_network("172.28.99.0/24"))
            r = d.run_compose("config", "-q", check=False)
            assert r.returncode == 0, (arch, mode, r.stderr)
