"""Error distributions on the Fazeli drops at every law's fit and at every engine's preset
and calibrated settings, each with an interval (issue 25, 'Done when').

The drops are split by drop into two halves with a seed (:func:`fitting.fold_splits`): a
training half and a held-out half. Per engine and preset:

* *at the preset*: the engine's runs on every drop at the (μ, e) the caller ran it at (a
  law's fit), its preset's own settings untouched;
* *at calibrated settings*: :func:`calibrate.calibrate` against the measured drops on a
  seeded sample of :data:`CALIBRATION_DROPS` drops of the training half picks the pair's
  (μ, e) and the engine's own knobs; the engine then runs at that pick on every held-out
  drop. An engine calibrate finds no pick for (no cell with single impacts on half of the
  drops, or no knob that moves the error) is reported as "cannot be calibrated" with that
  reason and keeps its preset row;
* beside each, the difference of its median error from Poisson's on the same drops
  (at the same (μ, e) for the preset; fitted to the training half on :data:`LAW_MUS` ×
  :data:`LAW_ES`, refined, for the calibrated settings), with a paired bootstrap.

Per law: its median error at the caller's fit on every drop, and at its fit to the training
half on the held-out half, with the paired difference from Poisson there.

Every median has the 95 % percentile interval of :data:`REPLICATES` bootstrap resamples of
its drops (:func:`fitting.resampled_rows`, :func:`fitting.percentile_interval`, the law
fits' own resampling). Flagged engine runs are counted with their reason and never scored.
Only aggregates leave this module (medians, intervals, counts, quantile curves): the
per-drop errors stay in memory.
"""

from __future__ import annotations

import numpy as np

from harness.engines import preset_label

from . import analysis, calibrate, drops_engines, fitting
from .records import MeasuredImpacts

#: Bootstrap resamples behind every interval here, and the intervals' confidence.
REPLICATES = 1000
CONFIDENCE = 0.95
#: Training drops an engine is calibrated on: a seeded sample of the training half. Every
#: cell of the calibration grid runs the engine on each of them (MuJoCo's grid has 27 cells,
#: and its `accurate` preset with a `solref` time constant of 0.02 s takes some 0.15 s a
#: drop), so the sample is small; the pick is then scored on the whole held-out half.
CALIBRATION_DROPS = 12
#: The laws' fit to the training half: this quick grid, refined ten times finer around its
#: best cell (:func:`fitting.fit`). Every law's best fit to these drops is frictionless, so
#: μ = 0 is on it.
LAW_MUS = (0.0, 0.1, 0.3)
LAW_ES = tuple(np.round(np.linspace(0.0, 1.0, 11), 2))
#: The law every other result is set against, drop by drop.
REFERENCE_LAW = "poisson"
#: What the calibration and the laws' training fit minimise.
OBJECTIVE = "median-error"


def median_interval(errors, replicates: int = REPLICATES, seed: int = 0,
                    confidence: float = CONFIDENCE) -> dict:
    """The median of the finite per-drop ``errors`` (NaN: flagged or unsolved, left out)
    with the percentile interval of its bootstrap over those drops; ``scored`` counts
    them (no median and no interval when none)."""
    errors = np.asarray(errors, dtype=float)
    scored = errors[np.isfinite(errors)]
    if scored.size == 0:
        return {"median": None, "interval": None, "scored": 0}
    medians = [np.median(scored[rows])
               for rows in fitting.resampled_rows(scored.size, replicates, seed)]
    found = fitting.percentile_interval(medians, confidence)
    return {"median": float(np.median(scored)), "interval": [found.low, found.high],
            "scored": int(scored.size)}


def paired_difference(errors, reference, replicates: int = REPLICATES, seed: int = 0,
                      confidence: float = CONFIDENCE) -> dict | None:
    """median(``errors``) − median(``reference``) over the drops where both are scored,
    with the percentile interval of a paired bootstrap (the same resampled drops for
    both); beside it each median on those drops with its interval from the same resamples
    (``median``, ``reference``), and the drops ``errors`` loses (NaN: flagged) where the
    reference is scored, with the reference's median error on them (``lost``): an engine's
    median over the drops it keeps is set beside the law's on the very same drops, never
    against the law's on all of them. None when no drop is scored by both."""
    errors, reference = np.asarray(errors, dtype=float), np.asarray(reference, dtype=float)
    both = np.isfinite(errors) & np.isfinite(reference)
    a, b = errors[both], reference[both]
    if a.size == 0:
        return None
    resampled = [(np.median(a[rows]), np.median(b[rows]))
                 for rows in fitting.resampled_rows(a.size, replicates, seed)]
    medians = np.array(resampled)
    found = fitting.percentile_interval(medians[:, 0] - medians[:, 1], confidence)
    own, other = (fitting.percentile_interval(medians[:, k], confidence) for k in (0, 1))
    lost = reference[~np.isfinite(errors) & np.isfinite(reference)]
    return {"difference": float(np.median(a) - np.median(b)),
            "interval": [found.low, found.high], "drops": int(a.size),
            "median": {"median": float(np.median(a)), "interval": [own.low, own.high]},
            "reference": {"median": float(np.median(b)), "interval": [other.low, other.high]},
            "lost": {"drops": int(lost.size),
                     "reference_median": float(np.median(lost)) if lost.size else None}}


def law_errors(drop_errors: fitting.DropErrors, law: str, mu: float, e: float) -> np.ndarray:
    """The paper's normalized error per drop of ``law`` at (μ, e); NaN where unsolved."""
    errors, status = drop_errors(law, mu, e)
    return np.where(status == 0, errors[OBJECTIVE], np.nan)


def training_fit(impacts: MeasuredImpacts, law: str) -> fitting.Fit:
    """``law`` fitted to ``impacts`` by :data:`OBJECTIVE` on the quick grid, refined."""
    drop_errors = fitting.DropErrors(impacts)
    table = fitting.error_table(drop_errors, law, LAW_MUS, LAW_ES)
    return fitting.fit(drop_errors, table, OBJECTIVE)


def _flagged(verdicts: dict) -> dict:
    return {reason: count for reason, count in verdicts.items() if reason != "ok"}


def split(drops: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The training and held-out rows of ``drops`` drops (two halves by drop, seeded:
    the first fold of :func:`fitting.fold_splits` is held out), each in increasing order."""
    training, held = fitting.fold_splits(drops, 2, seed)[0]
    return np.sort(training), np.sort(held)


def calibration_sample(drops: int, seed: int, count: int = CALIBRATION_DROPS) -> np.ndarray:
    """The rows an engine is calibrated on: ``count`` of the training half of ``drops``,
    drawn with ``seed`` (:func:`calibrate.sample_rows`)."""
    training, _ = split(drops, seed)
    return training[calibrate.sample_rows(training.size, count, seed)]


def calibrate_engine(engine, preset: str, target: MeasuredImpacts, thetas, seed: int,
                     count: int = CALIBRATION_DROPS, replicates: int = calibrate.REPLICATES,
                     progress=lambda text: None) -> calibrate.Calibration:
    """``engine`` under ``preset`` calibrated to the drops of :func:`calibration_sample`."""
    rows = calibration_sample(len(target), seed, count)
    return calibrate.calibrate(engine, preset, target.subset(rows), np.asarray(thetas)[rows],
                               "data", sample={"drops": int(rows.size), "of": len(target),
                                               "seed": seed, "from": "training half"},
                               replicates=replicates, seed=seed, progress=progress)


def compute(target: MeasuredImpacts, thetas, law_fits: dict, engine_runs, *, seed: int = 0,
            replicates: int = REPLICATES, calibration_drops: int = CALIBRATION_DROPS,
            calibrations: dict | None = None, curves: bool = True,
            progress=lambda text: None) -> dict:
    """The aggregates: ``law_fits`` maps each law to its fit ``{"mu", "e"}`` on every drop
    (it must hold :data:`REFERENCE_LAW`); ``engine_runs`` is ``[(engine, preset, run)]``
    with ``run`` a :func:`drops_engines.run_drops` result on every drop of ``target``
    made with ``keep_errors``; its per-drop errors are read, never kept. ``calibrations``:
    ``(engine name, preset) -> Calibration`` made already by :func:`calibrate_engine` with
    the same ``seed`` and ``calibration_drops``; the others are made here. ``curves``:
    keep the held-out error distributions as quantile curves (for a figure)."""
    if REFERENCE_LAW not in law_fits:
        raise ValueError(f"law_fits: must hold {REFERENCE_LAW!r}; has {', '.join(law_fits)}")
    training, held = split(len(target), seed)
    calibrations = dict(calibrations or {})
    on_held = target.subset(held)
    everywhere, held_errors = fitting.DropErrors(target), fitting.DropErrors(on_held)
    laws, cdfs = [], {}
    for law, fit in law_fits.items():
        at_fit = law_errors(everywhere, law, fit["mu"], fit["e"])
        trained = training_fit(target.subset(training), law)
        held_out = law_errors(held_errors, law, trained.mu, trained.e)
        cdfs[law] = held_out
        laws.append({"law": law, "fit": {"mu": fit["mu"], "e": fit["e"]},
                     "at_fit": median_interval(at_fit, replicates, seed),
                     "unsolved": int(np.count_nonzero(~np.isfinite(at_fit))),
                     "training_fit": {"mu": trained.mu, "e": trained.e},
                     "held_out": median_interval(held_out, replicates, seed),
                     **({"held_out_cdf": analysis.quantiles(held_out)} if curves else {})})
    reference_held = cdfs[REFERENCE_LAW]
    for row in laws:
        row["held_out_vs_reference"] = paired_difference(cdfs[row["law"]], reference_held,
                                                         replicates, seed)
    sample = calibration_sample(len(target), seed, calibration_drops)
    engines = []
    for engine, preset, run in engine_runs:
        progress(f"{engine.name} ({preset_label(engine.name, preset)}): calibrated on the "
                 "training half, scored on the held-out half")
        preset_errors = np.asarray(run["per_drop_errors"], dtype=float)
        reference = law_errors(everywhere, REFERENCE_LAW, run["mu"], run["e"])
        row = {"engine": engine.name, "preset": preset,
               "at_preset": {"mu": run["mu"], "e": run["e"],
                             **median_interval(preset_errors, replicates, seed),
                             "flagged": _flagged(run["verdicts"]),
                             "vs_reference": paired_difference(preset_errors, reference,
                                                               replicates, seed)}}
        found = calibrations.get((engine.name, preset))
        if found is None:
            found = calibrate_engine(engine, preset, target, thetas, seed, calibration_drops,
                                     # a cached.Progress tells the cells every 2 s at most
                                     progress=getattr(progress, "step", progress))
        row.update(calibrated_row(engine, preset, found, thetas, held, on_held,
                                  reference_held, seed, replicates))
        if not curves and row["calibrated"] is not None:
            row["calibrated"].pop("cdf")
        engines.append(row)
    return {"objective": OBJECTIVE, "reference": REFERENCE_LAW, "seed": seed,
            "replicates": replicates, "confidence": CONFIDENCE,
            "split": {"training": int(training.size), "held_out": int(held.size)},
            "calibration": {"drops": int(sample.size), "grid": "quick",
                            "mus": list(calibrate.PAIR_GRIDS["quick"][0]),
                            "es": list(calibrate.PAIR_GRIDS["quick"][1]),
                            "knobs": {engine.name: calibrate.engine_knobs(engine)
                                      for engine, _, _ in engine_runs},
                            "tolerance": calibrate.TOLERANCE},
            "law_grid": {"mus": list(LAW_MUS), "es": list(LAW_ES)},
            "laws": laws, "engines": engines}


def calibrated_row(engine, preset: str, found: calibrate.Calibration, thetas, held,
                   on_held: MeasuredImpacts, reference_held, seed: int,
                   replicates: int) -> dict:
    """``engine`` run at the pick of the calibration ``found`` on the held-out rows
    ``held`` (``on_held``): ``calibrated`` (None with ``cannot``, the reason, when the
    calibration has no pick)."""
    sample = found.sample or {}
    knobs = list(found.knobs)
    if found.best is None:
        return {"calibrated": None, "cannot_knobs": knobs,
                "cannot": (f"no setting tried gives single impacts on half of the "
                           f"{sample.get('drops', '?')} training drops")}
    if set(found.cannot()) == set(knobs):
        return {"calibrated": None, "cannot_knobs": knobs,
                "cannot": (f"no setting tried moves its median error by "
                           f"{calibrate.TOLERANCE:g} or more")}
    best = dict(found.best)
    mu, e = best.pop("mu"), best.pop("e")
    run = drops_engines.run_drops(engine, preset, on_held, np.asarray(thetas)[held], mu, e,
                                  keep_errors=True, overrides=best)
    errors = run.pop("per_drop_errors")
    return {"cannot": None, "cannot_knobs": found.cannot(),
            "calibrated": {"settings": found.best, "training_objective": found.best_objective,
                           **median_interval(errors, replicates, seed),
                           "flagged": _flagged(run["verdicts"]),
                           "vs_reference": paired_difference(errors, reference_held,
                                                             replicates, seed),
                           "cdf": analysis.quantiles(errors)}}


def interval_text(found: dict | None, key: str = "median") -> str:
    """``0.364 [0.348, 0.388]``; a difference signed; "—" when nothing was scored."""
    if found is None or found.get(key) is None:
        return "—"
    sign = "+" if key == "difference" else ""

    def shown(value: float) -> str:  # rounded first: a difference of -1e-17 reads +0.000
        return f"{round(value, 3) + 0.0:{sign}.3f}"

    low, high = found["interval"]
    return f"{shown(found[key])} [{shown(low)}, {shown(high)}]"


def settings_text(settings: dict) -> str:
    """A calibration's pick in a line: ``μ 0, e 0.6, length_scale 8``."""
    names = {"mu": "μ", "e": "e"}
    return ", ".join(f"{names.get(k, k)} {v:g}" if isinstance(v, float | int)
                     else f"{names.get(k, k)} {v}" for k, v in settings.items())


def paired_cells(vs: dict | None) -> list[str]:
    """An engine beside the reference law on the same drops, as four cells: its median,
    the law's median on the drops it scored, their paired difference (each with its
    interval), and the drops it lost with the law's median error on them."""
    if vs is None:
        return ["—", "—", "—", "every drop"]
    lost = vs["lost"]
    lost_text = "none" if not lost["drops"] else (
        f"{lost['drops']:,} (law {lost['reference_median']:.3f})")
    return [interval_text(vs["median"]), interval_text(vs["reference"]),
            interval_text(vs, "difference"), lost_text]


#: The paired columns of an engine (after each of "at preset" and "calibrated, held out").
PAIRED_COLUMNS = ("median", "{law}, same drops", "difference", "lost (law's median on them)")


def markdown(result: dict, label=lambda engine, preset: preset) -> list[str]:
    """The command's tables (Markdown lines): the engines, then the laws; ``label(engine,
    preset)`` names a preset."""
    level = f"{result['confidence']:.0%}"
    split = result["split"]
    law = result["reference"]
    paired = [f"{part}: {column.format(law=law)}" for part in ("preset", "held out")
              for column in PAIRED_COLUMNS]
    lines = [f"Drops split by drop with seed {result['seed']}: {split['training']} training, "
             f"{split['held_out']} held out; engines calibrated on "
             f"{result['calibration']['drops']} training drops (quick grid μ "
             f"{', '.join(f'{m:g}' for m in result['calibration']['mus'])} × e "
             f"{', '.join(f'{e:g}' for e in result['calibration']['es'])}, own knobs); "
             f"medians with {level} intervals ({result['replicates']} bootstrap resamples); "
             f"each engine's median beside {law}'s on the drops it scored (paired bootstrap "
             f"of the difference), and the drops it lost with {law}'s median error on them.\n",
             "| engine | preset | calibrated settings | " + " | ".join(paired)
             + " | flagged (preset / held out) |",
             "|---|---|---|" + "---:|" * len(paired) + "---|"]
    for row in result["engines"]:
        preset, calibrated = row["at_preset"], row["calibrated"]
        flagged = [", ".join(f"{k}: {v}" for k, v in part["flagged"].items()) or "none"
                   for part in (preset, calibrated) if part is not None]
        held = (paired_cells(calibrated["vs_reference"]) if calibrated is not None
                else ["—"] * len(PAIRED_COLUMNS))
        lines.append(
            f"| {row['engine']} | {label(row['engine'], row['preset'])} | "
            + (f"cannot be calibrated: {row['cannot']}" if calibrated is None
               else settings_text(calibrated["settings"]))
            + " | " + " | ".join(paired_cells(preset["vs_reference"]) + held) + " | "
            + " / ".join(flagged) + " |")
    lines += ["", f"| law | fit (all drops) | median at fit | fit (training half) | median "
              f"held out | vs {law} | unsolved |",
              "|---|---|---:|---|---:|---:|---:|"]
    for row in result["laws"]:
        lines.append(f"| {row['law']} | μ {row['fit']['mu']:.3f}, e {row['fit']['e']:.3f} | "
                     f"{interval_text(row['at_fit'])} | μ {row['training_fit']['mu']:.3f}, e "
                     f"{row['training_fit']['e']:.3f} | {interval_text(row['held_out'])} | "
                     f"{interval_text(row['held_out_vs_reference'], 'difference')} | "
                     f"{row['unsolved']} |")
    return lines
