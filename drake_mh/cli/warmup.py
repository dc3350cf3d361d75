"""``drake-mh warmup``: compile every kernel once, in parallel processes (:mod:`drake_mh.study.warmup`)."""

from __future__ import annotations

import argparse
import sys
import time


def register(subparsers, common: argparse.ArgumentParser) -> None:
    """Adds ``warmup``."""
    p = subparsers.add_parser(
        "warmup",
        parents=[common],
        help="compile every kernel once, in parallel processes (minutes from an empty cache; seconds after)",
        description="Compile the package's numba kernels ahead of their first use, a family of kernels per "
        "process, and keep them in numba's disk cache: later processes load them in about a second. From an "
        "empty cache this takes minutes (docs/first_use.md); with the kernels cached, seconds.",
    )
    p.add_argument("groups", nargs="*", metavar="GROUP", help="kernel families to compile (default: all; see --list)")
    p.add_argument("--jobs", "-j", type=int, default=None, metavar="N", help="parallel processes (default: CPU count)")
    p.add_argument("--list", action="store_true", help="list the kernel families and exit")
    p.set_defaults(func=cmd_warmup)


def cmd_warmup(args: argparse.Namespace) -> int:
    """``drake-mh warmup [GROUP ...] [--jobs N] [--list]``: exit 0 when every family compiled."""
    import os

    from drake_mh.study.warmup import GROUPS, check_groups, warmup

    if args.list:
        for name, (what, _) in GROUPS.items():
            print(f"{name:16s} {what}")
        return 0
    names, workers = check_groups(args.groups or None, args.jobs)
    print(f"compiling {len(names)} kernel families in {workers} processes (cached in "
          f"{os.environ.get('NUMBA_CACHE_DIR', 'numba’s default folder')}; cached kernels only load)", flush=True)
    quiet = getattr(args, "quiet", False)
    start, done, failed = time.perf_counter(), [], []

    def progress(result: dict) -> None:
        done.append(result)
        if result["error"]:
            failed.append(result)
        if not quiet or result["error"]:
            status = f"failed: {result['error']}" if result["error"] else "ok"
            print(f"[{len(done)}/{len(names)}] {result['group']}: {result['seconds']:.0f} s "
                  f"({result['cpu']:.0f} s CPU) {status}", flush=True)

    warmup(names, processes=workers, progress=progress)
    print(f"{len(done) - len(failed)}/{len(names)} kernel families ready in {time.perf_counter() - start:.0f} s",
          flush=True)
    if failed:
        print(f"drake-mh warmup: {len(failed)} families failed to compile ({', '.join(r['group'] for r in failed)}); "
              f"they compile on first use instead", file=sys.stderr)
        return 1
    return 0
