import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../.."))
# fixtures (rvc) and hooks (skips fail under CI=true) shared by every pytest tier
from rvc_testlib import (BY_DESIGN, PLATFORM, pytest_make_collect_report, pytest_runtest_makereport,  # noqa: E402,F401
                         rvc, rvc_binary, transports_built)
