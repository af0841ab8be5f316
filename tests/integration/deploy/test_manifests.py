"""Kubernetes manifests (deploy/k8s) and the Swarm stack (deploy/swarm), offline.

No Kubernetes cluster can run on the project's machines, so the manifests are validated against
the Kubernetes API's OpenAPI schemas by kubernetes-validate (PyPI), strictly (an unknown field is an
error; a mutated copy must fail, so the validator is known to look). And the manifests must stay
equivalent to the Swarm stack, which the container tier runs for real (test_swarm.py): the same
images, the same command line for router, monitor and replay, the same replica count, the same
PostgreSQL settings, the same health check, the same service names. `docker stack config` checks
the stack file's own schema where a docker client is installed.
"""
import copy
import glob
import os
import re
import shlex
import shutil
import subprocess

import pytest
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
K8S = sorted(glob.glob(os.path.join(ROOT, "deploy", "k8s", "*.yaml")))
STACK = os.path.join(ROOT, "deploy", "swarm", "stack.yml")


@pytest.fixture(scope="module")
def kv():
    return pytest.importorskip("kubernetes_validate", reason="kubernetes-validate (PyPI) not installed")


def docs(path):
    with open(path) as f:
        return [d for d in yaml.safe_load_all(f) if d]


def interpolate(text, env=None):
    """Compose's ${VAR:-default} / ${VAR} with the defaults (or env), as `docker stack deploy` does."""
    env = env or {}
    return re.sub(r"\$\{(\w+)(?::?-([^}]*))?\}", lambda m: env.get(m.group(1), m.group(2) or ""), text)


@pytest.fixture(scope="module")
def stack():
    with open(STACK) as f:
        return yaml.safe_load(interpolate(f.read()))


@pytest.fixture(scope="module")
def k8s():
    return {(d["kind"], d["metadata"]["name"]): d for d in docs(os.path.join(ROOT, "deploy", "k8s", "fleet.yaml"))}


def test_every_manifest_validates_strictly(kv):
    assert K8S, "no manifests in deploy/k8s"
    for path in K8S:
        for d in docs(path):
            kv.validate(d, "1.30.0", strict=True)  # raises ValidationError naming the field
            kv.validate(d, "1.37.0", strict=True)


def test_validator_rejects_a_broken_manifest(kv, k8s):
    bad = copy.deepcopy(k8s[("Deployment", "rvc-monitor")])
    bad["spec"]["replicaz"] = bad["spec"].pop("replicas")
    with pytest.raises(kv.ValidationError):
        kv.validate(bad, "1.37.0", strict=True)
    bad = copy.deepcopy(k8s[("StatefulSet", "rvc-router")])
    bad["spec"]["template"]["spec"]["containers"][0]["args"] = "router"  # a string, not a list
    with pytest.raises(kv.ValidationError):
        kv.validate(bad, "1.37.0", strict=True)


def container(k8s, kind, name, init=False):
    spec = k8s[(kind, name)]["spec"]["template"]["spec"]
    return spec["initContainers" if init else "containers"][0], spec


def test_manifests_equal_the_swarm_stack(stack, k8s):
    svc = stack["services"]
    pairs = {"router": ("StatefulSet", "rvc-router"), "monitor": ("Deployment", "rvc-monitor"),
             "replay": ("Job", "rvc-replay"), "postgres": ("StatefulSet", "rvc-postgres")}
    for name, (kind, k8s_name) in pairs.items():
        c, _ = container(k8s, kind, k8s_name)
        assert c["image"] == svc[name]["image"], name
        if name != "postgres":
            # the same rvc command line (the Swarm stack's monitor flags variable empty)
            assert c["args"] == shlex.split(svc[name]["command"]), name
            if name != "replay":  # a one-shot Job: no liveness probe
                assert c["livenessProbe"]["exec"]["command"] == svc[name]["healthcheck"]["test"][1:], name
    assert svc["monitor"]["deploy"]["replicas"] in (2, "2")
    assert k8s[("Deployment", "rvc-monitor")]["spec"]["replicas"] == 2
    assert k8s[("HorizontalPodAutoscaler", "rvc-monitor")]["spec"]["minReplicas"] == 2
    # the names the command lines use: Swarm service names = Kubernetes Service names
    for name, port in (("router", 7447), ("postgres", 5432)):
        assert ("Service", name) in k8s and k8s[("Service", name)]["spec"]["ports"][0]["port"] == port
        assert name in svc
    pg, _ = container(k8s, "StatefulSet", "rvc-postgres")
    env = {e["name"]: e.get("value") for e in pg["env"]}
    for k, v in svc["postgres"]["environment"].items():
        assert env[k] == v, k
    # the properties: a ConfigMap mounted where the stack's config is
    mon, spec = container(k8s, "Deployment", "rvc-monitor")
    assert [c["target"] for c in svc["monitor"]["configs"]] == ["/etc/rvc/props.yaml"]
    mounts = {m["name"]: m["mountPath"] for m in mon["volumeMounts"]}
    vols = {v["name"]: v for v in spec["volumes"]}
    assert mounts["properties"] + "/props.yaml" == "/etc/rvc/props.yaml"
    assert vols["properties"]["configMap"]["name"] == "rvc-properties"
    assert "props.yaml" in k8s[("ConfigMap", "rvc-properties")]["data"]
    # the replay's trace at the same path; the same non-root user as the image
    rep, rspec = container(k8s, "Job", "rvc-replay")
    assert svc["replay"]["configs"][0]["target"] == "/etc/rvc/trace.jsonl"
    gen, _ = container(k8s, "Job", "rvc-replay", init=True)
    assert gen["args"][-1] == "/etc/rvc/trace.jsonl"
    for kind, name in (("Deployment", "rvc-monitor"), ("StatefulSet", "rvc-router"), ("Job", "rvc-replay")):
        assert k8s[(kind, name)]["spec"]["template"]["spec"]["securityContext"]["runAsUser"] == 10001
    # the internal network: no port published in the stack, a NetworkPolicy in the manifests
    assert all("ports" not in s for s in svc.values())
    assert stack["networks"]["rvc"]["internal"] is True
    assert ("NetworkPolicy", "rvc-internal") in k8s


def test_stack_file_passes_docker_stack_config(tmp_path):
    docker = shutil.which("docker")
    if not docker:
        return  # the stack's schema is then checked by the container tier's deploy (test_swarm.py)
    r = subprocess.run([docker, "stack", "config", "-c", STACK], capture_output=True, text=True, timeout=60,
                       cwd=tmp_path)
    if "unknown command" in r.stderr or "is not a docker command" in r.stderr:
        return  # a client older than `stack config` (docker 23)
    assert r.returncode == 0, r.stderr
    out = yaml.safe_load(r.stdout)
    assert sorted(out["services"]) == ["monitor", "postgres", "replay", "router"]
    assert "--connect" in out["services"]["monitor"]["command"]
