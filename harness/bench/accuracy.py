"""Speed against accuracy per engine (``impact-harness bench --speed-accuracy``).

For every installed engine the registry lists (those registered at run time too), a sweep of
the knobs that trade cost for accuracy (time step, solver iterations, sub-steps, presets,
MuJoCo's contact time constant and integrator) over
four scenario families (:func:`harness.bench.engines.reference_scenes`):

* ``disk``       disk r 0.1 m, v (1, −1) m/s (sticks under newton-lcp);
* ``rod``        the 45° rod, v (0.5, −1) m/s: slip reversal under Poisson (docs/theory.md,
  'The velocity-level law (newton-lcp)');
* ``box-corner`` a box corner with spin;
* ``two-bodies`` two disks off-centre, both free.

Measured per (engine, setting, family): wall time per impact (s; the least of ``repeats``
runs, caches warm, set-up outside the timed region) and the departure
``‖u_engine − u_law‖_M / ‖u_before‖_M`` from Poisson, from Stronge (exact energetic) and from
the engine's own law, which its class declares (``own_law``) beside its sweep
(``bench_sweep``):

* a law: ``newton-lcp``, the velocity-level Newton–Coulomb law (pymunk, pybullet, Box2D
  solve it), or ``poisson`` or ``stronge``;
* ``converged``: no closed form exists (MuJoCo's soft contact), so its own law is its
  converged limit: the sweep's point its class names in ``bench_reference`` (MuJoCo: RK4,
  the 0.5 ms contact resolved over 400 steps; its sweep holds the contact's duration and
  refines its time step). An engine declaring ``converged`` without naming a point of its
  sweep is refused before any engine runs (:func:`reference_label`).

Outputs: ``pareto-<engine>.png`` in ``out_dir`` (time per impact vs departure from the own law,
one panel per family, the Pareto front drawn, Poisson and Stronge departures as faint marks),
and the table of the cheapest settings (least mean time per impact) whose worst departure
from the own law over all families is ≤ 1% and ≤ 0.1%, or "not reachable". Plus the speed-up
of :func:`harness.run.executor.run_tasks` from 1 to 2 local workers on a batch of engine impacts.
Timings are measurements and are not cached.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from harness.engines import (
    EngineNotInstalled,
    engine_class,
    engine_names,
    ke_norm,
    load_engine,
)
from harness.laws import LAW_NAMES
from harness.processes import default_workers
from harness.run.executor import progress_printer, run_tasks
from harness.scene.geometry import impact_problem
from harness.scene.reference import reference_scenes
from harness.store.files import save_figure

FAMILIES: dict[str, str] = {"disk": "disk", "rod": "rod-45", "box-corner": "box-corner",
                             "two-bodies": "two-disks"}
THRESHOLDS: tuple[float, ...] = (1e-2, 1e-3)


# ---------------------------------------------------------------------- sweeps
def sweep(engine_name: str, quick: bool) -> list[tuple[str, str, dict]]:
    """``[(label, preset, overrides)]`` for one engine: the settings to measure (its
    adapter's ``bench_sweep``)."""
    return engine_class(engine_name).bench_sweep(quick)


TIE_FRACTION = 0.1  # settings whose mean time is within 10% are within timing noise


# ---------------------------------------------------------------------- laws
def reference_label(engine_name: str, quick: bool) -> str | None:
    """The label of the sweep point engine ``engine_name`` converges to (own_law
    ``converged``: its class's ``bench_reference``), None for an engine whose own law is a
    law. Raises ``ValueError`` naming the engine, the attribute and the sweep's labels when
    it names no point of the sweep."""
    cls = engine_class(engine_name)
    if cls.own_law != "converged":
        return None
    labels = [label for label, _, _ in sweep(engine_name, quick)]
    if cls.bench_reference not in labels:
        raise ValueError(f"engine {engine_name!r}: own_law 'converged' needs bench_reference, "
                         f"the label of its converged point in bench_sweep(quick={quick}); got "
                         f"{cls.bench_reference!r}, allowed: {labels}")
    return cls.bench_reference


def reference_problems(quick: bool) -> list[str]:
    """What :func:`reference_label` refuses, for every installed engine the registry lists
    (``bench`` checks it before any work starts)."""
    problems = []
    for name in engine_names():
        try:
            reference_label(name, quick)
        except EngineNotInstalled:
            continue
        except ValueError as error:
            problems.append(str(error))
    return problems


#: The laws every engine's departures are measured from (and its own law, when another).
BENCH_LAWS = ("poisson", "stronge", "newton-lcp")


def law_velocities(scene, contact, normal, laws=BENCH_LAWS) -> dict[str, np.ndarray]:
    """Post-impact generalised speeds of ``scene`` under each of ``laws``."""
    problem = impact_problem(scene, contact, normal)
    return {law: np.asarray(problem.solve(mu=scene.friction, e=scene.restitution,
                                          law=law).u_after, dtype=float)
            for law in laws}


def departure(scene, u_engine, u_law) -> float:
    """``‖u_engine − u_law‖_M / ‖u_before‖_M`` (the runner's metric)."""
    difference = np.asarray(u_engine, dtype=float) - np.asarray(u_law, dtype=float)
    return ke_norm(scene, difference) / ke_norm(scene, scene.state())


# ---------------------------------------------------------------------- measuring
def measure_engine(engine_name: str, quick: bool, progress=None) -> dict:
    """All sweep points × families for one engine (runs inline: timings undisturbed)."""
    engine = load_engine(engine_name)
    reference_setting = reference_label(engine_name, quick)  # checked before any run
    scenes = reference_scenes()
    repeats = 3 if quick else 7
    points = sweep(engine_name, quick)
    # its own law too, when it claims one the bench does not measure every engine from
    solved = BENCH_LAWS + ((engine.own_law,) if engine.own_law in LAW_NAMES
                           and engine.own_law not in BENCH_LAWS else ())
    laws = {family: law_velocities(*scenes[key], laws=solved)
            for family, key in FAMILIES.items()}
    rows = []
    for index, (label, preset, overrides) in enumerate(points):
        settings = engine.settings(preset, overrides)
        for family, key in FAMILIES.items():
            scene = scenes[key][0]
            row = {"engine": engine_name, "setting": label, "preset": preset,
                   "overrides": overrides, "family": family}
            try:
                run = engine.run(scene, settings)  # warm caches, and the answer
                best = math.inf
                for _ in range(repeats):
                    started = time.perf_counter()
                    engine.run(scene, settings)
                    best = min(best, time.perf_counter() - started)
            except Exception as error:  # noqa: BLE001 - a setting the engine refuses is a finding
                row.update(error=f"{type(error).__name__}: {error}"[:200])
                rows.append(row)
                continue
            u_after = run.u_after
            finite = bool(np.all(np.isfinite(u_after)))
            row.update(status=run.status, steps=run.steps, time_per_impact_s=best,
                       u_after=u_after.tolist(),
                       departure={law: (departure(scene, u_after, u) if finite else math.inf)
                                  for law, u in laws[family].items()})
            rows.append(row)
        if progress is not None:
            progress(index + 1, len(points))
    # the own law: one of the laws, or the engine's converged reference run (MuJoCo's)
    for row in rows:
        if "departure" not in row:
            continue
        if engine.own_law in row["departure"]:
            row["departure"]["own"] = row["departure"][engine.own_law]
        else:
            reference = next(r for r in rows
                             if r["setting"] == reference_setting
                             and r["family"] == row["family"])
            scene = scenes[FAMILIES[row["family"]]][0]
            row["departure"]["own"] = departure(scene, row["u_after"], reference["u_after"])
    return {"engine": engine_name, "version": engine.version, "own_law": engine.own_law,
            "reference_setting": reference_setting, "rows": rows}


def cheapest_settings(result: dict) -> dict:
    """Per threshold: the setting of least mean time per impact whose worst own-law departure
    over the families is within the threshold (MuJoCo's reference run itself excluded)."""
    by_setting: dict[str, list[dict]] = {}
    for row in result["rows"]:
        by_setting.setdefault(row["setting"], []).append(row)
    candidates = []
    for label, rows in by_setting.items():
        if label == result.get("reference_setting") or any(
                "departure" not in r or r["status"] != "ok" for r in rows):
            continue
        worst = max(r["departure"]["own"] for r in rows)
        mean_time = float(np.mean([r["time_per_impact_s"] for r in rows]))
        candidates.append((mean_time, worst, label))
    table = {}
    for threshold in THRESHOLDS:
        reaching = sorted(c for c in candidates if c[1] <= threshold)
        if reaching:
            mean_time, worst, label = reaching[0]
            ties = [c[2] for c in reaching[1:] if c[0] <= mean_time * (1 + TIE_FRACTION)]
            table[f"{threshold:g}"] = {"setting": label, "time_per_impact_s": mean_time,
                                       "worst_departure": worst, "within_timing_noise": ties}
        else:
            best = min(candidates, key=lambda c: c[1]) if candidates else None
            table[f"{threshold:g}"] = {"setting": "not reachable",
                                       "best_worst_departure": best[1] if best else None,
                                       "best_setting": best[2] if best else None}
    return table


def pareto_front(points: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """Points not dominated in (time, departure), sorted by time."""
    front, best = [], math.inf
    for time_s, error in sorted(points):
        if error < best:
            front.append((time_s, error))
            best = error
    return front


def setting_label(row: dict, varying: set[str] | None = None) -> str:
    """A point's setting as a reader names it: the overrides it sweeps (``iterations=50``;
    only the ``varying`` keys when given: a time step every point shares says nothing), or
    the preset's name."""
    overrides = {key: value for key, value in (row.get("overrides") or {}).items()
                 if varying is None or key in varying}
    if not overrides:
        return str(row.get("setting") or row.get("preset") or "")
    return ", ".join(f"{key}={value:g}" if isinstance(value, float) else f"{key}={value}"
                     for key, value in overrides.items())


def varying_keys(rows: list[dict]) -> set[str]:
    """The override keys whose value differs between ``rows``."""
    seen: dict[str, set[str]] = {}
    for row in rows:
        for key, value in (row.get("overrides") or {}).items():
            seen.setdefault(key, set()).add(repr(value))
    keys = {key for key, values in seen.items() if len(values) > 1}
    # a key some rows leave at the preset varies too
    keys |= {key for key in seen if any(key not in (row.get("overrides") or {})
                                        for row in rows)}
    return keys


def write_pareto_figure(result: dict, path: Path) -> None:
    """Per family, wall time per impact against departure, one point per setting; the Pareto
    front of the departures from the engine's own law is drawn and its points are labelled
    with their setting; the legend sits below the panels, outside the data."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import LogLocator

    figure, axes = plt.subplots(1, len(FAMILIES), figsize=(4.6 * len(FAMILIES), 6.6),
                                sharey=True)
    floor = 1e-17  # departures of exactly 0 are drawn here
    varying = varying_keys(result["rows"])
    listed = 0  # the most settings listed under a panel
    for axis, family in zip(axes, FAMILIES):
        rows = [r for r in result["rows"] if r["family"] == family and "departure" in r
                and r["setting"] != result.get("reference_setting")]
        times = np.array([r["time_per_impact_s"] for r in rows]) * 1e6
        for law, style in (("poisson", dict(marker="x", color="#777777", alpha=0.6)),
                           ("stronge", dict(marker="+", color="#b8860b", alpha=0.7))):
            values = np.array([max(r["departure"][law], floor) for r in rows])
            axis.scatter(times, values, s=18, label=f"from {law} (every setting)", **style)
        own = np.array([max(r["departure"]["own"], floor) for r in rows])
        ok = np.array([r["status"] == "ok" for r in rows], dtype=bool)
        axis.scatter(times[ok], own[ok], s=24, color="#0072b2", zorder=3,
                     label=f"from its own law ({result['own_law']})")
        axis.scatter(times[~ok], own[~ok], s=24, color="#d55e00", marker="s", zorder=3,
                     label="status not ok (own law)")
        front = pareto_front(list(zip(times[ok].tolist(), own[ok].tolist())))
        if front:
            axis.step(*zip(*front), where="post", color="#0072b2", linewidth=1,
                      label="Pareto front (numbered: settings below)")
            # the front's points numbered on the plot from the fastest, their settings
            # listed under the panel
            names = []
            for time_us, value in front:
                row = next(r for r, t, v in zip(rows, times.tolist(), own.tolist())
                           if r["status"] == "ok" and (t, v) == (time_us, value))
                names.append(setting_label(row, varying))
                axis.annotate(str(len(names)), (time_us, value), fontsize=9,
                              xytext=(4, 2), textcoords="offset points",
                              color="#0072b2", fontweight="bold")
            # under the tick labels and the axis label (about 30 points), whatever the height
            listing = axis.annotate("\n".join(f"{number}  {name}" for number, name
                                              in enumerate(names, 1)),
                                    (0.0, 0.0), xycoords="axes fraction", xytext=(0, -40),
                                    textcoords="offset points", va="top", ha="left",
                                    fontsize=8.5)
            listing.set_in_layout(False)
            listed = max(listed, len(names))
        for threshold in THRESHOLDS:
            axis.axhline(threshold, color="black", linestyle=":", linewidth=0.8)
        axis.set_xscale("log")
        axis.set_yscale("log")
        axis.yaxis.set_major_locator(LogLocator(base=10, numticks=7))
        time_axis(axis, times)
        axis.set_title(family, fontsize=12)
        axis.set_xlabel("wall time per impact [µs]", fontsize=11)
        axis.tick_params(labelsize=10)
        axis.grid(True, which="major", alpha=0.3)
    axes[0].set_ylabel("departure ‖Δu‖_M / ‖u_before‖_M", fontsize=11)
    handles, labels = axes[0].get_legend_handles_labels()
    for axis in axes[1:]:  # a panel may have what the first lacks (a red point, a front)
        for handle, label in zip(*axis.get_legend_handles_labels()):
            if label not in labels:
                handles.append(handle)
                labels.append(label)
    figure.legend(handles, labels, loc="upper center", ncol=len(labels), fontsize=10,
                  frameon=False, bbox_to_anchor=(0.5, 0.955))
    figure.suptitle(f"{result['engine']} {result['version']}: time against departure per "
                    "setting (dotted: 1% and 0.1%)", fontsize=13)
    # inches, top to bottom: title and legend, panel titles, panels, tick labels and axis
    # label, the longest listing of settings (placed, not left to tight_layout, which left
    # gaps of an inch around a listing it could not see)
    above, titles, panels, labels, below = 0.8, 0.3, 3.0, 0.6, 0.15 * listed + 0.3
    height = above + titles + panels + labels + below
    width = 4.6 * len(FAMILIES)
    figure.set_size_inches(width, height)
    figure.legends[0].set_bbox_to_anchor((0.5, 1 - 0.4 / height))
    figure.subplots_adjust(left=0.75 / width, right=1 - 0.15 / width, wspace=0.08,
                           top=1 - (above + titles) / height, bottom=(labels + below) / height)
    save_figure(figure, path, "png", dpi=110)  # over a regular file only
    plt.close(figure)


def time_axis(axis, times_us: np.ndarray) -> None:
    """A log axis of wall times (µs) that names its values as numbers (``20``, ``5000``):
    1, 2 and 5 times the powers of ten when the times span less than two decades (over at
    least a factor of 2.56, which holds one of them: times within one decade may hold no
    power of ten, and so show no number), the powers of ten alone beyond (more would
    crowd)."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    finite = times_us[np.isfinite(times_us) & (times_us > 0)]
    if finite.size and finite.max() / finite.min() < 100.0:
        middle = math.sqrt(finite.max() * finite.min())
        half = max(1.6, 1.15 * math.sqrt(finite.max() / finite.min()))
        axis.set_xlim(middle / half, middle * half)
        axis.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    else:
        axis.xaxis.set_major_locator(LogLocator(base=10, numticks=6))
    axis.xaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    axis.xaxis.set_minor_formatter(NullFormatter())


# ---------------------------------------------------------------------- scaling
def impact_chunk(task: dict) -> list[list[float]]:
    """``task["impacts"]`` engine impacts of one reference scene (top-level: worker processes)."""
    engine = load_engine(task["engine"])
    scene = reference_scenes()[task["scene"]][0]
    settings = engine.settings(task["preset"])
    return [engine.run(scene, settings).u_after.tolist() for _ in range(task["impacts"])]


def worker_speedup(quick: bool) -> dict:
    """Wall time of a batch of engine impacts through run_tasks with 1 and with 2 workers."""
    installed = {}
    for name in engine_names():
        try:
            installed[name] = load_engine(name).bench_impact_seconds
        except EngineNotInstalled:
            continue
    if not installed:
        return {"skipped": "no engine installed"}
    # The slowest per impact (its class's bench_impact_seconds), so the batch is compute,
    # not pickling or start-up.
    engine_name = max(installed, key=installed.get)
    # rod-45, accurate preset
    per_impact_s = installed[engine_name]
    chunks = 16 if quick else 32
    impacts = max(1, int((2.0 if quick else 10.0) / (per_impact_s * chunks)))  # ~2 s (10 s) serial
    tasks = [{"engine": engine_name, "scene": "rod-45", "preset": "accurate",
              "impacts": impacts}] * chunks
    import os

    load_before = os.getloadavg()[0] if hasattr(os, "getloadavg") else None
    timings = {}
    results = {}
    for workers in (1, 2):
        started = time.perf_counter()
        results[workers] = run_tasks(impact_chunk, tasks, workers=workers)
        timings[workers] = time.perf_counter() - started
    return {
        "engine": engine_name, "scene": "rod-45", "preset": "accurate",
        "impacts": chunks * impacts, "local_cores": default_workers(),
        "seconds_1_worker": timings[1], "seconds_2_workers": timings[2],
        "speedup": timings[1] / timings[2], "identical_results": results[1] == results[2],
        "load_average_before": load_before,
        "note": "2-worker time includes starting the process pool; other load on the machine "
                "lowers the speed-up (see load_average_before)",
    }


# ---------------------------------------------------------------------- entry point
def format_table(report: dict) -> str:
    lines = ["Cheapest settings reaching the engine's own law (worst over families):",
             f"{'engine':9} {'own law':11} {'≤ 1%':44} {'≤ 0.1%':44}"]
    for name, entry in report["engines"].items():
        if "skipped" in entry:
            lines.append(f"{name:9} skipped: {entry['skipped'][:90]}")
            continue
        cells = []
        for threshold in THRESHOLDS:
            cell = entry["cheapest"][f"{threshold:g}"]
            if cell["setting"] == "not reachable":
                best = cell["best_worst_departure"]
                cells.append(f"not reachable (best {best:.2g})" if best is not None
                             else "not reachable")
            else:
                ties = len(cell["within_timing_noise"])
                cells.append(f"{cell['setting']} ({cell['time_per_impact_s'] * 1e6:.0f} µs"
                             + (f", ~{ties} tie)" if ties else ")"))
        lines.append(f"{name:9} {entry['own_law']:11} {cells[0]:44} {cells[1]:44}")
    scaling = report["scaling"]
    if "speedup" in scaling:
        lines.append(f"run_tasks 1 → 2 workers ({scaling['impacts']} {scaling['engine']} impacts, "
                     f"{scaling['local_cores']} cores): {scaling['seconds_1_worker']:.2f} s → "
                     f"{scaling['seconds_2_workers']:.2f} s, speed-up {scaling['speedup']:.2f}×, "
                     f"identical results: {scaling['identical_results']}")
    return "\n".join(lines)


def run(quick: bool, out_dir: Path) -> dict:
    """The speed–accuracy benchmark; writes ``pareto-*.png`` into ``out_dir``, returns the table."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    report: dict = {"quick": quick, "families": FAMILIES, "thresholds": list(THRESHOLDS),
                    "engines": {}}
    installed = []
    for name in engine_names():
        try:
            load_engine(name)
        except EngineNotInstalled as error:
            report["engines"][name] = {"skipped": str(error)}
            # an earlier run's figure would show on the bench page as this run's
            stale = out_dir / f"pareto-{name}.png"
            if stale.is_file() and not stale.is_symlink():
                stale.unlink()
            continue
        reference_label(name, quick)  # a converged engine without its point: refused now
        installed.append(name)
    for name in installed:
        progress = None if quick else progress_printer(f"speed-accuracy {name}")
        result = measure_engine(name, quick, progress=progress)
        result["cheapest"] = cheapest_settings(result)
        path = out_dir / f"pareto-{name}.png"
        write_pareto_figure(result, path)
        result["figure"] = path.name
        report["engines"][name] = result
    report["scaling"] = worker_speedup(quick)
    report["seconds"] = time.perf_counter() - started
    print(format_table(report))
    print(f"speed-accuracy: {report['seconds']:.1f} s; figures {out_dir}/pareto-*.png")
    return report
