"""Run the numerically sensitive tests again on other kernels: ``make test`` runs this after
the whole suite, and it can be run by hand (arguments go to pytest)::

    .venv/bin/python tests/other_kernels.py -n 2

The tests marked ``kernel_sensitive`` (pins of stored results, counts, decisions, findings:
see tests/conftest.py) run once more with OpenBLAS's Prescott kernels (SSE3, which every
x86-64 CPU runs; elsewhere the BLAS kernel is left as it is, with a note) and with every
SIMD target numpy dispatches to at run time turned off (``NPY_DISABLE_CPU_FEATURES``: numpy
then runs its baseline loops). Results through BLAS, libm or SIMD differ in the last bits
between such kernels as they do between CPUs; these tests must pass on each (issue 22).
"""

from __future__ import annotations

import os
import platform
import subprocess
import sys
from pathlib import Path

#: OpenBLAS's kernels for the oldest x86-64 CPUs it knows (SSE3): they run on every x86-64.
OLD_KERNEL = "Prescott"


def kernel_environment() -> tuple[dict[str, str], list[str]]:
    """The environment of the second run, and what it changes (for the log)."""
    try:
        from numpy._core._multiarray_umath import __cpu_dispatch__
    except ImportError:  # numpy < 2
        from numpy.core._multiarray_umath import __cpu_dispatch__

    environment = dict(os.environ)
    changes = []
    if platform.machine().lower() in ("x86_64", "amd64"):
        environment["OPENBLAS_CORETYPE"] = OLD_KERNEL
        changes.append(f"OPENBLAS_CORETYPE={OLD_KERNEL}")
    else:
        changes.append(f"BLAS kernel left as is ({platform.machine()} is not x86-64)")
    if __cpu_dispatch__:  # disabling a target the CPU lacks is allowed (and does nothing)
        environment["NPY_DISABLE_CPU_FEATURES"] = " ".join(__cpu_dispatch__)
        changes.append(f"NPY_DISABLE_CPU_FEATURES={' '.join(__cpu_dispatch__)}")
    return environment, changes


def main(arguments: list[str]) -> int:
    environment, changes = kernel_environment()
    print(f"kernel_sensitive tests again with {', '.join(changes)}", flush=True)
    root = Path(__file__).resolve().parent.parent
    return subprocess.call([sys.executable, "-m", "pytest", "-q", "-m", "kernel_sensitive",
                            *arguments], cwd=root, env=environment)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
