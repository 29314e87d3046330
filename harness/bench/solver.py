"""``impact-harness bench``: benchmarks, never timed tests.

* ``--solver``: batch throughput of every law on 10^6 random problems, as a ratio to 12
  plain numpy passes over arrays of the same length measured in the same run (target for
  ``poisson``: ≤ 8); scalar ``solve`` per call; the exact impulse process per problem;
  throughput against batch size (1 … 10^6, 10^7 without ``--quick``).

  The passes are timed two ways, and both ratios are printed. *Kept*: each pass's result
  stays alive, as the 12 arrays of a batch result do, so the 12 passes write 96 MB of
  distinct memory. *Reused*: each result is dropped at once, so every pass gets the same
  buffer back and the three arrays it touches (24 MB) stay in a large last-level cache
  (32 MB on the development machine). The target is judged against *kept*, like for like: a
  batch solver reads its 7 inputs and writes its 12 outputs (about 130 MB at 10^6 rows),
  which no cache holds. Both are reported; ``output_write_time`` (allocating and filling a
  result's arrays, no arithmetic) shows the floor under any batch solver.
* ``--engines``: the harness's cost per impact beside each engine's bare stepping
  (:mod:`harness.bench.engines`).
* ``--speed-accuracy``: run time against error per engine (:mod:`harness.bench.accuracy`).
* ``--survey``: the survey end to end beside the engines' bare stepping of the same impacts
  (:mod:`harness.bench.survey`).
* ``--executors``: 2,000 engine tasks through the local pool and a local 2-worker Dask
  cluster (:mod:`harness.bench.executors`; needs ``pip install -e ".[dask]"``).

With no selection, all of them run. Every benchmark checks its own answer before timing it
(a fast wrong answer is no result). Figures and a machine-readable table go to
``reports/bench/`` (``--out``). The table, ``bench.json``, is updated, not replaced: a run of
some sections replaces those and keeps the others already there, and its ``measured`` entry
says when (and with which commit, whether ``--quick``) each section was measured.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

import planar_impact as pi
from harness import bounds
from harness.bench import accuracy as bench_accuracy
from harness.bench import engines as bench_engines
from harness.bench import executors as bench_executors
from harness.bench import survey as bench_survey
from harness.run.executor import DaskNotInstalled, check_arguments
from harness.run.provenance import provenance
from harness.scene.random_problems import random_problems, row
from harness.store.files import (
    make_output_directory,
    output_directory_problem,
    save_figure,
    write_text_atomically,
)
from harness.store.identity import code_version_of

BENCH_FORMAT = "impact-harness-bench"
BENCH_FORMAT_VERSION = 2
BASELINE_PASSES = 12


def _best_time(function, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        function()
        best = min(best, time.perf_counter() - start)
    return best


def numpy_passes_time(size: int, repeat: int = 5, keep: bool = True) -> float:
    """Time of ``BASELINE_PASSES`` plain elementwise numpy passes (``a * b``, allocating)
    over arrays of ``size`` float64; with ``keep`` every result stays alive until the end."""
    rng = np.random.default_rng(0)
    a, b = rng.random(size), rng.random(size)

    def passes_kept():
        kept = [a * b for _ in range(BASELINE_PASSES)]
        return kept

    def passes_reused():
        for _ in range(BASELINE_PASSES):
            a * b

    return _best_time(passes_kept if keep else passes_reused, repeat)


def result_dtypes() -> list:
    """The dtype of every array a batch result holds."""
    result = pi.solve_batch(1.0, 0.0, 1.0, -1.0, 0.0, 0.0, 0.0)
    return [values.dtype for values in result.as_dict().values() if isinstance(values, np.ndarray)]


def output_write_time(size: int, repeat: int = 5) -> float:
    """Time to allocate and fill the arrays of one batch result (no arithmetic): the floor
    under any batch solver's time."""
    dtypes = result_dtypes()

    def write():
        arrays = [np.empty(size, dtype=dtype) for dtype in dtypes]
        for values in arrays:
            values.fill(0)
        return arrays

    return _best_time(write, repeat)


def solver_benchmark(quick: bool) -> dict:
    size = 1_000_000
    problems = random_problems(size, seed=1)
    rounds = 3 if quick else 5
    sample = random_problems(200, seed=2)
    solved_share = {}
    for law in pi.LAWS:
        solved_share[law] = float(np.mean(pi.solve_batch(**problems, law=law).status == 0))
        _check_against_process(law, sample)
    # Interleaved rounds, best of each: a burst of load on the shared machine then hits the
    # baselines and the laws alike. Each call's result is dropped before the next, as the
    # passes' are: a live result changes where the allocator puts the next one.
    timed = {"kept": lambda: numpy_passes_time(size, 1, keep=True),
             "reused": lambda: numpy_passes_time(size, 1, keep=False),
             "write": lambda: output_write_time(size, 1)}
    timed.update({law: (lambda law=law: _best_time(
                            lambda: pi.solve_batch(**problems, law=law), 1))
                  for law in pi.LAWS})
    best = {name: float("inf") for name in timed}
    for _ in range(rounds):
        for name, measure in timed.items():
            best[name] = min(best[name], measure())
    baseline, reused = best["kept"], best["reused"]
    results = {"size": size, "numpy_passes": BASELINE_PASSES, "numpy_passes_s": baseline,
               "numpy_passes_reused_s": reused, "output_write_s": best["write"], "laws": {}}
    for law in pi.LAWS:
        seconds = best[law]
        results["laws"][law] = {
            "batch_s": seconds,
            "problems_per_s": size / seconds,
            "ratio_to_numpy_passes": seconds / baseline,
            "ratio_to_reused_passes": seconds / reused,
            "solved_share": solved_share[law],
        }
    results["scalar_solve_us"] = scalar_solve_times(rounds)
    results["process_us"] = process_times(quick)
    results["batch_sizes"] = batch_size_scan(quick)
    return results


def _check_against_process(law: str, sample: dict) -> None:
    """A fast wrong answer is no answer: compare a sample with the exact impulse process."""
    if law == "newton-lcp":
        return  # checked against enumeration and PGS in the test suite; no process exists
    batch = pi.solve_batch(**sample, law=law)
    for index in range(len(sample["mnn"])):
        r = row(sample, index)
        if law == "stronge-paper":
            r["e"] = float(batch.restitution_poisson[index])
        sign = -1.0 if r["vt"] == 0.0 and r["mnt"] < 0 else 1.0
        walked = pi.impulse_process(**{**r, "mnt": sign * r["mnt"]},
                                    law="poisson" if law == "stronge-paper" else law)
        scale = abs(r["vn"]) / r["mnn"] + abs(r["vt"]) / r["mtt"]
        if abs(walked.normal_impulse - batch.normal_impulse[index]) > 1e-9 * scale:
            raise AssertionError(f"bench: {law} disagrees with the impulse process on {r}")


def scalar_solve_times(repeat: int) -> dict:
    problem = pi.builders.two_sleds(gamma=0.2, delta=0.85)
    times = {}
    for law in pi.LAWS:
        calls = 2000
        # B023: _best_time calls the closure at once, within this iteration.
        seconds = _best_time(
            lambda: [problem.solve(mu=0.3, e=0.8, law=law)  # noqa: B023
                     for _ in range(calls)],  # noqa: B023
            repeat)
        times[law] = seconds / calls * 1e6
    return times


def process_times(quick: bool) -> dict:
    """Exact impulse process (pure Python, scalar) per problem, against the closed form."""
    count = 2000 if quick else 20000
    sample = random_problems(count, seed=3)
    rows = [row(sample, i) for i in range(count)]
    times = {}
    for law in ("newton", "poisson", "stronge"):
        start = time.perf_counter()
        for r in rows:
            sign = -1.0 if r["vt"] == 0.0 and r["mnt"] < 0 else 1.0
            pi.impulse_process(**{**r, "mnt": sign * r["mnt"]}, law=law)
        times[law] = (time.perf_counter() - start) / count * 1e6
    return times


def batch_size_scan(quick: bool) -> dict:
    sizes = [10**k for k in range(0, 7 if quick else 8)]
    largest = random_problems(sizes[-1], seed=4)
    scan = {law: {} for law in pi.LAWS}
    for size in sizes:
        problems = {k: v[:size] for k, v in largest.items()}
        repeat = 3 if size >= 10**6 else 7
        for law in pi.LAWS:
            # B023: _best_time calls the closure at once, within this iteration.
            seconds = _best_time(lambda: pi.solve_batch(**problems, law=law),  # noqa: B023
                                 repeat)
            scan[law][size] = size / seconds
    return scan


def print_solver(results: dict) -> None:
    print(f"Solver, batch of {results['size']:,} random problems; {BASELINE_PASSES} numpy passes "
          f"keeping their results {results['numpy_passes_s'] * 1e3:.1f} ms, reusing one buffer "
          f"{results['numpy_passes_reused_s'] * 1e3:.1f} ms; allocating and filling a batch "
          f"result's arrays {results['output_write_s'] * 1e3:.1f} ms")
    print(f"  {'law':<14} {'time [ms]':>10} {'problems/s':>12} {'ratio':>7} {'ratio (reused)':>15}"
          "  (target for poisson: ratio ≤ 8)")
    for law, entry in results["laws"].items():
        print(f"  {law:<14} {entry['batch_s'] * 1e3:>10.1f} "
              f"{entry['problems_per_s'] / 1e6:>10.1f} M "
              f"{entry['ratio_to_numpy_passes']:>7.2f} {entry['ratio_to_reused_passes']:>15.2f}")
    print("  scalar solve per call: "
          + ", ".join(f"{law} {t:.0f} µs" for law, t in results["scalar_solve_us"].items())
          + " (target ≤ 10 µs)")
    print("  exact impulse process per problem (pure Python): "
          + ", ".join(f"{law} {t:.1f} µs" for law, t in results["process_us"].items()))


def write_solver_figure(results: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    for law, scan in results["batch_sizes"].items():
        sizes = sorted(int(s) for s in scan)
        ax.loglog(sizes, [scan[s] for s in sizes], marker="o", label=law)
    process = results["process_us"].get("poisson")
    if process:
        ax.axhline(1e6 / process, color="0.5", ls=":", label="impulse process (scalar, poisson)")
    ax.set_xlabel("batch size [problems]")
    ax.set_ylabel("throughput [problems/s]")
    ax.set_title("planar_impact.solve_batch throughput")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    save_figure(fig, path, "png", dpi=110)  # over a regular file only
    plt.close(fig)


def add_arguments(parser) -> None:
    parser.add_argument("--solver", action="store_true", help="solver throughput and scalar cost")
    parser.add_argument("--engines", action="store_true", help="harness overhead per engine impact")
    parser.add_argument("--speed-accuracy", action="store_true",
                        help="run time against error per engine")
    parser.add_argument("--survey", action="store_true",
                        help="survey end to end beside the engines' bare stepping of its impacts")
    parser.add_argument("--executors", action="store_true",
                        help="2,000 engine tasks: local pool against a local 2-worker Dask "
                        "cluster")
    parser.add_argument("--workers", type=bounds.option("workers"), default=1,
                        help="--survey: processes for the survey and, as many, for the bare "
                        "stepping it is compared with (default 1)")
    parser.add_argument("--quick", action="store_true", help="smaller sizes; finishes in minutes")
    parser.add_argument("--out", type=Path, default=Path("reports/bench"),
                        help="output directory (default: reports/bench); the sections run "
                        "replace theirs in its bench.json, the others are kept")


def main(args) -> int:
    names = ("solver", "engines", "speed_accuracy", "survey", "executors")
    selected = [name for name in names if getattr(args, name)] or list(names)
    problem = output_directory_problem(args.out)
    if problem:
        print(f"impact-harness bench: --out {args.out}: {problem}", file=sys.stderr)
        return 2
    if "speed_accuracy" in selected:
        for problem in bench_accuracy.reference_problems(args.quick):
            print(f"impact-harness bench --speed-accuracy: {problem}", file=sys.stderr)
            return 2
    make_output_directory(args.out)  # the directory asked for (itself only)
    # the digest of harness/bench/ beside the cached code's: the report links the bench page
    # only while both are today's (harness/report/pages.py)
    command_code = code_version_of((Path(__file__).resolve().parent,))
    table = {"provenance": provenance(BENCH_FORMAT, BENCH_FORMAT_VERSION,
                                      command_code_version=command_code),
             "quick": bool(args.quick)}
    path = args.out / "bench.json"

    def keep() -> None:
        """bench.json with every section measured so far: a section that fails later (an
        engine, a subprocess) leaves the finished ones written."""
        write_text_atomically(path, json.dumps(merged_table(path, table, names), indent=1,
                                               default=str))

    if "solver" in selected:
        results = solver_benchmark(args.quick)
        print_solver(results)
        write_solver_figure(results, args.out / "solver-throughput.png")
        table["solver"] = results
        keep()
    if "engines" in selected:
        report = bench_engines.run_engine_overhead_benchmark(quick=args.quick)
        print(bench_engines.format_table(report))
        table["engines"] = report
        keep()
    if "speed_accuracy" in selected:
        table["speed_accuracy"] = bench_accuracy.run(args.quick, args.out)
        keep()
    if "survey" in selected:
        samples = bench_survey.QUICK_SAMPLES if args.quick else bench_survey.SAMPLES
        rounds = bench_survey.QUICK_ROUNDS if args.quick else bench_survey.ROUNDS
        # The end to end at full size in quick mode too: at QUICK_SAMPLES the survey's fixed
        # cost per family and pair (statistics, files) outweighs its cost per impact.
        report = bench_survey.run(samples, rounds=rounds, workers=max(1, args.workers),
                                  end_to_end_samples=bench_survey.SAMPLES)
        report["memory"] = bench_survey.memory(
            bench_survey.QUICK_MEMORY_SIZES if args.quick else bench_survey.MEMORY_SIZES)
        print(bench_survey.format_report(report))
        table["survey"] = report
        keep()
    if "executors" in selected:
        try:
            check_arguments("dask")
        except DaskNotInstalled as error:
            print(f"executors: skipped: {error}")
        else:
            report = bench_executors.run(
                repeats=bench_executors.QUICK_REPEATS if args.quick else bench_executors.REPEATS,
                per_task=not args.quick)
            print(bench_executors.format_report(report))
            table["executors"] = report
            keep()
    keep()  # (the sections not run this time kept from the file, as each keep() did)
    print(f"written {path}")
    return 0


def merged_table(path: Path, table: dict, names: tuple[str, ...]) -> dict:
    """``table`` (this run's sections among ``names``) with the sections of the existing
    ``bench.json`` at ``path`` that this run did not measure, and ``measured``: for each
    section, when, from which commit, with which versions, on which machine and whether
    ``--quick`` (the top-level provenance is this run's only; a section kept from a file
    without it gets that file's provenance). README tables and the bench page read the
    file as a whole: a run of one section must not drop the others."""
    ran = table["provenance"]
    this_run = {"created_utc": ran["created_utc"], "commit": ran["git"]["commit"],
                "quick": table["quick"], "versions": ran.get("versions"),
                "machine": ran.get("machine")}
    try:
        existing = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):  # none yet, or unreadable: this run's sections only
        existing = {}
    if not isinstance(existing, dict) or \
            existing.get("provenance", {}).get("format") != BENCH_FORMAT:
        existing = {}
    before = existing.get("provenance", {})
    measured_before = existing.get("measured") or {}
    merged = dict(table)
    measured = {}
    for name in names:
        if name in table:
            measured[name] = this_run
        elif name in existing:
            merged[name] = existing[name]
            measured[name] = measured_before.get(name) or {
                "created_utc": before.get("created_utc"),
                "commit": (before.get("git") or {}).get("commit"),
                "quick": existing.get("quick"), "versions": before.get("versions"),
                "machine": before.get("machine")}
    merged["measured"] = measured
    return merged
