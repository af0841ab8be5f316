"""Skips are visible: under CI=true a skipped test (missing oracle) fails; "[platform]" and
"[by design]" skips stay skips (tests/rvc_testlib.py, shared by every pytest tier)."""
import os
import subprocess
import sys

TESTS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

CASES = '''
import pytest
def test_missing_oracle():
    pytest.importorskip("rvc_no_such_oracle_module")
def test_platform():
    pytest.skip("[platform] this kernel has no ipvlan")
def test_by_design():
    pytest.skip("[by design] covered by another test")
@pytest.mark.skipif(True, reason="needs docker")
def test_skipif():
    pass
def test_passes():
    pass
'''


def run_cases(tmp_path, ci):
    (tmp_path / "conftest.py").write_text(
        "import sys\nsys.path.insert(0, %r)\n"
        "from rvc_testlib import pytest_make_collect_report, pytest_runtest_makereport\n" % TESTS)
    (tmp_path / "test_cases.py").write_text(CASES)
    env = dict(os.environ)
    env.pop("CI", None)
    if ci:
        env["CI"] = "true"
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-rA", "-p", "no:cacheprovider", str(tmp_path)],
                       capture_output=True, text=True, env=env, cwd=tmp_path)
    return r.returncode, r.stdout


def test_skips_fail_under_ci(tmp_path):
    rc, out = run_cases(tmp_path, ci=True)
    assert rc == 1, out
    assert "FAILED test_cases.py::test_missing_oracle" in out
    assert "ERROR test_cases.py::test_skipif" in out  # a skipif is reported in the setup phase
    assert "[platform] this kernel has no ipvlan" in out and "2 skipped" in out
    assert "[by design] covered by another test" in out
    assert "PASSED test_cases.py::test_passes" in out


def test_skips_stay_skips_outside_ci(tmp_path):
    rc, out = run_cases(tmp_path, ci=False)
    assert rc == 0, out
    assert "1 passed, 4 skipped" in out
