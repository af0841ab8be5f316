#!/usr/bin/env python3
"""Fetches Reelay 25's source distribution from PyPI and builds our reelay_check harness against it.

  python3 bench/reelay_cpp/fetch.py            # fetch + build; prints the binary's path

- Source: `reelay==25.0.0` sdist (MPL-2.0), found by package name on PyPI's simple index
  (https://pypi.org/simple/reelay/); the sha256 in the link's fragment is checked. (`pip download
  --no-binary` cannot be used: the sdist's build backend runs cmake just to produce metadata.)
- Cache: bench/results/reelay-src/ (git-ignored). Reelay's code is never copied into the source tree.
- Needs Boost.ICL (Debian libboost-dev; installed with apt-get if missing) and libsimdjson-dev.
- Build: g++ -O3 -DNDEBUG -std=c++17 reelay_check.cpp -isystem <sdist>/include -isystem cudd_stub -lsimdjson
  -> bench/results/reelay_cpp/reelay_check (rebuilt when its inputs are newer; ~30 s, one core).
  Reelay's headers include CUDD's (its data monitors keep value sets as BDDs); CUDD is neither on PyPI
  nor in Debian, so cudd_stub/ declares the few names they use, each aborting if reached. The harness
  runs formulas without data references only, whose monitors never touch a BDD.

Every failure raises FetchError with a one-line reason, so the benchmark can leave its column out.
"""
import hashlib
import html.parser
import os
import shutil
import subprocess
import sys
import tarfile
import urllib.parse
import urllib.request

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
RESULTS = os.path.join(ROOT, "bench", "results")
CACHE = os.path.join(RESULTS, "reelay-src")
OUT = os.path.join(RESULTS, "reelay_cpp")
PACKAGE, VERSION = "reelay", "25.0.0"
SDIST = f"{PACKAGE}-{VERSION}.tar.gz"


class FetchError(RuntimeError):
    pass


class _Links(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.links = {}
        self._href = None

    def handle_starttag(self, tag, attrs):
        if tag == "a":
            self._href = dict(attrs).get("href")

    def handle_data(self, data):
        if self._href:
            self.links[data.strip()] = self._href

    def handle_endtag(self, tag):
        if tag == "a":
            self._href = None


def _sdist_url():
    index = f"https://pypi.org/simple/{PACKAGE}/"
    req = urllib.request.Request(index, headers={"Accept": "text/html", "User-Agent": "rvc-bench"})
    with urllib.request.urlopen(req, timeout=60) as r:
        page = r.read().decode()
    p = _Links()
    p.feed(page)
    href = p.links.get(SDIST)
    if not href:
        raise FetchError(f"{SDIST} not listed on {index}")
    url = urllib.parse.urljoin(index, href)
    frag = urllib.parse.urlparse(url).fragment
    if not frag.startswith("sha256="):
        raise FetchError(f"no sha256 fragment for {SDIST} on {index}")
    return url.split("#", 1)[0], frag.split("=", 1)[1]


def fetch(cache=CACHE):
    """Returns the sdist's include directory, downloading and unpacking it once."""
    src = os.path.join(cache, f"{PACKAGE}-{VERSION}")
    include = os.path.join(src, "include")
    if os.path.isfile(os.path.join(include, "reelay", "monitors.hpp")):
        return include
    os.makedirs(cache, exist_ok=True)
    tarball = os.path.join(cache, SDIST)
    try:
        url, sha = _sdist_url()
        if not os.path.exists(tarball) or hashlib.sha256(open(tarball, "rb").read()).hexdigest() != sha:
            req = urllib.request.Request(url, headers={"User-Agent": "rvc-bench"})
            with urllib.request.urlopen(req, timeout=120) as r:
                blob = r.read()
            got = hashlib.sha256(blob).hexdigest()
            if got != sha:
                raise FetchError(f"sha256 mismatch for {SDIST}: index says {sha}, got {got}")
            with open(tarball + ".part", "wb") as f:
                f.write(blob)
            os.replace(tarball + ".part", tarball)
    except OSError as e:  # URLError, timeouts, disk
        raise FetchError(f"download of {SDIST} from PyPI failed: {e}") from e
    with tarfile.open(tarball) as t:
        members = [m for m in t.getmembers() if m.name.startswith(f"{PACKAGE}-{VERSION}/")
                   and ".." not in m.name and (m.isfile() or m.isdir())]
        t.extractall(cache, members=members)
    if not os.path.isfile(os.path.join(include, "reelay", "monitors.hpp")):
        raise FetchError(f"{SDIST} has no include/reelay/monitors.hpp")
    return include


def _has_boost_icl():
    return any(os.path.isfile(os.path.join(d, "boost", "icl", "interval_set.hpp"))
               for d in ("/usr/include", "/usr/local/include"))


def ensure_boost():
    if _has_boost_icl():
        return
    sudo = [] if os.geteuid() == 0 else ["sudo", "-n"]
    install = sudo + ["apt-get", "install", "-y", "--no-install-recommends", "libboost-dev"]
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    print("reelay_cpp: installing libboost-dev (Boost.ICL) ...", file=sys.stderr, flush=True)
    if subprocess.run(install, env=env).returncode != 0:
        subprocess.run(sudo + ["apt-get", "update"], env=env)
        subprocess.run(install, env=env)
    if not _has_boost_icl():
        raise FetchError("Boost.ICL headers missing and `apt-get install libboost-dev` failed")


def build(out=OUT, cache=CACHE):
    """Fetches, then compiles reelay_check (if stale); returns the binary's path."""
    include = fetch(cache)
    ensure_boost()
    source = os.path.join(HERE, "reelay_check.cpp")
    binary = os.path.join(out, "reelay_check")
    inputs = [source, os.path.join(HERE, "cudd_stub", "cudd", "cudd.hpp"), os.path.abspath(__file__)]
    if os.path.exists(binary) and os.path.getmtime(binary) >= max(os.path.getmtime(p) for p in inputs):
        return binary
    os.makedirs(out, exist_ok=True)
    cxx = os.environ.get("CXX", shutil.which("g++") or "c++")
    stub = os.path.join(HERE, "cudd_stub")  # see cudd_stub/cudd/cudd.hpp: CUDD is not on PyPI or Debian
    cmd = [cxx, "-O3", "-DNDEBUG", "-std=c++17", "-o", binary + ".part", source, "-isystem", include,
           "-isystem", stub, "-lsimdjson"]
    print("reelay_cpp: " + " ".join(cmd), file=sys.stderr, flush=True)
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise FetchError("build of reelay_check failed:\n" + proc.stderr[-4000:])
    os.replace(binary + ".part", binary)
    return binary


if __name__ == "__main__":
    try:
        print(build())
    except FetchError as e:
        sys.exit(f"reelay_cpp: {e}")
