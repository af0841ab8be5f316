import os
import shutil
import pytest


def rvc_binary():
    path = os.environ.get("RVC_BIN")
    if path:
        return path
    here = os.path.dirname(os.path.abspath(__file__))
    for preset in ("release", "core", "debug"):
        candidate = os.path.join(here, "..", "..", "build", preset, "rvc")
        if os.path.exists(candidate):
            return os.path.abspath(candidate)
    found = shutil.which("rvc")
    if found:
        return found
    pytest.exit("rvc binary not found: build first or set RVC_BIN", returncode=2)


@pytest.fixture(scope="session")
def rvc():
    return rvc_binary()
