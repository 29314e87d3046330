"""``impact-harness experiments``: the laws against measured impacts.

Prints, for the Fazeli et al. (2017) drops when a copy is given, the paper's six models
scored by its metric, every law fitted by the named objective (held-out error, bootstrap
intervals, collision types), Poisson against Stronge, and where the drops lie on Routh's
diagram; then the Kharaz et al. (2001) curves for every law beside the digitised points.
Only aggregates are printed or written: the Fazeli data carry no licence.
Without a copy it says where to get one and goes on with the rest (exit 0).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import dataclass

import numpy as np

import planar_impact as pi
from harness import bounds
from harness.engines import EngineNotInstalled, engine_names, load_engine, preset_label
from harness.scene import ellipse
from harness.store.cache import ResultCache
from harness.store.files import output_file_problem, write_text_atomically

from . import (
    aggregates,
    analysis,
    cached,
    calibrated_errors,
    drops_engines,
    engine_curves,
    fazeli,
    fitting,
    frames,
    kharaz,
    metric,
    registry,
)

KHARAZ_ANGLES = (10, 20, 30, 40, 50, 60, 70, 80)
GAP_MUS = (0.05, 0.1, 0.2, 0.3, 0.5, 1.0)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--data", metavar="DIR", default=None,
                        help="directory holding the Fazeli et al. 2017 files (default: "
                             f"${registry.FAZELI_2017.env_var})")
    parser.add_argument("--objective", choices=sorted(metric.OBJECTIVES),
                        default=aggregates.SHOWN_OBJECTIVE,
                        help="what the fit minimises (default "
                             f"{aggregates.SHOWN_OBJECTIVE}: {aggregates.SHOWN_LAW}'s fit by it "
                             "is the headline fit the engines run at, here and in the "
                             "report): " + "; ".join(
                                 f"{name}: {text}" for name, text in metric.OBJECTIVES.items()))
    parser.add_argument("--post-speeds", choices=tuple(frames.FRAMES),
                        default=frames.DEFAULT_FRAME,
                        help="the frame of the post-impact speeds the laws are fitted to and "
                             "every law, model and engine is scored against: " + "; ".join(
                                 f"{name}: {text}" for name, text in frames.FRAMES.items())
                             + f" (default {frames.DEFAULT_FRAME}; the command prints both "
                             "frames side by side and why)")
    parser.add_argument("--replicates", type=bounds.option("replicates"), default=200,
                        help="bootstrap replicates (default 200)")
    parser.add_argument("--seed", type=bounds.option("seed"),
                        default=0, help="seed of folds and bootstrap")
    parser.add_argument("--workers", type=bounds.option("workers"), default=None,
                        help="forked workers for the law fits (default: the local cores)")
    parser.add_argument("--engines", default="all",
                        help="engines for the Kharaz curves: 'all' (the installed ones), "
                             "'none', or names separated by commas")
    parser.add_argument("--json", metavar="PATH", default=None,
                        help="also write the aggregates (with the data's SHA-256) as JSON")
    parser.add_argument("--no-cache", action="store_true",
                        help="compute everything again (by default a rerun with the same data, "
                             "code, installed versions and options reads the result cache)")


def option_problem(args) -> str | None:
    """A ``--json`` that cannot be written (:func:`harness.store.files.output_file_problem`:
    a link, a missing or read-only directory), as one line; None when it can. Checked before
    any work (the counts were bounded by their argparse types, harness.bounds.option)."""
    if args.json is not None:
        reason = output_file_problem(args.json)
        if reason is not None:
            return f"--json {args.json}: {reason}"
    return None


def main(args) -> int:
    problem = option_problem(args)
    if problem is not None:
        print(f"impact-harness experiments: {problem}", file=sys.stderr)
        return 2
    registered = engine_names()  # those registered at run time too
    engines = (list(registered) if args.engines == "all" else [] if args.engines == "none"
               else [name.strip() for name in args.engines.split(",") if name.strip()])
    unknown = [name for name in engines if name not in registered]
    if unknown:
        print(f"impact-harness experiments: --engines: unknown {', '.join(unknown)}; allowed: "
              f"all, none or {', '.join(registered)}", file=sys.stderr)
        return 2
    cache = None if args.no_cache else ResultCache()
    problem = cached.cache_problem(cache)
    if problem is not None:
        print(f"impact-harness experiments: the cache {cache.root}: {problem} (or --no-cache)",
              file=sys.stderr)
        return 2
    try:
        directory = registry.locate(registry.FAZELI_2017, args.data)
        data = fazeli.load(directory)
    except registry.DataMissing as missing:
        print(f"Fazeli et al. 2017: skipped. {missing}\n")
        data = None
    except registry.DataInvalid as invalid:
        print(f"impact-harness experiments: {invalid}", file=sys.stderr)
        return 2
    found = computed_once(args, data, engines, cache)
    output = found["output"]
    if data is not None:  # this copy's place, not the one a cached run read (same hashes)
        output["fazeli2017"]["provenance"] = cached.json_plain(data.provenance())
    if args.json:  # atomically, never through a link (checked before the work too)
        write_text_atomically(args.json, json.dumps(output, indent=1) + "\n")
    return 0


def computed_once(args, data: fazeli.FazeliData | None, engines: list[str],
                  cache: ResultCache | None, echo: bool = True) -> dict:
    """``{"text": what the command prints, "output": its --json document, "seconds"}``,
    read from ``cache`` when these options, data, code and versions were computed before
    (:mod:`.cached`); ``echo``: print the text."""
    progress = cached.Progress("impact-harness experiments")
    settings = {"objective": args.objective, "post_speeds": args.post_speeds,
                "replicates": args.replicates, "seed": args.seed, "engines": engines}
    return cached.printed_once(
        cache, cached.payload("experiments", settings, None if data is None else data.hashes),
        lambda: {"output": compute(args, data, engines, progress, cache)}, progress, echo)


def default_options() -> argparse.Namespace:
    """The command's options when none is given (what the texts' stated numbers come
    from: harness/report/experiments.py, ``stated_numbers``)."""
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    return parser.parse_args([])


def compute(args, data: fazeli.FazeliData | None, engines: list[str], progress,
            cache: ResultCache | None = None) -> dict:
    """Everything the command prints (printed as it goes) and its ``--json`` document, as
    plain JSON. The engines on the drops are read from ``cache`` when the report (or an
    earlier run) made them from the same inputs (:data:`cached.ENGINES_ON_DROPS`)."""
    output: dict = {"objective": args.objective, "objective_means": metric.OBJECTIVES[
        args.objective], "post_speeds": args.post_speeds}
    if data is not None:
        output["fazeli2017"], target, fit = fazeli_section(data, args, progress)
    runs = run_engines(engines, progress)  # each engine loaded, each preset's curves, once
    if data is not None:
        rows, calibrated = engines_on_drops(runs, data, target, fit, output["fazeli2017"]["laws"],
                                            args, cache, progress)
        output["fazeli2017"]["engines_on_drops"] = rows
        output["fazeli2017"]["calibrated_errors"] = calibrated
    output["ellipse_polygons"] = ellipse_section(data)
    progress("each engine's ellipse against the true one")
    output["ellipse_polygons"]["engines"] = ellipse_engines_section(
        [run.engine if run.engine is not None else run.name for run in runs])
    output["kharaz2001"] = kharaz_section()
    output["kharaz2001"]["engines"] = kharaz_engines_table(runs)
    return cached.json_plain(output)


def fazeli_section(data: fazeli.FazeliData, args, progress=lambda text: None):
    """The drops' part of the output without the engines; returns it, the impacts the laws
    were fitted to and Poisson's fit (at which the engines run)."""
    impacts = data.impacts
    print(f"## Fazeli et al. 2017: {len(impacts)} processed drops of {fazeli.RAW_DROPS}")
    for name, digest in data.hashes.items():
        print(f"- {name}: SHA-256 {digest} (matches the published file)")
    print("- raw drops flagged: " + ", ".join(f"{k} {v}" for k, v in data.flag_counts().items()))
    target = frames.in_frame(impacts, args.post_speeds)
    print(f"\n### The paper's metric on its six models (post-impact speeds: "
          f"{args.post_speeds})\n")
    models = analysis.paper_models(data.model_speeds, target)
    print("| model | median | q25 | q75 | q90 |\n|---|---:|---:|---:|---:|")
    for name, summary in models.items():
        print(f"| {name} | {summary['q50']:.3f} | {summary['q25']:.3f} | {summary['q75']:.3f} "
              f"| {summary['q90']:.3f} |")
    in_frames = frames.compare(data, seed=args.seed, progress=progress)
    print("\n### Laws and models in one frame, both frames\n")
    print("\n".join(frames.markdown(in_frames)))
    progress(f"fitting every law by {args.objective} ({args.replicates} bootstrap replicates)")
    started = time.perf_counter()
    laws = analysis.fit_laws(target, args.objective, replicates=args.replicates,
                             seed=args.seed, workers=args.workers)
    seconds = time.perf_counter() - started
    print(f"\n### Every law fitted: objective {args.objective} "
          f"({metric.OBJECTIVES[args.objective]}); post-impact speeds {args.post_speeds}\n")
    print(f"Grid μ 0..1 × e 0..1 step 0.01, refined to 0.001; 5-fold held-out by drop; "
          f"{args.replicates} bootstrap replicates (95%, local grid step 0.002); "
          f"{seconds:.1f} s.\n")
    print("| law | μ | e | objective | held-out | μ 95% | e 95% | median error | q90 error "
          "| collision types |\n|---|---:|---:|---:|---:|---|---|---:|---:|---|")
    for law, result in laws.items():
        fit, boot = result.fit, result.bootstrap
        clipped = f" ({boot.at_window_edge} clipped)" if boot.at_window_edge else ""
        edge = " (grid edge)" if fit.on_grid_edge else ""
        types = ", ".join(f"{t}: {c}" for t, c in sorted(result.collision_types.items()))
        print(f"| {law} | {fit.mu:.3f}{edge} | {fit.e:.3f} | {fit.value:.4g} "
              f"| {result.held_out.held_out:.4g} | {boot.mu.low:.3f}–{boot.mu.high:.3f}{clipped} "
              f"| {boot.e.low:.3f}–{boot.e.high:.3f} | {result.errors['q50']:.3f} "
              f"| {result.errors['q90']:.3f} | {types} |")
    print("\nEach drop's own best (μ, e) on the grid, quartiles (a single drop rarely pins "
          "both):\n")
    for law, result in laws.items():
        own = result.per_drop
        print(f"- {law}: μ {own['mu']['q25']:.2f} / {own['mu']['q50']:.2f} / "
              f"{own['mu']['q75']:.2f}; e {own['e']['q25']:.2f} / {own['e']['q50']:.2f} / "
              f"{own['e']['q75']:.2f}")
    progress("Poisson against Stronge (paired bootstrap)")
    difference = analysis.compare_laws(target, args.objective, laws["poisson"].fit,
                                       laws["stronge"].fit, seed=args.seed)
    print(f"\n### Poisson against Stronge\n\nobjective(poisson) − objective(stronge) = "
          f"{difference.objective_difference:.3g}, 95% interval "
          f"{difference.interval.low:.3g} to {difference.interval.high:.3g} (paired bootstrap, "
          "1000 replicates); their predictions of the centre's velocity differ by "
          f"{difference.prediction_gap_median:.2%} of |v| (median drop), "
          f"{difference.prediction_gap_q99:.2%} (99th percentile), against a median error of "
          f"{difference.measurement_scale:.1%} of either law.")
    print(f"Verdict: {difference.verdict()}.")
    fixed_e = laws["poisson"].fit.e
    gaps = analysis.law_gap(target, "poisson", "stronge", GAP_MUS, fixed_e)
    print(f"At the same settings (e {fixed_e:.3f}) their predictions differ by (median / 99th "
          "percentile of drops, % of |v|): " + "; ".join(
              f"μ {mu:g}: {g['median']:.2%} / {g['q99']:.2%}" for mu, g in gaps.items()))
    routh = analysis.routh_position(target, laws["poisson"].fit.mu)
    print("\n### Where the drops lie on Routh's diagram (Poisson's fitted μ)\n")
    print("incidence |v_t|/|v_n| quartiles " + ", ".join(
        f"{k} {v:.3f}" for k, v in routh["incidence_ratio"].items())
        + f"; μ|m_nt|/m_nn {', '.join(f'{k} {v:.4f}' for k, v in routh['mu_coupling'].items())}"
        f"; m_nt opposes the slip in {routh['coupling_opposes_slip']} of {routh['drops']} drops."
        " Collision types (Routh's regions) per law in the table above.")
    headline = laws[aggregates.SHOWN_LAW].fit
    shared = (args.objective == aggregates.SHOWN_OBJECTIVE
              and args.post_speeds == frames.DEFAULT_FRAME)
    print(f"\n### The fit the engines run at: {aggregates.SHOWN_LAW} by {args.objective}, μ "
          f"{headline.mu:.3f}, e {headline.e:.3f} ({args.post_speeds} speeds)\n\n"
          + ("The headline fit: the report's figures and engines use the same." if shared else
             f"Not the headline fit (the defaults: {aggregates.SHOWN_LAW} by "
             f"{aggregates.SHOWN_OBJECTIVE} on {frames.DEFAULT_FRAME} speeds), which the "
             "report shows."))
    return ({"provenance": data.provenance(), "paper_models": models, "frames": in_frames,
             "headline": {"law": aggregates.SHOWN_LAW, "objective": args.objective,
                          "post_speeds": args.post_speeds, "mu": headline.mu,
                          "e": headline.e},
             "laws": {law: _law_dict(result) for law, result in laws.items()},
             "poisson_vs_stronge": difference, "poisson_stronge_gap": gaps, "routh": routh,
             "fit_seconds": seconds}, target, headline)


def _law_dict(result: analysis.LawResult) -> dict:
    boot = result.bootstrap
    return {"fit": result.fit, "held_out": result.held_out,
            "bootstrap": {"replicates": boot.replicates, "confidence": boot.confidence,
                          "mu": boot.mu, "e": boot.e, "value": boot.value, "step": boot.step,
                          "at_window_edge": boot.at_window_edge},
            "errors": result.errors, "collision_types": result.collision_types,
            "per_drop_fits": result.per_drop, "unsolved_cells": result.unsolved_cells}


@dataclass(frozen=True)
class EngineRuns:
    """One engine's runs: per preset its Kharaz curves; ``missing`` says why it did not run
    (not installed)."""

    name: str
    missing: str | None
    presets: tuple = ()  # (preset, engine_curves.EngineCurves)
    engine: object = None  # the loaded engine (None when missing)


def run_engines(engines: list[str], progress=lambda text: None) -> list[EngineRuns]:
    """Each engine loaded once and each of its presets run at the Kharaz incidences."""
    angles = np.array(KHARAZ_ANGLES, dtype=float)
    runs = []
    for name in engines:
        try:
            engine = load_engine(name)
        except EngineNotInstalled as missing:
            runs.append(EngineRuns(name, str(missing)))
            continue
        presets = []
        for preset in engine.presets:
            progress(f"{name} ({preset_label(name, preset)}): the Kharaz curves")
            presets.append((preset, engine_curves.engine_curves(engine, preset, angles)))
        runs.append(EngineRuns(name, None, tuple(presets), engine))
    return runs


def engines_on_drops(runs: list[EngineRuns], data: fazeli.FazeliData, target, fit,
                     laws: dict, args, cache: ResultCache | None,
                     progress=lambda text: None) -> tuple[list[dict], dict]:
    """Every installed engine and preset on every drop at the headline ``fit``, beside that
    law, and every engine and law at its fitted or calibrated settings (the laws' fits
    ``laws``), printed as two tables; returned as plain JSON. Read from ``cache`` when made
    before from the same inputs, by the report or this command
    (:data:`cached.ENGINES_ON_DROPS`), else computed and kept there."""
    thetas, residual = drops_engines.jacobian_angles(target, data.pre_impact_angles)
    installed = [run for run in runs if run.missing is None]
    key = cached.engines_on_drops_payload(
        data.hashes, args.post_speeds,
        {"law": fit.law, "objective": fit.objective, "mu": fit.mu, "e": fit.e},
        {law: [law_fit["fit"].mu, law_fit["fit"].e] for law, law_fit in laws.items()},
        [[run.name, preset] for run in installed for preset, _ in run.presets], args.seed,
        calibrated_errors.CALIBRATION_DROPS, calibrated_errors.REPLICATES)
    if not data.hashes:  # files not hashed: no key would tell this copy from another
        cache = None
    found = cached.engines_on_drops_get(cache, key)
    if found is not None:
        progress(f"the engines on the drops: read from the cache (computed in "
                 f"{found['seconds']:.0f} s)")
    else:
        started = time.perf_counter()
        law = calibrated_errors.law_errors(fitting.DropErrors(target), fit.law, fit.mu, fit.e)
        rows, engine_runs = [], []
        for run in installed:
            for preset, _ in run.presets:
                progress(f"{run.name} ({preset_label(run.name, preset)}): every drop")
                result = drops_engines.run_drops(run.engine, preset, target, thetas, fit.mu,
                                                 fit.e, keep_errors=True)
                engine_runs.append((run.engine, preset, dict(result)))
                errors = result.pop("per_drop_errors")  # in memory only: never kept
                rows.append({**result, "vs_reference": calibrated_errors.paired_difference(
                    errors, law, seed=args.seed)})
        calibrated = calibrated_errors_table(engine_runs, target, thetas, laws, args, progress)
        found = cached.engines_on_drops_put(cache, key, rows, calibrated,
                                            time.perf_counter() - started, progress)
    drops_engines_table(runs, found["rows"], fit, residual)
    print_calibrated_errors(found["calibrated"], args)
    return found["rows"], found["calibrated"]


def drops_engines_table(runs: list[EngineRuns], rows: list[dict], fit, residual) -> None:
    """Every engine and preset on every drop at the headline fit (μ, e), printed from its
    ``rows`` (in the order of ``runs``' installed engines and presets), each beside that
    law on the drops it scored (paired bootstrap) with the drops it lost."""
    if not runs:
        return
    print(f"\n### The engines on the drops (μ {fit.mu:.3f}, e {fit.e:.3f}: {fit.law}'s fit "
          f"by {fit.objective})\n")
    print(f"Each drop the ellipse (MuJoCo's ellipsoid, elsewhere the placed "
          f"{drops_engines.VERTICES}-gon) at the angle of its published "
          f"Jacobian (contact within {residual.max() * 1e3:.1g} mm of it); flagged runs are "
          f"counted with their reason, never scored. Each engine's median beside {fit.law}'s "
          "at the same (μ, e) on the drops it scored, their difference (95% intervals, "
          f"{calibrated_errors.REPLICATES} paired bootstrap resamples), and the drops it lost "
          f"with {fit.law}'s median error on them.\n")
    print(f"| engine | preset | single impacts | flagged (reason: drops) | median error | "
          f"{fit.law}, same drops | difference | lost ({fit.law}'s median on them) | q90 error "
          "|\n|---|---|---:|---|---:|---:|---:|---:|---:|")
    remaining = iter(rows)
    for run in runs:
        if run.missing is not None:
            print(f"| {run.name} | — | not installed: {run.missing} | | | | | |")
            continue
        for preset, _ in run.presets:
            result = next(remaining)
            counts = dict(result["verdicts"])
            ok = counts.pop("ok", 0)
            flagged = ", ".join(f"{k}: {v}" for k, v in counts.items()) or "none"
            errors = result["errors"]
            q90 = "—" if not errors["drops"] else f"{errors['q90']:.3f}"
            print(f"| {run.name} | {preset_label(run.name, preset)} | {ok} | {flagged} | "
                  + " | ".join(calibrated_errors.paired_cells(result["vs_reference"]))
                  + f" | {q90} |")


def calibrated_errors_table(engine_runs: list, target, thetas, laws: dict, args,
                            progress=lambda text: None) -> dict:
    """Every engine at its preset and at its calibrated settings, every law at its fit,
    with intervals (:mod:`.calibrated_errors`; ``engine_runs`` ``[(engine, preset, run)]``
    with each run's per-drop errors): the aggregates."""
    started = time.perf_counter()
    found = calibrated_errors.compute(
        target, thetas, {law: {"mu": law_fit["fit"].mu, "e": law_fit["fit"].e}
                         for law, law_fit in laws.items()}, engine_runs, seed=args.seed,
        curves=False, progress=progress)  # 101 quantiles of a few drops would give them
    # away; no figure here
    found["seconds"] = time.perf_counter() - started
    return found


def print_calibrated_errors(found: dict, args) -> None:
    """The aggregates of :func:`calibrated_errors_table`, printed."""
    print(f"\n### Every engine and law at its fitted or calibrated settings, with intervals "
          f"({found['seconds']:.1f} s)\n\nAt preset: every drop at the engines' (μ, e) above; "
          f"the laws' fit to all drops by {args.objective}, to the training half by "
          f"{calibrated_errors.OBJECTIVE}.")
    print("\n".join(calibrated_errors.markdown(found, preset_label)))


def ellipse_section(data: fazeli.FazeliData | None) -> dict:
    """The geometric error of standing a polygon in for the ellipse (engines other than
    MuJoCo take no ellipse), and the data's Jacobians against the pre-impact angle."""
    a, b = fazeli.SEMI_AXES
    print("\n## The ellipse as a polygon (for the engines)\n")
    print("| vertices | shape gap mm | fixed: moment arm error mm | fixed: height error mm "
          "| placed: moment arm error mm | placed: clearance to a 2nd contact mm |\n"
          "|---:|---:|---:|---:|---:|---:|")
    rows = [ellipse.moment_arm_error(a, b, n) for n in (8, 16, 32, 64)]
    for row in rows:
        print(f"| {row['vertices']} | {row['shape_gap'] * 1e3:.3f} | "
              f"{row['fixed_moment_arm'] * 1e3:.3f} | {row['fixed_height'] * 1e3:.3f} | "
              f"{row['placed_moment_arm'] * 1e3:.1g} | {row['placed_clearance_min'] * 1e3:.3f} |")
    section: dict = {"polygons": rows}
    if data is not None:
        theta = data.pre_impact_angles
        wn, wt = ellipse.jacobians(theta, a, b)
        gap = np.hypot(wn[:, 2] - data.impacts.wn[:, 2], wt[:, 2] - data.impacts.wt[:, 2])
        section["jacobian_vs_pre_angle_mm"] = {
            "median": float(np.median(gap) * 1e3), "q99": float(np.quantile(gap, 0.99) * 1e3),
            "max": float(np.max(gap) * 1e3)}
        print("\nThe published Jacobians (pose one frame before impact) against the lowest point "
              "at the pre-impact angle: the contact points lie "
              f"{np.median(gap) * 1e3:.2f} mm apart on the median drop, "
              f"{np.quantile(gap, 0.99) * 1e3:.2f} mm at the 99th percentile, "
              f"{np.max(gap) * 1e3:.2f} mm at most.")
    return section


def ellipse_engines_section(engines: list) -> list[dict]:
    """Each engine's ellipse (MuJoCo's ellipsoid, else the placed 8-gon) against the true
    one (``drops_engines.contact_error_table``)."""
    print("\n## Each engine's ellipse against the true one\n")
    print(f"{len(drops_engines.ARM_ANGLES)} angles, every 5° over half a turn; largest error "
          "over the single impacts (over every run in brackets when larger), mm.\n")
    rows, results = drops_engines.contact_error_table(engines)
    print("\n".join(rows))
    return results


def kharaz_section() -> dict:
    print(f"\n## Kharaz, Gorham & Salman 2001: 5 mm alumina sphere at {kharaz.SPEED} m/s "
          f"(μ {kharaz.MU}, e {kharaz.E})\n")
    limit = kharaz.sticking_limit_deg()
    print(f"Rigid disk, I = 2/5 m r²: rolling at separation below {limit:.1f}°"
          " (below it the real sphere's tangential compliance matters, which no rigid law "
          "has). m_nt = 0 here, so every law gives the same curve.")
    print(f"Measured points: {kharaz.SOURCE}; checked against {kharaz.CROSS_CHECK_SOURCE}.\n")
    angles = np.array(KHARAZ_ANGLES, dtype=float)
    curves = {law: kharaz.curves(law, angles) for law in pi.LAWS}
    print("| incidence ° | " + " | ".join(f"{law} e_t / rebound° / spin" for law in pi.LAWS)
          + " |\n|---:|" + "---|" * len(pi.LAWS))
    for k, angle in enumerate(angles):
        print(f"| {angle:.0f} | " + " | ".join(
            f"{c.tangential_restitution[k]:.3f} / {c.rebound_deg[k]:.1f} / {c.spin[k]:.0f}"
            for c in curves.values()) + " |")
    names = {"tangential_restitution": "tangential restitution", "rebound_deg": "rebound °",
             "spin": "forward spin rad/s"}
    print("\nMeasured against the rigid laws at the measured incidences (every law agrees):\n")
    print("| quantity | incidence ° | measured | rigid laws | regime |\n|---|---:|---:|---:|---|")
    for quantity in kharaz.QUANTITIES:
        measured = kharaz.MEASURED[quantity]
        rigid = getattr(kharaz.curves("poisson", measured.incidence_deg), quantity)
        for angle, value, law_value in zip(measured.incidence_deg, measured.values, rigid):
            regime = "sliding" if angle > limit else "rolls at separation (compliance)"
            digits = {"tangential_restitution": 3, "rebound_deg": 1, "spin": 0}[quantity]
            print(f"| {names[quantity]} | {angle:.1f} | {value:.{digits}f} "
                  f"| {law_value:.{digits}f} | {regime} |")
    return {"citation": registry.KHARAZ_2001.citation, "points_source": kharaz.SOURCE,
            "cross_check_source": kharaz.CROSS_CHECK_SOURCE, "sticking_limit_deg": limit,
            "curves": {law: {"incidence_deg": c.incidence_deg,
                             "tangential_restitution": c.tangential_restitution,
                             "rebound_deg": c.rebound_deg, "spin": c.spin}
                       for law, c in curves.items()},
            "measured": kharaz.MEASURED}


def kharaz_engines_table(runs: list[EngineRuns]) -> list:
    """The Kharaz curves through each engine and preset, printed; flagged runs show their
    reason."""
    if not runs:
        return []
    angles = np.array(KHARAZ_ANGLES, dtype=float)
    print("\n### The Kharaz curves through the engines (e_t / rebound° / spin rad/s; a flagged "
          "run shows the check it failed)\n")
    print("| engine | preset | " + " | ".join(f"{a:.0f}°" for a in angles) + " |\n|---|---|"
          + "---|" * angles.size)
    results = []
    for run in runs:
        if run.missing is not None:
            print(f"| {run.name} | — | not installed: {run.missing} |")
            continue
        for preset, curves in run.presets:
            cells = [f"{curves.tangential_restitution[k]:.3f} / {curves.rebound_deg[k]:.1f} / "
                     f"{curves.spin[k]:.0f}" if verdict == "ok" else f"flagged: {verdict}"
                     for k, verdict in enumerate(curves.verdicts)]
            print(f"| {run.name} | {preset_label(run.name, preset)} | " + " | ".join(cells)
                  + " |")
            results.append(curves)
    return results


