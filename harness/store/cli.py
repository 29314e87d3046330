"""``impact-harness cache info|prune|clear``: where the result cache is and how big
(:mod:`harness.store.cache`), and removing its entries -- only a cache's own, and only in a
directory the harness made."""

from __future__ import annotations

import sys
from pathlib import Path

from harness import bounds
from harness.store.cache import ResultCache
from harness.store.cache_directory import CACHE_MARKER, NotOurCache, default_cache_dir


def add_arguments(parser) -> None:
    parser.add_argument("action", choices=("info", "prune", "clear"),
                        help="info: where and how big; prune: remove entries of other code "
                        "versions (and older than --older-than); clear: remove every entry "
                        "its key sealed (any other file is left, and counted). "
                        "prune and clear remove only the cache's own entries, and only in a "
                        f"directory the harness made (it holds {CACHE_MARKER}); any other is "
                        "refused with exit 2")
    parser.add_argument("--cache-dir", type=Path, default=None,
                        help=f"cache directory (default: {default_cache_dir()})")
    parser.add_argument("--older-than", type=bounds.option("older-than"),
                        default=None, metavar="DAYS",
                        help="prune: also remove entries older than DAYS days")


def main(args) -> int:
    cache = ResultCache(args.cache_dir)
    try:  # before anything: a name too long was an OSError (exit 3), a file read as empty
        is_file = cache.root.exists() and not cache.root.is_dir()
    except OSError as error:
        print(f"impact-harness cache: --cache-dir {str(cache.root)[:200]}: cannot be used: "
              f"{error.strerror or error}", file=sys.stderr)
        return 2
    if is_file:
        print(f"impact-harness cache: --cache-dir {cache.root}: is not a directory; allowed: "
              "a cache's directory", file=sys.stderr)
        return 2
    if args.action == "info":
        info = cache.info()
        note = "" if info["marked"] or not cache.root.exists() else (
            f" (no {CACHE_MARKER} file: not a cache the harness made)")
        print(f"{info['root']}: {info['entries']} entries, {info['bytes'] / 1e6:.1f} MB{note}")
        return 0
    if args.older_than is not None and not args.older_than >= 0:
        print(f"impact-harness cache: --older-than {args.older_than}: must be >= 0",
              file=sys.stderr)
        return 2
    if not cache.root.exists():
        print(f"{cache.root}: no cache there: removed 0 entries")
        return 0
    try:
        done = cache.prune(args.older_than) if args.action == "prune" else cache.clear()
    except NotOurCache as error:
        print(f"impact-harness cache: {error}", file=sys.stderr)
        return 2
    left = done.get("left", 0)
    print(f"{cache.root}: removed {done['entries']} entries, {done['bytes'] / 1e6:.1f} MB"
          + (f"; left {left} files named like entries that the cache cannot tell it wrote "
             "(no seal of its key over them)" if left else ""))
    return 0


__all__ = ["add_arguments", "main"]
