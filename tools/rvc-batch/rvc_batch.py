#!/usr/bin/env python3
"""rvc-batch: `rvc check` over many ROS 2 bags, fanned out on a Dask cluster.

    tools/rvc-batch/rvc_batch.py BAGS... --store sqlite:results.db [--workers N | --scheduler ADDR]
                                 [--rvc PATH] [--timeout S] [--out-dir DIR] [--summary FILE]
                                 -- CHECK-ARGS...

BAGS: bag files (.mcap, .db3, also .zstd-compressed), bag folders (with metadata.yaml), folders to
search for them (every bag below, a bag folder taken whole), or @LIST (a file naming one per line).
CHECK-ARGS (after --) go to every `rvc check` as they are: --properties/--spec, --topic, ...

Each bag is one `rvc check BAG CHECK-ARGS -o STORE --stats`: one run in the results store
(docs/results.md; `runs.inputs` names the bag), exactly what `rvc check` would store for it alone.
By default a local Dask cluster of --workers workers (default: the machine's cores), each running
one bag at a time; --scheduler tcp://HOST:8786 uses an existing cluster instead (its workers need
the rvc binary at --rvc, the bags at the same paths and the store: PostgreSQL, or SQLite on a
shared file system).

A bag that cannot be checked (rvc exits 2, 3, 5, 6, crashes, or runs past --timeout) does not stop
the others: it is reported on stderr with rvc's last message and counted. The end prints one JSON
line on stdout: {"bags":200,"held":..,"violated":..,"failed":..,"exit_codes":{..},"seconds":..,
"bags_per_s":..,"workers":..}. --summary FILE writes one JSON line per bag.

Exit status: 0 every bag checked and held; 1 a property was violated in some bag, none failed;
2 usage error (no rvc, a path that does not exist, an unreachable scheduler); 5 some bag failed
(its results are not in the store); 6 no bag found.
"""
import argparse
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import time

BAG_SUFFIXES = (".mcap", ".db3", ".mcap.zstd", ".db3.zstd")
HELD, VIOLATED = 0, 1


def is_bag_file(path):
    return os.path.isfile(path) and path.endswith(BAG_SUFFIXES)


def is_bag_folder(path):
    return os.path.isdir(path) and os.path.isfile(os.path.join(path, "metadata.yaml"))


def find_bags(args):
    """The bags named by args, in a stable order (sorted by path within each argument), each once.
    Raises FileNotFoundError for an argument that does not exist."""
    found, seen = [], set()

    def add(path):
        key = os.path.realpath(path)
        if key not in seen:
            seen.add(key)
            found.append(os.path.abspath(path))

    def walk(top):
        for root, dirs, files in os.walk(top):
            dirs.sort()
            if is_bag_folder(root) and root != top:
                add(root)
                dirs[:] = []  # a bag folder's storage files are the bag, not bags of their own
                continue
            for f in sorted(files):
                if f.endswith(BAG_SUFFIXES):
                    add(os.path.join(root, f))

    for arg in args:
        if arg.startswith("@"):
            with open(arg[1:]) as f:
                names = [ln.strip() for ln in f if ln.strip() and not ln.lstrip().startswith("#")]
            base = os.path.dirname(os.path.abspath(arg[1:]))
            for n in names:
                p = n if os.path.isabs(n) else os.path.join(base, n)
                if not os.path.exists(p):
                    raise FileNotFoundError("%s (listed in %s)" % (n, arg[1:]))
                add(p)  # named explicitly: checked as it is, rvc says if it is no bag
        elif not os.path.exists(arg):
            raise FileNotFoundError(arg)
        elif is_bag_folder(arg) or os.path.isfile(arg):
            add(arg)
        else:
            walk(arg)
    return found


def masked(uri):
    """A store URI without its password (as rvc itself prints it)."""
    return re.sub(r"(://[^/:@]*:)[^@/]*@", r"\1***@", uri)


OUTPUT_MARK = "user.rvc.output"  # what rvc itself marks its files with (src/transport/output_file.cpp)


def not_ours(path):
    """Why rvc-batch must not write `path`, or None: an existing, non-empty regular file (or a link to
    one) that no rvc tool created is somebody else's, and is never truncated."""
    try:
        if not os.path.isfile(path) or os.path.getsize(path) == 0:
            return None
        os.getxattr(path, OUTPUT_MARK)
        return None
    except OSError:
        return "%s: it exists and rvc did not write it: refusing to write over it" % path


def open_output(path):
    f = open(path, "w")
    try:
        os.setxattr(f.fileno(), OUTPUT_MARK, b"1")
    except OSError:
        pass  # a file system without user xattrs: the file is still written
    return f


def verdicts_path(out_dir, bag):
    """DIR/<bag path, readable>-<hash>.jsonl: one file per bag whatever the names. The readable part alone
    is not one-to-one (`a b.mcap`, `a_b.mcap` and `a/b.mcap` all read `a_b.mcap`), so it is followed by a
    short hash of the bag's exact path; long paths keep their end (the bag's own name) readable."""
    readable = re.sub(r"[^A-Za-z0-9._-]", "_", bag.strip("/"))
    if len(readable) > 180:  # a file name has at most 255 bytes
        readable = readable[-180:]
    digest = hashlib.sha256(os.fsencode(bag)).hexdigest()[:12]
    return os.path.join(out_dir, "%s-%s.jsonl" % (readable, digest))


def check_bag(rvc, bag, check_args, store, out_dir=None, timeout=None):
    """Runs `rvc check` on one bag (on a Dask worker); never raises: a failure is a result."""
    cmd = [rvc, "check", bag] + list(check_args) + ["--stats"] + (["-o", store] if store else [])
    start = time.monotonic()
    out = subprocess.DEVNULL
    rec = {"bag": bag, "exit": None, "seconds": 0.0, "stats": None, "run": None, "error": None}
    try:
        if out_dir:
            out = open_output(verdicts_path(out_dir, bag))
            rec["verdicts"] = out.name
        p = subprocess.Popen(cmd, stdout=out, stderr=subprocess.PIPE, text=True)
        try:
            _, err = p.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            # SIGTERM first: rvc then ends its run in the store (reason "signal", status 6) with
            # every row of what it read; SIGKILL only if it does not end within 10 s.
            p.terminate()
            try:
                _, err = p.communicate(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                _, err = p.communicate()
            rec["exit"] = p.returncode
            rec["error"] = "still running after %g s (--timeout): stopped" % timeout
            return rec
        rec["exit"] = p.returncode
        lines = err.strip().splitlines()
        for ln in reversed(lines):
            if ln.startswith("{"):
                try:
                    rec["stats"] = json.loads(ln)
                    break
                except ValueError:
                    pass
        m = re.search(r", run (\S+?):", err)
        rec["run"] = m.group(1) if m else None
        if p.returncode not in (HELD, VIOLATED):
            msgs = [ln for ln in lines if not ln.startswith("{")]
            rec["error"] = msgs[-1] if msgs else "exit status %d" % p.returncode
    except OSError as e:
        rec["error"] = "cannot run %s: %s" % (rvc, e)
    finally:
        if out is not subprocess.DEVNULL:
            out.close()
        rec["seconds"] = time.monotonic() - start
    return rec


def failed(rec):
    """Not checked to its end: rvc's status says so, or it was stopped (--timeout: then its status,
    1 after a violation already seen, does not tell)."""
    return rec["error"] is not None or rec["exit"] not in (HELD, VIOLATED)


def make_client(args):
    from dask.distributed import Client, LocalCluster
    if args.scheduler:
        return Client(args.scheduler, timeout=args.connect_timeout), None
    # Threads, not processes: a task only waits on its rvc subprocess (the GIL is released), so one
    # process holds every worker, with no extra interpreters to start and no sockets (inproc://).
    cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=False,
                           dashboard_address=None)
    return Client(cluster), cluster


def progress_bar(total, enabled):
    try:
        from tqdm import tqdm
    except ImportError:  # the bar is a convenience: without tqdm, a line per 10 % on stderr
        tqdm = None
    if tqdm is not None:
        return tqdm(total=total, unit="bag", file=sys.stderr, disable=None if enabled is None else not enabled)

    class Lines:
        def __init__(self):
            self.n, self.step = 0, max(1, total // 10)

        def update(self, k):
            self.n += k
            if enabled is not False and (self.n % self.step == 0 or self.n == total):
                print("rvc-batch: %d/%d bags" % (self.n, total), file=sys.stderr)

        def set_postfix_str(self, s):
            pass

        def close(self):
            pass
    return Lines()


def parse(argv):
    if "--" in argv:
        i = argv.index("--")
        argv, check_args = argv[:i], argv[i + 1:]
    else:
        check_args = []
    ap = argparse.ArgumentParser(prog="rvc-batch", description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="rvc check's own options go after --, "
                                        "e.g. -- --properties p.yaml --topic /speed")
    ap.add_argument("bags", nargs="+", help="bag files, bag folders, folders to search, @LIST files")
    ap.add_argument("--store", required=True,
                    help="results store for every bag's run: sqlite:PATH or postgresql://... (docs/results.md)")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                    help="workers of the local cluster, one bag each at a time (default: cores)")
    ap.add_argument("--scheduler", help="address of an existing Dask scheduler (tcp://HOST:8786) instead")
    ap.add_argument("--connect-timeout", type=float, default=10.0, help="seconds to reach --scheduler")
    ap.add_argument("--rvc", default=os.environ.get("RVC_BIN") or shutil.which("rvc") or "rvc",
                    help="the rvc binary (default $RVC_BIN, else rvc on PATH)")
    ap.add_argument("--timeout", type=float, default=None, help="seconds one bag may take (default: no limit)")
    ap.add_argument("--out-dir", help="also write each bag's verdict lines (rvc check's stdout) to DIR/<bag>.jsonl")
    ap.add_argument("--summary", help="write one JSON line per bag (bag, exit, run, seconds, stats, error)")
    bar = ap.add_mutually_exclusive_group()
    bar.add_argument("--progress", dest="progress", action="store_true", default=None, help="progress bar always")
    bar.add_argument("--no-progress", dest="progress", action="store_false", help="no progress bar")
    args = ap.parse_args(argv)
    if args.workers < 1:
        ap.error("--workers must be at least 1")
    if not (args.store.startswith(("sqlite:", "postgresql:", "postgres:"))):
        ap.error("--store must be sqlite:PATH or a postgresql:// URI, not %r" % args.store)
    if "-o" in check_args or "--output" in check_args:
        ap.error("give the store with --store, not -o after -- (each bag's verdicts: --out-dir)")
    args.check_args = check_args
    return args


def main(argv=None):
    args = parse(sys.argv[1:] if argv is None else argv)
    say = lambda msg: print("rvc-batch: " + msg, file=sys.stderr)  # noqa: E731
    if not args.scheduler and not (os.path.isfile(args.rvc) or shutil.which(args.rvc)):
        say("no rvc binary at %s (--rvc or RVC_BIN)" % args.rvc)
        return 2
    try:
        bags = find_bags(args.bags)
    except (FileNotFoundError, OSError) as e:
        say("no such bag or folder: %s" % e)
        return 2
    # Before any bag runs: a file rvc-batch would write over that it did not create is refused.
    planned = ([args.summary] if args.summary else []) + \
        ([verdicts_path(args.out_dir, b) for b in bags] if args.out_dir else [])
    if len(set(planned)) != len(planned):  # (a hash collision: never seen, but never silent)
        say("two bags would share one --out-dir file: name them differently")
        return 2
    for path in planned:
        problem = not_ours(path)
        if problem:
            say(problem)
            return 2
    if not bags:
        say("no bag found in %s (.mcap, .db3, folders with metadata.yaml)" % " ".join(args.bags))
        print(json.dumps({"bags": 0, "held": 0, "violated": 0, "failed": 0}))
        return 6
    store = args.store
    if store.startswith("sqlite:"):  # the workers may run elsewhere: an absolute path
        store = "sqlite:" + os.path.abspath(store[len("sqlite:"):])
    if args.out_dir:
        os.makedirs(args.out_dir, exist_ok=True)
        args.out_dir = os.path.abspath(args.out_dir)
    rvc = os.path.abspath(args.rvc) if os.path.isfile(args.rvc) else args.rvc

    try:
        client, cluster = make_client(args)
    except (OSError, TimeoutError) as e:
        say("cannot reach the Dask scheduler %s: %s" % (args.scheduler, e))
        return 2
    start = time.monotonic()
    records, codes = [], {}
    try:
        from dask.distributed import as_completed
        workers = len(client.scheduler_info().get("workers", {}))
        futures = {client.submit(check_bag, rvc, b, args.check_args, store, args.out_dir, args.timeout,
                                 pure=False, key="rvc-check-%d" % i): b for i, b in enumerate(bags)}
        bar = progress_bar(len(bags), args.progress)
        for fut in as_completed(futures):
            try:
                rec = fut.result()
            except Exception as e:  # the worker itself failed (died, lost): the bag is not checked
                rec = {"bag": futures[fut], "exit": None, "seconds": 0.0, "stats": None, "run": None,
                       "error": "worker failed: %s" % e}
            records.append(rec)
            key = "none" if rec["exit"] is None else str(rec["exit"])
            codes[key] = codes.get(key, 0) + 1
            bar.update(1)
            bad = sum(1 for r in records if failed(r))
            bar.set_postfix_str("failed %d" % bad if bad else "")
            if failed(rec):
                say("bag %s failed (%s): %s" % (rec["bag"], "exit %s" % rec["exit"] if rec["exit"] is not None
                                                else "no exit status", rec["error"]))
        bar.close()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    seconds = time.monotonic() - start
    records.sort(key=lambda r: bags.index(r["bag"]))
    bad = sum(1 for r in records if failed(r))
    held = sum(1 for r in records if not failed(r) and r["exit"] == HELD)
    violated = len(records) - bad - held
    if args.summary:
        with open_output(args.summary) as f:
            for r in records:
                f.write(json.dumps(r) + "\n")
    if bad:
        say("%d of %d bags failed (their runs are not complete in %s)" % (bad, len(bags), masked(store)))
    print(json.dumps({"bags": len(bags), "held": held, "violated": violated, "failed": bad,
                      "exit_codes": dict(sorted(codes.items())), "store": masked(store),
                      "workers": workers, "seconds": round(seconds, 3),
                      "bags_per_s": round(len(bags) / seconds, 2) if seconds > 0 else None}))
    return 5 if bad else (1 if violated else 0)


if __name__ == "__main__":
    sys.exit(main())
