import os
import shutil
import pytest


def rvc_binary():
    path = os.environ.get("RVC_BIN")
    if path:
        return path
    root = os.path.dirname(os.path.abspath(__file__))
    while root != "/" and not os.path.exists(os.path.join(root, "CMakePresets.json")):
        root = os.path.dirname(root)
    for preset in ("release", "core", "debug"):
        candidate = os.path.join(root, "build", preset, "rvc")
        if os.path.exists(candidate):
            return os.path.abspath(candidate)
    found = shutil.which("rvc")
    if found:
        return found
    pytest.exit("rvc binary not found: build first or set RVC_BIN", returncode=2)


@pytest.fixture(scope="session")
def rvc():
    return rvc_binary()
