"""The size of the bounded-future rewrite is checked before it is built (issue 36): nested
until[0:255] is refused as a spec error (exit 2) at the until's column, naming the operators it would
need and the limit, within a small address-space cap; the widest inner until under the limit still
runs and gives the hand-computed verdict. Before: two levels took ~90 s and 2.2 GB (under this cap:
std::bad_alloc, exit 5), three ended in std::bad_alloc."""
import re
import subprocess

import pytest

from rvc_testlib import memory_capped

CAP_MIB = 1024  # far above what a refusal or a 65,000-node property needs


def run(rvc, spec, trace):
    return subprocess.run([rvc, "check", "--spec", spec, "-"], input=trace, capture_output=True, text=True,
                          timeout=120, **memory_capped(CAP_MIB))


def error_column(stderr):
    return int(re.search(r"spec error at column (\d+):", stderr).group(1))


@pytest.mark.parametrize("levels", [2, 3, 6])
def test_nested_until_is_refused_before_it_is_expanded(rvc, levels):
    spec = "{r}"
    for _ in range(levels):
        spec = "({p} until[0:255] " + spec + ")"
    spec = spec[1:-1]
    r = run(rvc, spec, '{"p": true, "q": true, "r": true}\n')
    assert r.returncode == 2, r.stderr
    m = re.search(r"property too large: its rewrite into past operators would need (more than )?(\d+) operators, "
                  r"the limit is 65000", r.stderr)
    assert m and int(m.group(2)) > 65000, r.stderr
    # the innermost until whose own rewrite is past the limit: the second innermost (one alone fits)
    untils = [m.start() + 1 for m in re.finditer("until", spec)]
    assert error_column(r.stderr) == untils[levels - 2]
    assert r.stdout == ""


def test_a_rewrite_just_under_the_limit_still_runs(rvc):
    # {q} until[0:26] inside until[0:255] is just under 65,000 operators (until[0:27]: 65,786, refused)
    trace = '{"p": true, "q": false, "r": false}\n' * 3 + '{"p": true, "q": false, "r": true}\n'
    under = run(rvc, "{p} until[0:255] ({q} until[0:26] {r})", trace)
    assert under.returncode == 0, under.stderr
    # r at step 3 only: the inner until holds at step 3; the outer at every step (p holds up to it)
    assert '"value":true' in under.stdout and '"value":false' not in under.stdout
    over = run(rvc, "{p} until[0:255] ({q} until[0:27] {r})", trace)
    assert over.returncode == 2 and "would need 65786 operators" in over.stderr, over.stderr
