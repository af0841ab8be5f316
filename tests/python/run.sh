#!/usr/bin/env bash
# The Python package tier (ctest python.package, docs/python.md): builds the wheel with the
# project's script, installs it with pip into fresh virtual environments and tests it there.
#  1. a clean venv (no system packages): `pip install` of the wheel alone, then a check in it;
#  2. a venv that also sees the system's packages (the oracles scripts/install-deps.sh installs:
#     reelay, rosbags, numpy, pandas, pytest), the wheel installed into it, pytest tests/python.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
PY=${PYTHON:-python3}
wheel=${RVC_WHEEL:-$(bash "$root/scripts/build-wheel.sh" | tail -1)}
case "$wheel" in /*) ;; *) wheel="$root/$wheel" ;; esac
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

"$PY" -m venv "$tmp/clean"
"$tmp/clean/bin/python" -m pip install -q --no-index "$wheel"
(cd "$tmp" && "$tmp/clean/bin/python" - <<'PYEOF'
import sys, rvc
assert rvc.__file__.startswith(sys.prefix), rvc.__file__
m = rvc.discrete_timed_monitor(pattern="historically[0:2]({p})")
out = [m.update({"p": v}) for v in (True, True, False, False, True, True, True)]
# hand-computed: false from step 2 (p fails there) until step 6 (steps 4..6 all hold p)
assert out == [{"time": 0, "value": True}, {}, {"time": 2, "value": False}, {}, {}, {}, {"time": 6, "value": True}], out
print("clean venv: the wheel pip-installed alone, a hand-computed check: ok")
PYEOF
)

"$PY" -m venv --system-site-packages "$tmp/oracles"
"$tmp/oracles/bin/python" -m pip install -q --no-index --no-deps "$wheel"
cd "$tmp"
exec "$tmp/oracles/bin/python" -m pytest -q -p no:cacheprovider "$root/tests/python" "$@"
