"""Run the numerically sensitive tests again on other kernels: ``make test`` runs this after
the whole suite, and it can be run by hand (arguments go to pytest)::

    .venv/bin/python tests/other_kernels.py --passes-at-once 2   # what make test runs
    .venv/bin/python tests/other_kernels.py --list      # the kernels it would run, and stop

The tests marked ``kernel_sensitive`` (pins of stored results, counts, decisions, findings:
see tests/conftest.py) run once more under every OpenBLAS core type this CPU can execute
(``OPENBLAS_CORETYPE``; :data:`CORE_TYPES`, each with the CPU flags its kernels need, read
from /proc/cpuinfo): Prescott (SSE3, every x86-64 CPU), Nehalem, SandyBridge, Haswell, Zen,
and SkylakeX and Cooperlake where the CPU has AVX-512. Results through BLAS, libm or SIMD
differ in the last bits between such kernels as they do between CPUs; these tests must pass
on each (issue 35): a kernel a CPU lacks cannot be tried here, so a bound found by trying
kernels is not a bound, and the tests compare within derived bounds (tests/error_bounds.py).

The passes, chosen to keep ``make test`` short:

* Prescott with every SIMD target numpy dispatches to at run time turned off
  (``NPY_DISABLE_CPU_FEATURES``: numpy then runs its baseline loops): the whole
  kernel_sensitive set, the oldest arithmetic against this run's newest (about 25 s of CPU
  on the development machine);
* each other core type the CPU can run: the kernel_sensitive tests but those marked
  ``blas_free`` (the contact geometry compared with its reference form, bit for bit: their
  arithmetic takes no BLAS product, so a BLAS kernel cannot move them, and
  ``test_contacts_are_the_same_bits_under_another_kernel``, which is run, checks exactly
  that under each), numpy's SIMD as it is (about 21 s of CPU each).

``--skip-native`` (``make test``, right after the whole suite) leaves out the pass of this
run's own core type with numpy's SIMD as it is (``OPENBLAS_CORETYPE`` where set, else what
OpenBLAS chose, read by threadpoolctl): the whole suite has just run every kernel_sensitive
test exactly so, and the report names the kernel left out. Run by hand, every pass runs.

Off x86-64 the BLAS kernel is left as it is (one pass, SIMD off, with a note). Every pass
runs even when one fails; the report at the end names each kernel with its outcome and time,
and the exit status is the first failure's (0 when all pass).

What keeps it short: each pass is one pytest process given only the test files that name
``kernel_sensitive`` (:func:`kernel_sensitive_files`), not the whole suite. ``-m`` alone
would still import and collect every test module (about 8 s of CPU without bytecode caches,
3 s with them, in each pytest-xdist worker) to run a thirtieth of the tests. The rule is a
plain text search, so a marked test can escape it only by being marked from another file (a
conftest hook, a shared mark object); ``tests/test_other_kernels.py`` checks, on the whole
suite's collection, that every test carrying the mark sits in a file the rule names. And the
passes, each a single process, run ``--passes-at-once N`` at a time (default 1) instead of
each spreading over pytest-xdist workers: a pass's tests then share one import of the
engines, and the two cores stay busy while one pass finishes its slowest test (each pass
took about 38 s of CPU over two workers before, 21 s alone). A pass's output is printed
whole when it ends (live when one runs at a time); its CPU time is its own process tree's
(``os.wait4``).
"""

from __future__ import annotations

import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: OpenBLAS's kernels for the oldest x86-64 CPUs it knows (SSE3): they run on every x86-64.
OLD_KERNEL = "Prescott"

#: OpenBLAS core types tried, oldest first, each with the /proc/cpuinfo flags its kernels use
#: (a CPU without one of them would stop at an illegal instruction).
CORE_TYPES = {
    "Prescott": ("pni",),  # SSE3
    "Nehalem": ("ssse3", "sse4_1", "sse4_2", "popcnt"),
    "SandyBridge": ("avx",),
    "Haswell": ("avx2", "fma"),
    "Zen": ("avx2", "fma"),
    "SkylakeX": ("avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl"),
    "Cooperlake": ("avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl", "avx512_bf16"),
}


def cpu_flags(cpuinfo: str | None = None) -> set[str]:
    """The flags of the first processor in /proc/cpuinfo (empty where there is none)."""
    if cpuinfo is None:
        try:
            cpuinfo = Path("/proc/cpuinfo").read_text()
        except OSError:
            return set()
    for line in cpuinfo.splitlines():
        name, _, value = line.partition(":")
        if name.strip() == "flags":
            return set(value.split())
    return set()


def runnable_core_types(flags: set[str]) -> list[str]:
    """The core types of :data:`CORE_TYPES` whose every flag the CPU has, oldest first."""
    return [name for name, needs in CORE_TYPES.items() if flags.issuperset(needs)]


def numpy_simd_targets() -> list[str]:
    """numpy's SIMD targets dispatched at run time (what ``NPY_DISABLE_CPU_FEATURES`` turns
    off)."""
    try:
        from numpy._core._multiarray_umath import __cpu_dispatch__
    except ImportError:  # numpy < 2
        from numpy.core._multiarray_umath import __cpu_dispatch__
    return list(__cpu_dispatch__)


def kernel_environment(core_type: str | None = OLD_KERNEL,
                       simd_off: bool = True) -> tuple[dict[str, str], list[str]]:
    """The environment of a pass under ``core_type`` (``None``: the BLAS kernel as it is),
    numpy's SIMD dispatch off when ``simd_off``, and what it changes (for the log)."""
    environment = dict(os.environ)
    changes = []
    if core_type is not None and platform.machine().lower() in ("x86_64", "amd64"):
        environment["OPENBLAS_CORETYPE"] = core_type
        changes.append(f"OPENBLAS_CORETYPE={core_type}")
    else:
        environment.pop("OPENBLAS_CORETYPE", None)
        changes.append(f"BLAS kernel left as is ({platform.machine()})")
    targets = numpy_simd_targets()
    if simd_off and targets:  # disabling a target the CPU lacks is allowed (and does nothing)
        environment["NPY_DISABLE_CPU_FEATURES"] = " ".join(targets)
        changes.append(f"NPY_DISABLE_CPU_FEATURES={' '.join(targets)}")
    else:
        environment.pop("NPY_DISABLE_CPU_FEATURES", None)
    return environment, changes


def printed_under_old_kernel(module: str, function: str) -> str:
    """What ``module.function()`` prints in a fresh Python process under
    :data:`OLD_KERNEL` with numpy's SIMD off (:func:`kernel_environment`): the bit-for-bit
    rerun tests compare a digest made there with this process's."""
    environment, _ = kernel_environment(OLD_KERNEL)
    root = Path(__file__).resolve().parent.parent
    script = f"from {module} import {function}; print({function}())"
    there = subprocess.run([sys.executable, "-c", script], cwd=root, env=environment,
                           capture_output=True, text=True, timeout=600, check=True)
    return there.stdout.strip()


#: The tests of every pass, and of the passes under the other BLAS core types.
ALL_TESTS, BLAS_TESTS = "kernel_sensitive", "kernel_sensitive and not blas_free"


def passes(flags: set[str]) -> list[tuple[str | None, bool, str]]:
    """``(core type, SIMD off, pytest marker expression)`` of each pass (module docstring)."""
    if platform.machine().lower() not in ("x86_64", "amd64"):
        return [(None, True, ALL_TESTS)]
    others = [name for name in runnable_core_types(flags) if name != OLD_KERNEL]
    return [(OLD_KERNEL, True, ALL_TESTS)] + [(name, False, BLAS_TESTS) for name in others]


def kernel_sensitive_files(tests_directory: Path) -> list[Path]:
    """The test files under ``tests_directory`` (pytest's default names: test_*.py, *_test.py)
    whose text names the ``kernel_sensitive`` mark, sorted: every file where a test can be
    marked with it (the rule's check: tests/test_other_kernels.py)."""
    return sorted(path for path in tests_directory.rglob("*.py")
                  if (path.name.startswith("test_") or path.name.endswith("_test.py"))
                  and "kernel_sensitive" in path.read_text(encoding="utf-8"))


def run_passes(runs: list[tuple[str, list[str], dict[str, str]]], at_once: int,
               cwd: Path) -> list[tuple[int, float, float]]:
    """Run each ``(title, command, environment)`` of ``runs`` in order, up to ``at_once`` at a
    time. One at a time, each prints as it goes under its title; else each one's output is
    kept in a file and printed whole, under its title, when it ends (never interleaved).
    Returns each run's exit status, wall time and CPU time (user + system of its process
    tree, s), in the order of ``runs``."""
    outcomes: list[tuple[int, float, float] | None] = [None] * len(runs)
    waiting = list(enumerate(runs))
    running = {}  # index: (process, its output file or None, started)
    while waiting or running:
        while waiting and len(running) < at_once:
            index, (title, command, environment) = waiting.pop(0)
            output = None
            if at_once == 1:
                print(f"\n== {title}", flush=True)
            else:
                output = tempfile.TemporaryFile()
            process = subprocess.Popen(command, cwd=cwd, env=environment, stdout=output,
                                       stderr=None if output is None else subprocess.STDOUT)
            running[index] = (process, output, time.monotonic())
        finished = []
        for index, (process, output, started) in running.items():
            pid, status, usage = os.wait4(process.pid, os.WNOHANG)
            if pid == 0:
                continue
            process.returncode = os.waitstatus_to_exitcode(status)  # reaped here, not by Popen
            outcomes[index] = (process.returncode, time.monotonic() - started,
                               usage.ru_utime + usage.ru_stime)
            if output is not None:
                output.seek(0)
                print(f"\n== {runs[index][0]}", flush=True)
                sys.stdout.buffer.write(output.read())
                sys.stdout.flush()
                output.close()
            finished.append(index)
        for index in finished:
            del running[index]
        if running and not finished:
            time.sleep(0.1)
    return outcomes


def native_core_type() -> str | None:
    """The OpenBLAS core type this process runs (``OPENBLAS_CORETYPE`` where set, else what
    OpenBLAS chose for the CPU, as threadpoolctl reads it), ``None`` where unknown."""
    if os.environ.get("OPENBLAS_CORETYPE"):
        return os.environ["OPENBLAS_CORETYPE"]
    try:
        from threadpoolctl import threadpool_info
    except ImportError:
        return None
    import numpy  # noqa: F401  (loads numpy's OpenBLAS, which threadpoolctl then sees)
    found = [entry.get("architecture") for entry in threadpool_info()
             if entry.get("internal_api") == "openblas"]
    return next((name for name in found if name in CORE_TYPES), None)


def without_native(planned, native: str | None):
    """``(planned, skipped)``: the passes but the native kernel's own (its core type with
    numpy's SIMD as it is: exactly how the whole suite, which ``make test`` runs first, ran
    every kernel_sensitive test), and the name of the one left out (``None`` if none)."""
    kept = [entry for entry in planned if not (entry[0] == native and not entry[1])]
    return kept, (native if len(kept) < len(planned) else None)


def passes_at_once(arguments: list[str]) -> tuple[int, list[str]]:
    """The ``--passes-at-once N`` (or ``=N``) of ``arguments`` (1 without it), and the
    arguments left for pytest."""
    at_once, rest = 1, []
    iterator = iter(arguments)
    for argument in iterator:
        if argument == "--passes-at-once":
            value = next(iterator, "")
        elif argument.startswith("--passes-at-once="):
            value = argument.partition("=")[2]
        else:
            rest.append(argument)
            continue
        if not value.isdigit() or int(value) < 1:
            raise SystemExit(f"other_kernels.py: --passes-at-once takes a count >= 1, "
                             f"not {value!r}")
        at_once = int(value)
    return at_once, rest


def main(arguments: list[str]) -> int:
    flags = cpu_flags()
    planned = passes(flags)
    names = [core_type or "as is" for core_type, _, _ in planned]
    lacking = [name for name in CORE_TYPES if name not in names]
    skipped = None
    if "--skip-native" in arguments:  # make test: the whole suite has just run natively
        arguments = [argument for argument in arguments if argument != "--skip-native"]
        planned, skipped = without_native(planned, native_core_type())
    print(f"kernel_sensitive tests again under {len(planned)} kernels: "
          f"{', '.join(core_type or 'as is' for core_type, _, _ in planned)}"
          + (f" ({skipped}, this run's own kernel: the whole suite ran them under it)"
             if skipped else "")
          + (f" (this CPU cannot run {', '.join(lacking)})" if lacking else ""), flush=True)
    if "--list" in arguments:
        return 0
    at_once, pytest_arguments = passes_at_once(arguments)
    root = Path(__file__).resolve().parent.parent
    files = [str(path.relative_to(root)) for path in kernel_sensitive_files(root / "tests")]
    runs, labels = [], []
    for core_type, simd_off, tests in planned:
        environment, changes = kernel_environment(core_type, simd_off)
        runs.append((f"{tests} with {', '.join(changes)}",
                     [sys.executable, "-m", "pytest", "-q", "-m", tests, *pytest_arguments,
                      *files], environment))
        labels.append(f"{', '.join(changes)}: {tests}")
    if at_once > 1:
        print(f"{len(runs)} passes, {at_once} at a time, each over the {len(files)} files "
              "that name kernel_sensitive; each pass's output when it ends", flush=True)
    outcomes = run_passes(runs, at_once, root)
    print("\nkernel_sensitive tests on other kernels (wall time, CPU time of the pass):")
    for label, (status, seconds, cpu) in zip(labels, outcomes):
        verdict = "passed" if status == 0 else f"FAILED (pytest exit status {status})"
        print(f"  {verdict:<34} {seconds:6.1f} s {cpu:6.1f} s CPU  {label}")
    return next((status for status, _, _ in outcomes if status != 0), 0)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
