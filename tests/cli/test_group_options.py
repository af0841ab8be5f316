"""rvc monitor --group/--shard-by (docs/fleet.md): what a replica refuses before it joins, each with
one clear line and exit 2, never a start that would shard nothing."""
import subprocess

import pytest


def run(rvc, *args):
    return subprocess.run([rvc, "monitor", "--spec", "{ok}", *args], capture_output=True, text=True, timeout=30)


@pytest.mark.parametrize("args, needle", [
    (["--input", "zenoh:fleet/*/s", "--group", "g"], "--group needs --shard-by"),
    (["--input", "zenoh:fleet/*/s", "--group", "g", "--shard-by", "fleet/**"], "'**' cannot name a shard"),
    (["--input", "zenoh:fleet/*/s", "--group", "g", "--shard-by", "fleet//*"], "empty chunk at column 7"),
    (["--input", "zenoh:fleet/*/s", "--group", "g", "--shard-by", "fleet/v*"], "chunk 'v*' (column 7)"),
    (["--input", "file:/dev/null", "--group", "g", "--shard-by", "fleet/*"], "is not a zenoh: input"),
    (["--input", "zenoh:fleet/*/s", "--group", "g", "--shard-by", "fleet/*", "--forward", "p1"],
     "--forward republishes one input"),
    # --shard-subscribe owned narrows each input key to one shard: '**' or one vehicle's key cannot be.
    (["--input", "zenoh:fleet/**", "--group", "g", "--shard-by", "fleet/*", "--shard-subscribe", "owned"],
     "the key of 'zenoh:fleet/**' must begin with --shard-by 'fleet/*'"),
    (["--input", "zenoh:fleet/v07/s", "--group", "g", "--shard-by", "fleet/*", "--shard-subscribe", "owned"],
     "the key of 'zenoh:fleet/v07/s' must begin"),
])
def test_refused_before_joining(rvc, args, needle):
    r = run(rvc, *args)
    assert r.returncode == 2, r.stderr
    assert needle in r.stderr, r.stderr
    assert "member" not in r.stderr  # refused before any token was declared
