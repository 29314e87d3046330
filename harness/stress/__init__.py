"""``impact-harness stress``: the solver and the engines over hostile inputs.

Solver (``planar_impact.solve_batch``, every law), contact-space families:

* ``mass-ratio``   two bodies, masses 1 and k, k = 1e-6 … 1e6 (random contact geometry);
* ``speed``        |v^A| = 1e-6 … 1e4 m/s;
* ``grazing``      |v_n^A|/|v_t^A| = 1e-9 … 1, and 1e-100 … 1e-300 (α near overflow);
* ``size``         body size L = 1e-6 … 1e6 m (inertia ∝ m L², lever arms ∝ L);
* ``e-mu-extremes`` e ∈ {0, 1} × μ ∈ {0, 10};
* ``conditioning`` Δ/(m_nn m_tt) = 1e-3 … 1e-15 (nearly singular mass matrix);
* boundaries, each approached from both sides, at k ulps (``np.nextafter``) and at relative
  distances δ = 1e-15 … 1e-2: ``α = r_m``, ``α = (1+e) r_m``, ``g → 0`` (μ → m_nt/m_tt),
  ``p → 0`` (μ → −m_nt/m_tt), ``h → 0`` (μ → m_nn/m_nt), ``q → 0`` (μ → −m_nn/m_nt).

Checks: no silent NaN/inf (a row with status 0 has finite outputs; a bad row has a status);
continuity at the boundaries (the *jump*: the largest change of ``(I_n, I_t)`` between
neighbouring inputs, relative to ``|I_n| + |I_t|``, must shrink with the distance; across one
ulp it is rounding); Poisson and Stronge never gain energy (a gain above 1e-10 of the
energy scale ``|v_n| I_n + |v_t I_t|`` plus the rounding allowance ``10 eps/c`` of a problem of
conditioning ``c = Δ/(m_nn m_tt)`` is counted; raw gains above 1e-10 are reported apart).
Newton's gains are counted too, as information (Newton can gain energy; docs/theory.md,
'Newton's law').

Engines (every engine of the registry, :func:`harness.engines.engine_names`, those
registered at run time too; each installed one under both presets, ``defaults`` and
``accurate``, quick or full): a disk and the 45° rod against the ground, scaled in mass
(1e-6 … 1e6 kg), size (1e-4 … 1e3 m), speed (1e-6 … 1e4 m/s), near grazing, e ∈ {0, 1},
μ ∈ {0, 10}, and time steps 1e-6 … 1e-1 s (MuJoCo and Drake keep their contact's duration at
``accurate``: ``time_step_overrides``). Each run's outcome is the first that applies of:
``stopped`` (over its time limit, or its worker died), ``error`` (exception),
``unsupported`` (the adapter refuses the scene: Box2D's polygons below its area floor at
size 1e-4 m), ``non-finite``, ``blow-up``, ``energy-gain``, ``no-separation`` (step cap hit
in contact), ``no-contact`` (never touched within the cap), ``deep-penetration`` (deeper
than 10% of the body's extent), ``clipped`` (a speed at the engine's cap), ``flagged``
(another failed verdict check), ``ok``. Full mode sweeps finer. An engine not installed is
reported as such (``skipped``, with the reason), never dropped.

Outputs in ``--out`` (default ``reports/stress``): ``stress.md`` (the stability report),
``stress.json`` (everything, machine-readable), ``stress-engines.csv`` (one row per engine
run), figures ``engine-grid.png``, ``solver-boundary-jumps.png``, ``solver-energy.png``.
Engine runs are cached (:class:`harness.store.cache.ResultCache`; ``--no-cache`` forces them) and
spread over local cores (:func:`harness.run.executor.run_tasks`; ``--executor dask``).
"""


from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from harness import bounds
from harness.run.executor import DaskNotInstalled, check_arguments, progress_printer
from harness.run.provenance import provenance
from harness.store.files import output_directory_problem, write_text_atomically
from harness.stress.engines import COMMAND_CODE_VERSION, engine_stress
from harness.stress.outputs import (
    boundary_jumps_figure,
    energy_figure,
    engine_grid_figure,
    stress_markdown,
    write_engine_csv,
)
from harness.stress.solver import solver_stress

STRESS_FORMAT = "impact-harness-stress"
STRESS_FORMAT_VERSION = 2


def run(quick: bool, out_dir: Path, executor: str = "local", workers: int | None = None,
        scheduler: str | None = None, use_cache: bool = True, engines: bool = True,
        engine_names: tuple[str, ...] | None = None) -> dict:
    """The whole stress test; writes the report into ``out_dir`` and returns it.
    ``engine_names``: the engines stressed (default: every registered one)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    solver = solver_stress(quick)
    solver_s = time.perf_counter() - started
    started = time.perf_counter()
    if engines:
        progress = None if quick else progress_printer("stress engines")
        engine_report = engine_stress(quick, executor, workers, scheduler, use_cache,
                                      progress=progress, engines=engine_names)
    else:
        engine_report = {"versions": {}, "skipped": {}, "presets": [], "runs": [], "counts": {},
                         "cache": {"hits": 0, "misses": 0}, "tasks_run": 0}
    engines_s = time.perf_counter() - started
    report = {
        "quick": quick,
        "provenance": provenance(STRESS_FORMAT, STRESS_FORMAT_VERSION,
                                 engine_versions=engine_report["versions"], executor=executor,
                                 command_code_version=COMMAND_CODE_VERSION),
        "timings": {"solver_s": solver_s, "engines_s": engines_s},
        "solver": solver,
        "engines": engine_report,
    }
    write_text_atomically(out_dir / "stress.json", json.dumps(report, indent=1, default=str))
    write_engine_csv(engine_report, out_dir / "stress-engines.csv")
    boundary_jumps_figure(solver, out_dir / "solver-boundary-jumps.png")
    energy_figure(solver, out_dir / "solver-energy.png")
    grid = out_dir / "engine-grid.png"
    if engine_report["runs"]:
        engine_grid_figure(engine_report, grid)
    elif grid.is_file() and not grid.is_symlink():  # an earlier run's, not this one's
        grid.unlink()
    write_text_atomically(out_dir / "stress.md", stress_markdown(report))
    return report


def add_arguments(parser) -> None:
    parser.add_argument("--quick", action="store_true",
                        help="fewer cases; finishes in about a minute")
    parser.add_argument("--out", type=Path, default=Path("reports/stress"),
                        help="output directory (default: reports/stress)")
    parser.add_argument("--executor", choices=("local", "dask"), default="local",
                        help="where engine runs execute (default: a local process pool)")
    parser.add_argument("--workers", type=bounds.option("workers"), default=None,
                        help="worker processes (default: all cores)")
    parser.add_argument("--scheduler", default=None,
                        help="Dask scheduler address (with --executor dask)")
    parser.add_argument("--no-cache", action="store_true", help="rerun every engine case")
    parser.add_argument("--solver-only", action="store_true", help="skip the engines")


def counts_text(counts: dict) -> str:
    """``{"silent_non_finite": 0, "energy_gain": 2}`` as a reader's line, ``silent non-finite
    0, energy gain 2`` (not Python's dict)."""
    return ", ".join(f"{str(name).replace('_', ' ')} {count}" for name, count in counts.items())


def main(args) -> int:
    problem = output_directory_problem(args.out)
    if problem:
        print(f"impact-harness stress: --out {args.out}: {problem}", file=sys.stderr)
        return 2
    try:  # --executor, --workers and --scheduler as `run` checks them, before any work
        check_arguments(args.executor, args.workers, args.scheduler)
    except (ValueError, DaskNotInstalled) as error:
        print(f"impact-harness stress: {error}", file=sys.stderr)
        return 2
    started = time.perf_counter()
    report = run(args.quick, args.out, executor=args.executor, workers=args.workers,
                 scheduler=args.scheduler, use_cache=not args.no_cache,
                 engines=not args.solver_only)
    totals = report["solver"]["totals"]
    print(f"solver: {counts_text(totals)}")
    for group, counts in report["engines"]["counts"].items():
        bad = {name: count for name, count in counts.items() if count and name != "ok"}
        print(f"{group}: ok {counts['ok']}, {counts_text(bad) or 'no failures'}")
    for name, reason in report["engines"]["skipped"].items():
        print(f"{name}: skipped ({reason})")
    print(f"written {args.out / 'stress.md'} ({time.perf_counter() - started:.1f} s)")
    # exit status: the solver's guarantees (engines' failures are findings, not errors)
    failed = (totals["silent_non_finite"] or totals["energy_gain_poisson_stronge"]
              or totals["scalar_silent_non_finite"])
    return 1 if failed else 0
