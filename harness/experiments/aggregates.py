"""What the report shows of the Fazeli drops: aggregates only (issue 25, item 7).

The files carry no licence, so nothing here keeps a per-drop number: the fits with their
intervals, error distributions as quantiles, predicted against measured as a 2-D histogram
whose bins holding fewer than :data:`MIN_BIN_COUNT` drops are emptied (a bin of one or two
drops would give those drops away) with medians per bin of the measured value, and the
calibrated settings of each engine. Everything returned is plain JSON (numbers, lists,
dicts), written by the report beside its figures.
"""

from __future__ import annotations

import copy
import time

import numpy as np

import planar_impact as pi
from harness.engines import preset_label

from . import (
    analysis,
    cached,
    calibrate,
    calibrated_errors,
    drops_engines,
    fazeli,
    fitting,
    frames,
    metric,
)
from .analysis import quantiles
from .predict import predict

#: A bin of the predicted-against-measured histogram with fewer drops than this is emptied.
MIN_BIN_COUNT = 5
#: Objectives the laws are fitted by (both: they give different fits, docs/experiments.md).
OBJECTIVES = ("median-error", "impulse")
#: The headline fit, the one fit both ``impact-harness experiments`` (its default
#: ``--objective``) and the report lead with: the law whose predictions are set against the
#: measurements and at whose fit the engines run (the authors' own cost, which does not fit
#: friction away).
SHOWN_LAW, SHOWN_OBJECTIVE = "poisson", "impulse"

#: Paired bootstrap resamples of the comparison of Poisson with Stronge.
COMPARE_REPLICATES = 1000
#: Post-impact speeds: names and units of the predicted-against-measured panels.
SPEEDS = (("v_x'", "m/s"), ("v_y'", "m/s"), ("ω'", "rad/s"))


def density(predicted, measured, bins: int = 20, median_bins: int = 12) -> dict:
    """Predicted against measured, one quantity: a ``bins`` × ``bins`` histogram over the
    central 99 % of both (bins of fewer than :data:`MIN_BIN_COUNT` drops emptied) and, in
    ``median_bins`` bins of the measured value holding at least that many drops, the
    quartiles of the predicted one."""
    predicted, measured = np.asarray(predicted, float), np.asarray(measured, float)
    both = np.concatenate([predicted, measured])
    low, high = np.quantile(both, [0.005, 0.995])
    edges = np.linspace(low, high, bins + 1)
    counts, _, _ = np.histogram2d(measured, predicted, bins=[edges, edges])
    hidden = int(counts[(counts > 0) & (counts < MIN_BIN_COUNT)].sum())
    counts[counts < MIN_BIN_COUNT] = 0
    coarse = np.linspace(low, high, median_bins + 1)
    which = np.digitize(measured, coarse) - 1
    centres, q25, q50, q75 = [], [], [], []
    for k in range(median_bins):
        inside = predicted[which == k]
        if inside.size >= MIN_BIN_COUNT:
            centres.append(float((coarse[k] + coarse[k + 1]) / 2))
            a, b, c = np.quantile(inside, [0.25, 0.5, 0.75])
            q25.append(float(a))
            q50.append(float(b))
            q75.append(float(c))
    outside = int(np.count_nonzero((measured < low) | (measured > high)
                                   | (predicted < low) | (predicted > high)))
    return {"edges": edges.tolist(), "counts": counts.astype(int).tolist(),
            "hidden_in_sparse_bins": hidden, "outside_range": outside,
            "binned": {"measured": centres, "q25": q25, "q50": q50, "q75": q75},
            "drops": int(measured.size)}


def law_fits(target, *, replicates: int, seed: int, workers: int | None, laws=pi.LAWS,
             mus=fitting.MU_GRID, es=fitting.E_GRID) -> tuple[dict, dict]:
    """Every law fitted by each of :data:`OBJECTIVES`: (μ, e) with bootstrap intervals,
    held-out value and the normalized errors' quantiles at the fit; and per objective
    whether the data tell Poisson from Stronge (:func:`laws_apart`)."""
    drop_errors = fitting.DropErrors(target)
    fits: dict = {}
    apart: dict = {}
    for objective in OBJECTIVES:
        results = analysis.fit_laws(target, objective, laws, replicates=replicates,
                                    seed=seed, workers=workers, mus=mus, es=es)
        apart[objective] = laws_apart(target, objective, results, seed)
        fits[objective] = {}
        for law, result in results.items():
            fit, boot = result.fit, result.bootstrap
            errors, status = drop_errors(law, fit.mu, fit.e)
            normalized = np.where(status == 0, errors["median-error"], np.nan)
            fits[objective][law] = {
                "mu": fit.mu, "e": fit.e, "objective": fit.value,
                "held_out": result.held_out.held_out,
                "mu_interval": [boot.mu.low, boot.mu.high],
                "e_interval": [boot.e.low, boot.e.high],
                "replicates": boot.replicates, "confidence": boot.confidence,
                "at_window_edge": boot.at_window_edge, "on_grid_edge": fit.on_grid_edge,
                "errors": quantiles(normalized)}
    return fits, apart


def laws_apart(target, objective: str, results: dict, seed: int) -> dict | None:
    """Poisson against Stronge, each at its own fit by ``objective``: the difference of
    their objectives with its paired-bootstrap interval (:data:`COMPARE_REPLICATES`
    resamples), how far their predictions lie apart, and the verdict with its stated band
    (:func:`analysis.compare_laws`). None when either law was not fitted."""
    if not {"poisson", "stronge"} <= set(results):
        return None
    found = analysis.compare_laws(target, objective, results["poisson"].fit,
                                  results["stronge"].fit, replicates=COMPARE_REPLICATES,
                                  seed=seed)
    return {"difference": found.objective_difference,
            "interval": [float(found.interval.low), float(found.interval.high)],
            "confidence": found.confidence, "replicates": COMPARE_REPLICATES,
            "objective_of_stronge": found.objective_value,
            "prediction_gap": {"median": found.prediction_gap_median,
                               "q99": found.prediction_gap_q99},
            "median_error": found.measurement_scale, "band": analysis.PRACTICAL_BAND,
            "verdict": found.verdict()}


def compute(data: fazeli.FazeliData, *, engines=(), replicates: int = 100, seed: int = 0,
            workers: int | None = None,
            calibration_drops: int = calibrated_errors.CALIBRATION_DROPS, laws=pi.LAWS,
            mus=fitting.MU_GRID, es=fitting.E_GRID, progress=lambda text: None,
            cache=None, data_sha256: dict | None = None) -> dict:
    """The report's aggregates of ``data``: the paper's six models, every law under both
    objectives (and whether Poisson and Stronge differ; where the drops lie on Routh's
    diagram, at the shown fit's μ), Poisson's predictions against the measurements, each
    engine (loaded, with its presets) on every drop at Poisson's ``impulse`` fit, and each
    engine's calibrated (μ, e) and own settings on ``calibration_drops`` drops of the
    training half drawn with ``seed``, with intervals and a held-out error; then
    (:mod:`.calibrated_errors`) every law at its :data:`SHOWN_OBJECTIVE` fit (as the
    command's default) and every engine at its preset and at that calibration, scored on
    the held-out half, with intervals.
    ``laws`` must include :data:`SHOWN_LAW`. With ``cache`` (a result cache), the engines
    on the drops and the calibrated errors are kept there as ``impact-harness experiments``
    makes them from the same inputs (:data:`cached.ENGINES_ON_DROPS`): the command, and
    ``findings --check`` through it, read them instead of computing them again, keyed by
    the files' SHA-256 ``data_sha256`` (checked by the caller; None: ``data.hashes``; never
    kept for a copy whose files were not hashed)."""
    target = frames.in_frame(data.impacts, frames.DEFAULT_FRAME)  # as the command's default
    models = {name: quantiles(metric.normalized_error(speeds, target.speeds_after))
              for name, speeds in data.model_speeds.items()}
    progress("the laws and the six models in both frames")
    in_frames = frames.compare(data, seed=seed)
    progress("fitting every law by both objectives")
    fits, apart = law_fits(target, replicates=replicates, seed=seed, workers=workers,
                           laws=laws, mus=mus, es=es)
    shown = fits[SHOWN_OBJECTIVE][SHOWN_LAW]
    routh = analysis.routh_position(target, shown["mu"])
    shown_errors = calibrated_errors.law_errors(fitting.DropErrors(target), SHOWN_LAW,
                                                shown["mu"], shown["e"])
    predicted = predict(target, SHOWN_LAW, shown["mu"], shown["e"]).speeds_after
    densities = [density(predicted[:, k], target.speeds_after[:, k]) for k in range(3)]
    thetas, _ = drops_engines.jacobian_angles(target, data.pre_impact_angles)
    sample = {"drops": int(calibrated_errors.calibration_sample(
        len(target), seed, calibration_drops).size), "of": len(target), "seed": seed,
        "from": "training half"}
    on_drops, calibrated, engine_runs, calibrations = [], [], [], {}
    started = time.perf_counter()
    for engine in engines:
        for preset in engine.presets:
            progress(f"{engine.name} ({preset_label(engine.name, preset)}) on every drop, "
                     "then calibrated")
            run = drops_engines.run_drops(engine, preset, target, thetas, shown["mu"],
                                          shown["e"], keep_errors=True)
            engine_runs.append((engine, preset, dict(run)))  # its errors, in memory only
            errors = run.pop("per_drop_errors")
            on_drops.append({**run, "cdf": quantiles(errors),
                             "vs_reference": calibrated_errors.paired_difference(
                                 errors, shown_errors, seed=seed)})
            # on the training half of calibrated_errors' split: its held-out half scores it
            result = calibrated_errors.calibrate_engine(engine, preset, target, thetas, seed,
                                                        calibration_drops)
            calibrations[engine.name, preset] = result
            calibrated.append({"engine": engine.name, "preset": preset, "best": result.best,
                               "objective": result.best_objective, "moves": result.moves,
                               "cannot": result.cannot(), "knobs": result.knobs,
                               **calibration_uncertainty(result.uncertainty)})
    progress("every law and engine at its fitted or calibrated settings, with intervals")
    at_settings = calibrated_errors.compute(
        target, thetas, {law: {"mu": fit["mu"], "e": fit["e"]}
                         for law, fit in fits[SHOWN_OBJECTIVE].items()},  # as the command
        engine_runs, seed=seed, calibration_drops=calibration_drops,
        calibrations=calibrations)
    data_sha256 = data.hashes if data_sha256 is None else data_sha256
    if cache is not None and data_sha256:
        _keep_engines_on_drops(cache, data_sha256, shown, fits[SHOWN_OBJECTIVE], engines, seed,
                               calibration_drops, on_drops, at_settings,
                               time.perf_counter() - started, progress)
    return {"drops": len(target), "post_speeds": frames.DEFAULT_FRAME, "seed": seed,
            "replicates": replicates, "paper_models": models, "frames": in_frames,
            "laws": fits,
            "poisson_vs_stronge": apart, "routh": routh,
            "shown": {"law": SHOWN_LAW, "objective": SHOWN_OBJECTIVE, "mu": shown["mu"],
                      "e": shown["e"], "speeds": [name for name, _ in SPEEDS],
                      "units": [unit for _, unit in SPEEDS], "density": densities},
            "engines": on_drops, "calibration": {"sample": sample, "grid": "quick",
                                                 "tolerance": calibrate.TOLERANCE,
                                                 "replicates": calibrate.REPLICATES,
                                                 "confidence": calibrate.CONFIDENCE,
                                                 "results": calibrated},
            "calibrated_errors": at_settings}


def _keep_engines_on_drops(cache, data_sha256: dict, shown: dict, law_fits: dict, engines,
                           seed: int, calibration_drops: int, on_drops: list, at_settings: dict,
                           seconds: float, progress) -> None:
    """The engines on the drops and the calibrated errors kept in ``cache`` as the command
    makes them (:data:`cached.ENGINES_ON_DROPS`): its rows have no ``cdf``, its calibrated
    errors no curves (``calibrated_errors.compute(curves=False)``)."""
    key = cached.engines_on_drops_payload(
        data_sha256, frames.DEFAULT_FRAME,
        {"law": SHOWN_LAW, "objective": SHOWN_OBJECTIVE, "mu": shown["mu"], "e": shown["e"]},
        {law: [fit["mu"], fit["e"]] for law, fit in law_fits.items()},
        [[engine.name, preset] for engine in engines for preset in engine.presets], seed,
        calibration_drops, calibrated_errors.REPLICATES)
    rows = [{k: v for k, v in row.items() if k != "cdf"} for row in on_drops]
    uncurved = copy.deepcopy(at_settings)
    for row in uncurved["laws"]:
        row.pop("held_out_cdf", None)
    for row in uncurved["engines"]:
        if row["calibrated"] is not None:
            row["calibrated"].pop("cdf", None)
    cached.engines_on_drops_put(cache, key, rows, {**uncurved, "seconds": seconds}, seconds,
                                progress)


def calibration_uncertainty(found: calibrate.Uncertainty | None) -> dict:
    """A calibration's intervals and held-out error, as plain JSON (None: no cell scored):
    the best objective's interval, each setting's interval (values tried), the share of
    resamples that re-picked the best cell, and the split's in-sample and held-out values
    with the fitting half's pick."""
    if found is None:
        return {"objective_interval": None, "settings_interval": None, "agree": None,
                "held_out": None}
    scored = bool(found.settings)
    return {"objective_interval": ([found.objective.low, found.objective.high] if scored
                                   else None),
            "settings_interval": found.settings if scored else None,
            "agree": found.agree if scored else None, "unscored": found.unscored,
            "held_out": {"in_sample": _finite(found.in_sample),
                         "held_out": _finite(found.held_out),
                         "fitting_drops": int(sum(found.split.held_out_drops[1:])),
                         "held_out_drops": int(found.split.held_out_drops[0]),
                         "picked": found.split_best[0]}}


def _finite(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None
