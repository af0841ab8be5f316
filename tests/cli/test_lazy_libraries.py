"""CycloneDDS and libpq are loaded when a feature first needs them, not at every start.

Linked normally, the two libraries and what they pull in (iceoryx; Kerberos, LDAP, GnuTLS, SASL)
cost every rvc run about 18 M instructions of relocations, more than `rvc check` spends on a small
file. The dynamic loader's own trace (LD_DEBUG=files) says which libraries a run loaded: these tests
read it, and never time anything.
"""
import subprocess

import pytest

from rvc_testlib import transports_built


def loaded_libraries(cmd, **kwargs) -> tuple[str, subprocess.CompletedProcess]:
    """Runs cmd with the loader's file trace; returns (trace, completed process)."""
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=60,
                          env={"LD_DEBUG": "files", "PATH": "/usr/bin:/bin"}, **kwargs)
    trace = "\n".join(line for line in proc.stderr.splitlines() if "file=" in line)
    return trace, proc


def test_check_loads_neither_dds_nor_postgres(rvc, tmp_path):
    trace_file = tmp_path / "t.jsonl"
    trace_file.write_text('{"time":0,"p":true}\n{"time":1,"p":false}\n')
    trace, proc = loaded_libraries([rvc, "check", "--spec", "{p}", str(trace_file)])
    assert proc.returncode == 1, proc.stderr[-2000:]  # p is violated at step 1: the run itself worked
    assert '"value":false' in proc.stdout
    assert "file=libsimdjson" in trace  # the trace is real: a linked library shows up in it
    assert "libddsc" not in trace
    assert "libpq" not in trace


def test_dds_endpoint_loads_cyclonedds_on_first_use(rvc):
    if "dds" not in transports_built(rvc):
        pytest.skip("this rvc has no DDS transport")
    # A monitor on a topic nobody publishes: it makes a participant and a reader, waits
    # --idle-timeout for a message, and ends incomplete (exit 6).
    trace, proc = loaded_libraries([rvc, "monitor", "--spec", "{p}", "--input", "dds:/rvc_test/lazy_load",
                                    "--idle-timeout", "0.3"])
    assert proc.returncode == 6, proc.stderr[-2000:]
    assert "file=libddsc" in trace and "dynamically loaded by" in trace
    assert "libpq" not in trace
