"""The Swarm stack (deploy/swarm/stack.yml) on a one-node swarm: a Zenoh router, two monitor
replicas writing to PostgreSQL (deploy/docker/postgres), a replay of a Timescales trace.

Oracle: `rvc check` of the same trace and properties inside the same image, stored in SQLite: each
replica's run in PostgreSQL must hold exactly its verdict changes and have received and checked
every message. Then `docker service scale` to 3 replicas: the third one starts its run. At the end
the stack, its volume and (when this test made it) the swarm and its docker_gwbridge network are
gone: the host is left as it was found. The swarm listens on 127.0.0.1 only, its address pool is
172.29.0.0/16, the stack's network is an internal overlay and no port is published.
"""
import json
import os
import secrets
import sqlite3
import subprocess
import time

import pytest

from test_containers import IMAGE, ROOT, docker, image, in_image, run  # noqa: F401 (fixtures)

STACK_FILE = os.path.join(ROOT, "deploy", "swarm", "stack.yml")
PG_IMAGE = os.environ.get("RVC_POSTGRES_IMAGE", "rvc-postgres:15")
STEPS = 2000


SWARM_LABEL = "rvc.test.swarm"  # on the node of a swarm this test made
POOL = "172.29.0.0/16"


def swarm_state():
    return run(["docker", "info", "--format", "{{.Swarm.LocalNodeState}}"]).stdout.strip()


def left_by_us():
    """A swarm this test made in a run that was killed before its teardown (CI stopped, the session
    ended): its node carries our label, or -- made before the label existed -- it is one node on
    127.0.0.1 with our address pool. After dockerd restarts, such a swarm keeps its state but its
    overlay networks cannot be allocated again ("could not find local network state"): tasks stay
    in state New forever. It is ours to remove; any other swarm is left as it is."""
    label = run(["docker", "node", "inspect", "self", "--format",
                 '{{index .Spec.Labels "%s"}}' % SWARM_LABEL]).stdout.strip()
    info = run(["docker", "info", "--format",
                "{{.Swarm.NodeAddr}} {{.Swarm.Nodes}} {{json .Swarm.Cluster.DefaultAddrPool}}"]).stdout.split()
    return label == "1" or info == ["127.0.0.1", "1", '["%s"]' % POOL]


def init_swarm():
    r = run(["docker", "swarm", "init", "--advertise-addr", "127.0.0.1", "--listen-addr", "127.0.0.1:2377",
             "--default-addr-pool", POOL, "--default-addr-pool-mask-length", "24"], timeout=60)
    if r.returncode != 0:
        pytest.fail("docker swarm init failed: " + r.stderr)
    run(["docker", "node", "update", "--label-add", SWARM_LABEL + "=1", "self"], timeout=30)


def networks():
    # This host's own networks (a swarm's overlays go with the swarm, some moments after it).
    return set(run(["docker", "network", "ls", "--filter", "scope=local", "--format", "{{.Name}}"]).stdout.split())


@pytest.fixture
def swarm(docker):  # noqa: F811
    """A one-node swarm made here (and removed at the end), or this host's own (left as it is)."""
    if swarm_state() == "active" and left_by_us():
        run(["docker", "swarm", "leave", "--force"], timeout=60)
        run(["docker", "network", "rm", "docker_gwbridge"])  # made with that swarm
        assert swarm_state() == "inactive"
    before = networks()
    ours = swarm_state() == "inactive"
    if ours:
        init_swarm()
    assert swarm_state() == "active"
    yield
    if ours:
        run(["docker", "swarm", "leave", "--force"], timeout=60)
        if "docker_gwbridge" not in before:
            run(["docker", "network", "rm", "docker_gwbridge"])
        assert swarm_state() == "inactive"
        assert networks() == before, "networks left behind: %s" % (networks() - before)


def psql(container, sql):
    r = run(["docker", "exec", container, "psql", "-U", "postgres", "-d", "rvc", "-Atc", sql], timeout=30)
    return r.stdout if r.returncode == 0 else None


def task_container(stack, service):
    ids = run(["docker", "ps", "-q", "--filter", "label=com.docker.swarm.service.name=%s_%s" % (stack, service)])
    return (ids.stdout.split() or [None])[0]


def wait_for(what, fn, timeout, info=lambda: ""):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        got = fn()
        if got:
            return got
        time.sleep(1)
    pytest.fail("timed out waiting for %s\n%s" % (what, info()))


def test_swarm_stack_router_monitors_postgres_scale(image, swarm, tmp_path):  # noqa: F811
    b = run(["docker", "build", "-q", "-t", PG_IMAGE, os.path.join(ROOT, "deploy", "docker", "postgres")],
            timeout=900)
    assert b.returncode == 0, b.stderr[-3000:]
    # Trace with some flipped values (verdicts change), its property, the oracle's verdict changes.
    d = tmp_path / "stack"
    d.mkdir()
    os.chmod(d, 0o755)
    gen = in_image("timescales", "AlwaysBQR", "--ubound", "10", "--duration", str(STEPS), "--seed", "3")
    lines = gen.stdout.splitlines()
    assert gen.returncode == 0 and len(lines) == STEPS
    for i in range(71, STEPS, 409):
        e = json.loads(lines[i])
        e["p"] = not e["p"]
        lines[i] = json.dumps(e, separators=(",", ":"))
    (d / "trace.jsonl").write_text("\n".join(lines) + "\n")
    spec = in_image("timescales", "AlwaysBQR", "--ubound", "10", "--formula").stdout.strip()
    (d / "props.yaml").write_text("properties:\n  - name: p1\n    spec: %s\n" % json.dumps(spec))
    out = tmp_path / "oracle"
    out.mkdir()
    os.chmod(out, 0o777)
    for f in ("trace.jsonl", "props.yaml"):
        os.chmod(d / f, 0o644)
    chk = in_image("check", "--properties", "/data/props.yaml", "/data/trace.jsonl", "-o", "sqlite:/out/o.db",
                   volumes=["%s:/data:ro" % d, "%s:/out" % out])
    assert chk.returncode in (0, 1), chk.stderr
    con = sqlite3.connect(out / "o.db")
    expected = [(p, float(t), int(v)) for p, t, v in
                con.execute("SELECT property, time, value FROM verdicts ORDER BY id")]
    con.close()
    assert (expected[0][2], expected[-1][2]) == (1, 0)  # a flip violates the property: the verdict changes
    password = secrets.token_hex(12)
    (d / "pw").write_text(password + "\n")
    (d / "pgpass").write_text("*:*:*:rvc:%s\n" % password)

    stack = "rvcsw%d" % (os.getpid() % 100000)
    env = dict(os.environ, RVC_IMAGE=IMAGE, RVC_POSTGRES_IMAGE=PG_IMAGE, RVC_PROPERTIES=str(d / "props.yaml"),
               RVC_TRACE=str(d / "trace.jsonl"), RVC_PG_PASSWORD_FILE=str(d / "pw"),
               RVC_PGPASS_FILE=str(d / "pgpass"), RVC_MONITORS="2")
    def logs():
        # The scheduler's view first (a task stuck in New or Pending says why there), then each
        # service's last lines.
        out = [run(["docker", "stack", "ps", "--no-trunc", "--format",
                    "{{.Name}} {{.CurrentState}} {{.Error}}", stack]).stdout]
        for s in ("monitor", "replay", "router", "postgres"):
            r = run(["docker", "service", "logs", "--tail", "20", "%s_%s" % (stack, s)])
            out.append(r.stdout + r.stderr)
        return "\n".join(out)
    try:
        r = run(["docker", "stack", "deploy", "--resolve-image", "never", "-c", STACK_FILE, stack], env=env,
                timeout=120)
        assert r.returncode == 0, r.stderr
        pg = wait_for("PostgreSQL", lambda: task_container(stack, "postgres"), 120, logs)

        def two_runs_done():
            rows = psql(pg, "SELECT c.run, c.counters FROM counters c WHERE c.id IN "
                            "(SELECT max(id) FROM counters GROUP BY run)")
            if not rows:
                return None
            done = {}
            for ln in rows.splitlines():
                run_id, counters = ln.split("|", 1)
                c = json.loads(counters)
                if c.get("eos") and c.get("checked") == STEPS:
                    done[run_id] = c
            return done if len(done) >= 2 else None
        done = wait_for("both replicas to check the whole trace", two_runs_done, 180, logs)
        assert len(done) == 2, done
        for run_id, c in done.items():
            assert c["received"] == STEPS and c["rejected"] == 0 and c["gaps"] == 0 and c["duplicates"] == 0, c
            rows = psql(pg, "SELECT property, time, value FROM verdicts WHERE run = '%s' ORDER BY id" % run_id)
            got = [(p, float(t), int(v)) for p, t, v in (ln.split("|") for ln in rows.splitlines())]
            assert got == expected, run_id
        state = run(["docker", "service", "ps", "--format", "{{.CurrentState}}", "%s_replay" % stack]).stdout
        assert state.splitlines()[0].startswith("Complete"), state

        # Scale: a third replica joins (its run appears in the store) and the service converges.
        s = run(["docker", "service", "scale", "--detach=false", "%s_monitor=3" % stack], timeout=180)
        assert s.returncode == 0, s.stderr
        replicas = run(["docker", "service", "ls", "--filter", "name=%s_monitor" % stack,
                        "--format", "{{.Replicas}}"]).stdout.strip()
        assert replicas == "3/3", replicas
        wait_for("the third replica's run", lambda: (psql(pg, "SELECT count(*) FROM runs") or "0").strip() == "3",
                 60, logs)
        print("\nswarm stack: 2 replicas checked %d messages each, %d verdict changes each; scaled to %s"
              % (STEPS, len(expected), replicas))
    finally:
        run(["docker", "stack", "rm", stack], timeout=120)
        end = time.monotonic() + 90
        while time.monotonic() < end and (
                run(["docker", "ps", "-aq", "--filter", "label=com.docker.stack.namespace=" + stack]).stdout.strip()
                or run(["docker", "network", "ls", "-q", "--filter", "name=%s_rvc" % stack]).stdout.strip()):
            time.sleep(1)
        run(["docker", "volume", "rm", "%s_pgdata" % stack])
    left = {"containers": run(["docker", "ps", "-aq", "--filter", "label=com.docker.stack.namespace=" + stack]).stdout,
            "networks": run(["docker", "network", "ls", "-q", "--filter", "name=%s_" % stack]).stdout,
            "volumes": run(["docker", "volume", "ls", "-q", "--filter", "name=%s_" % stack]).stdout,
            "configs": run(["docker", "config", "ls", "-q", "--filter", "name=%s_" % stack]).stdout}
    assert not any(v.strip() for v in left.values()), left
