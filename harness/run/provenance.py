"""Provenance: where an output file came from (one block for results, bench and stress).

Versions of the engines and libraries, the harness code version, the git commit (and whether
the tree was dirty), the machine with its CPU model, the command and the time.
"""

from __future__ import annotations

import os
import platform
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Iterable

from harness.engines import ENGINE_NAMES, engine_distribution
from harness.store.identity import code_version

#: Packages whose versions every output file records (None when not installed).
PACKAGES = ("numpy", *(engine_distribution(name) for name in ENGINE_NAMES), "matplotlib",
            "planar-impact-harness")


def package_versions(names: Iterable[str] = PACKAGES) -> dict:
    """Installed versions (``None`` when a package is not installed)."""
    from importlib import metadata

    versions = {"python": platform.python_version()}
    for name in names:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return versions


#: Where the outputs are generated (top level of the tree): a change there is no change of
#: the source. ``make validate`` rewrites ``reports/`` (the Table 3 files) before ``run``
#: records its provenance, so counting them stamped every report on a clean clone dirty.
GENERATED_DIRS = ("reports",)


def git_commit(cwd: Path | None = None) -> dict:
    """``{"commit": sha or None, "dirty": bool or None}`` of the source tree: dirty when a
    tracked file outside :data:`GENERATED_DIRS` differs from the commit."""
    cwd = cwd or Path(__file__).resolve().parent.parent.parent
    outside_outputs = [f":(top,exclude){name}" for name in GENERATED_DIRS]
    try:
        commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=cwd, capture_output=True,
                                text=True, timeout=10).stdout.strip() or None
        status = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no",
                                 "--", ":(top)", *outside_outputs],
                                cwd=cwd, capture_output=True, text=True, timeout=10)
        dirty = bool(status.stdout.strip()) if status.returncode == 0 else None
    except (OSError, subprocess.SubprocessError):
        commit, dirty = None, None
    return {"commit": commit, "dirty": dirty}


def cpu_model() -> str | None:
    """The CPU's model name (``/proc/cpuinfo`` on Linux, else ``platform.processor()``)."""
    try:
        for line in Path("/proc/cpuinfo").read_text(encoding="utf-8").splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or None


def machine() -> dict:
    """Platform, architecture, CPU model and core count of the machine producing a file."""
    return {
        "platform": platform.platform(),
        "machine": platform.machine(),
        "cpu_model": cpu_model(),
        "cpu_count": os.cpu_count(),
    }


def provenance(kind: str, format_version: int, *, command: Iterable[str] | None = None,
               **extra: Any) -> dict:
    """The provenance block of every output file (results, bench, stress).

    ``kind`` and ``format_version`` name the file's format; the block adds the time, the
    command, package versions, the code version the cache keys on, the git commit, the
    machine (with its CPU model) and ``extra`` (e.g. ``engine_settings``).
    """
    return {
        "format": kind,
        "format_version": format_version,
        "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "command": list(command) if command is not None else list(sys.argv),
        "versions": package_versions(),
        "code_version": code_version(),
        "git": git_commit(),
        "machine": machine(),
        **extra,
    }


__all__ = ["GENERATED_DIRS", "PACKAGES", "cpu_model", "git_commit", "machine", "package_versions",
           "provenance"]
