"""The Python package tier (tests/python/run.sh): these tests import the `rvc` package
installed from the wheel into a fresh virtual environment, never the source folder."""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))  # rvc_testlib: skips fail under CI=true
sys.path.insert(0, os.path.join(HERE, "..", "differential"))  # randspec and the Reelay comparisons' helpers
from rvc_testlib import pytest_make_collect_report, pytest_runtest_makereport  # noqa: E402,F401

import pytest  # noqa: E402


@pytest.fixture(scope="session", autouse=True)
def installed_package():
    import rvc
    # The package under test is the wheel installed in this interpreter's environment.
    assert os.path.realpath(rvc.__file__).startswith(os.path.realpath(sys.prefix)), rvc.__file__
    return rvc
