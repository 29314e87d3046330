"""Calibration of an engine's own knobs against measured drops or against a law (issue 25,
item 4).

A small grid over the pair's (μ, e), which every engine takes, times a few values of the
engine's own settings (its class's ``calibration_knobs``; none by default: then it cannot be
calibrated by a setting of its own, for its ``no_calibration_knobs_why``), each cell scored
by a named objective: the median over the impacts of the paper's normalized error of the
centre's velocity (:func:`metric.normalized_error`) against the measured speeds
(``--to data``) or against a law's prediction at fixed settings ``law_mu``, ``law_e``
(``--to LAW``, on a population of ellipse drops generated here, no data needed). Flagged
runs are never scored; a cell where fewer than half of the runs are single impacts has no
objective. A knob that moves the objective by less than :data:`TOLERANCE` across its values
(the others at the best cell) is reported as one the engine cannot be calibrated by.

How far to trust the pick: every cell keeps its per-drop errors (NaN for a flagged run), so
that the drops can be resampled without running the engine again. A seeded bootstrap of
:data:`REPLICATES` resamples of the drops re-picks the best cell on each and gives the
central :data:`CONFIDENCE` percentile interval of the best objective and of each setting
chosen; the drops split by drop into :data:`HELD_OUT_FOLDS` halves (seeded) give a held-out
error: the best cell of one half scored on the other, beside its in-sample value. Both reuse
the law fits' resampling (:mod:`.fitting`). The per-drop errors stay in memory: only
aggregates leave this module.
"""

from __future__ import annotations

import itertools
import json
from dataclasses import dataclass, field

import numpy as np

from harness.engines import preset_label
from harness.scene import ellipse

from . import drops_engines, fazeli, fitting, metric
from .engine_curves import judged
from .predict import predict
from .records import MeasuredImpacts

#: A knob whose values move the objective by less than this (absolute, in units of the
#: normalized error) does not calibrate the engine.
TOLERANCE = 1e-3
#: A cell is scored when at least this share of its runs are single impacts.
MIN_SCORED_SHARE = 0.5
#: Bootstrap resamples of the scored drops, and the intervals' confidence.
REPLICATES = 1000
CONFIDENCE = 0.95
#: The held-out error's split: two halves by drop, the best cell of one (the fitting half)
#: scored on the other (the held-out half); the other way round is shown beside it.
HELD_OUT_FOLDS = 2
#: The (μ, e) grids: ``quick`` (the default) and ``fine``. Every law's best fit to the
#: Fazeli drops is frictionless (docs/experiments.md), so the quick grid holds μ = 0: an
#: engine calibrated without it could not reach the laws' fit.
PAIR_GRIDS = {"quick": ((0.0, 0.1, 0.3), (0.3, 0.6, 0.9)),
              "fine": (tuple(np.round(np.linspace(0.0, 1.0, 11), 2)),
                       tuple(np.round(np.linspace(0.0, 1.0, 11), 2)))}


def engine_knobs(engine, preset: str | None = None) -> dict:
    """``{setting: [values]}``: the engine's own settings tried beside the pair, from its
    class (``Engine.calibration_knobs``; empty: none of its own), and under ``preset`` that
    preset's own value of each as well (first, where the class does not list it): the
    calibration never does worse than the preset's settings on the pair's grid. (MuJoCo's
    ``matched-bounce`` maps e to its damping, ``solref = "restitution"``; without its own
    value every cell tried replaced that mapping by a fixed damping and no cell gave single
    impacts.) A preset that ignores a setting shows it as "cannot be calibrated" rather than
    being special-cased."""
    knobs = {}
    for setting, values in type(engine).calibration_knobs:
        values = list(values)
        if preset is not None:
            own = engine.presets[preset].get(setting)
            if own is not None and own not in values:
                values.insert(0, own)
        knobs[setting] = values
    return knobs


@dataclass(frozen=True)
class Uncertainty:
    """How far the pick of a calibration holds: a bootstrap over the drops (the best cell
    re-picked on each resample) and a held-out error (split by drop)."""

    replicates: int
    confidence: float
    seed: int
    objective: fitting.Interval  # percentile interval of the best cell's objective
    #: knob -> [low, high]: the percentile interval of the value chosen, on values tried
    settings: dict
    agree: float  # share of the scored resamples that chose the full sample's best cell
    unscored: int  # resamples on which no cell was scored
    split: fitting.CrossValidation  # the halves: each one's best cell scored on the other
    split_best: tuple  # the settings picked on each fitting half (None: no cell scored)

    # The split's first fold is the held-out half, the others the fitting half; a mean over
    # both ways round would make in-sample and held-out equal whenever the halves agree.
    @property
    def in_sample(self) -> float:
        """The objective of the fitting half's best cell on the fitting half."""
        return self.split.in_sample[0]

    @property
    def held_out(self) -> float:
        """The objective of the fitting half's best cell on the held-out half."""
        return self.split.held_out[0]


@dataclass(frozen=True)
class Calibration:
    engine: str
    preset: str
    target: str  # "data" or a law's name
    objective: str
    knobs: dict  # knob -> the values tried
    cells: list = field(repr=False)  # [(settings dict, objective or None, ok share)]
    best: dict | None  # the best cell's settings (None: no cell scored)
    best_objective: float | None
    moves: dict  # knob -> how far it moves the objective at the best cell (None: unscored)
    #: Which impacts were scored: {"drops": n, "of": N, "seed": s} for a seeded random
    #: sample of the data (:func:`sample_rows`) or of a generated population.
    sample: dict | None = None
    #: (cells, drops): each cell's per-drop error, NaN for a flagged run, in the order of
    #: ``cells``. In memory only: never written (the Fazeli data carry no licence).
    errors: np.ndarray | None = field(default=None, repr=False)
    #: The bootstrap intervals and the held-out error (None: no cell scored).
    uncertainty: Uncertainty | None = None
    #: Why no setting of the engine's own is among ``knobs`` (its class's
    #: ``no_calibration_knobs_why``); None when it has some.
    no_knobs_why: str | None = None

    def cannot(self) -> list[str]:
        """The knobs that do not move the objective (the engine cannot be calibrated by
        them)."""
        return [knob for knob, moved in self.moves.items()
                if moved is not None and moved < TOLERANCE]


def sample_rows(total: int, count: int, seed: int = 0) -> np.ndarray:
    """``count`` distinct rows of ``total``, drawn at random with ``seed`` (all of them when
    ``count >= total``), in increasing order: the drops a calibration scores. The first
    drops of a file are not a sample (the recording's order follows the experiment's)."""
    if count >= total:
        return np.arange(total)
    rng = np.random.default_rng(seed)
    return np.sort(rng.choice(total, size=count, replace=False))


def drop_population(count: int = 24, seed: int = 0) -> tuple[MeasuredImpacts, np.ndarray]:
    """``count`` ellipse drops (the Fazeli body) at random angles and speeds like the
    experiments' (v_y 2.2 to 3 m/s down, |v_x| ≤ 0.6 m/s, |ω| ≤ 8 rad/s); the speeds after
    are NaN. Returns the impacts and their angles."""
    rng = np.random.default_rng(seed)
    theta = rng.uniform(-np.pi, np.pi, count)
    wn, wt = ellipse.jacobians(theta, *fazeli.SEMI_AXES)
    before = np.stack([rng.uniform(-0.6, 0.6, count), rng.uniform(-3.0, -2.2, count),
                       rng.uniform(-8.0, 8.0, count)], axis=1)
    impacts = MeasuredImpacts("ellipse-population", fazeli.mass_matrix(), before,
                              np.full((count, 3), np.nan), wn, wt, np.arange(count))
    return impacts, theta


def cell_objectives(errors) -> np.ndarray:
    """The objective of every cell from per-drop errors ``(cells..., drops)`` (NaN for a
    flagged run): the median over the scored runs, NaN for a cell fewer than
    :data:`MIN_SCORED_SHARE` of whose runs are scored."""
    errors = np.asarray(errors, dtype=float)
    flat = errors.reshape(-1, errors.shape[-1])
    flat = np.where(np.isfinite(flat), flat, np.nan)
    scored = np.mean(np.isfinite(flat), axis=1) >= MIN_SCORED_SHARE
    values = np.full(flat.shape[0], np.nan)
    if scored.any():
        values[scored] = metric.aggregate("median-error", flat[scored])
    return values.reshape(errors.shape[:-1])


def _per_drop_errors(engine, preset: str, impacts: MeasuredImpacts, thetas, mu: float,
                     e: float, overrides: dict, reference: np.ndarray) -> np.ndarray:
    """The normalized error of each impact's run against ``reference``, NaN where the run
    is flagged (not judged a single impact)."""
    scenes = [drops_engines.drop_scene(impacts, i, float(thetas[i]), mu, e)
              for i in range(len(impacts))]
    runs = engine.run_many(scenes, preset=preset, overrides=overrides or None)
    ok = np.array([judged(run, scene) == "ok" for run, scene in zip(runs, scenes)])
    after = np.array([np.asarray(run.u_after, dtype=float)[:3] for run in runs])
    return np.where(ok, metric.normalized_error(after, reference), np.nan)


def uncertainty(errors: np.ndarray, cells: list[dict], best_index: int, knobs: dict,
                replicates: int = REPLICATES, seed: int = 0,
                confidence: float = CONFIDENCE) -> Uncertainty:
    """The bootstrap and held-out error of a calibration from its per-drop errors
    ``(cells, drops)`` (``cells``: each row's settings; ``best_index``: the full sample's
    best row)."""
    chosen, values = [], []
    for rows in fitting.resampled_rows(errors.shape[-1], replicates, seed):
        grid = cell_objectives(errors[:, rows])
        if np.all(np.isnan(grid)):
            continue
        (row,) = fitting.best_cell(grid)
        chosen.append(row)
        values.append(grid[row])
    if chosen:
        objective = fitting.percentile_interval(values, confidence)
        settings = {}
        for knob, tried in knobs.items():
            # position in the values tried (a setting may be a list, as MuJoCo's solref)
            picked = [tried.index(cells[row][knob]) for row in chosen]
            span = fitting.percentile_interval(picked, confidence, method="inverted_cdf")
            settings[knob] = [tried[int(span.low)], tried[int(span.high)]]
        agree = float(np.mean(np.array(chosen) == best_index))
    else:
        objective, settings, agree = fitting.Interval(np.nan, np.nan), {}, float("nan")
    split = fitting.cross_validate(errors, cell_objectives, HELD_OUT_FOLDS, seed)
    split_best = tuple(None if cell is None else cells[cell[0]] for cell in split.cells)
    return Uncertainty(replicates, confidence, seed, objective, settings, agree,
                       replicates - len(chosen), split, split_best)


def calibrate(engine, preset: str, impacts: MeasuredImpacts, thetas, target: str,
              grid: str = "quick", law_mu: float = 0.3, law_e: float = 0.6,
              sample: dict | None = None, replicates: int = REPLICATES,
              seed: int = 0, progress=lambda text: None) -> Calibration:
    """Every cell of the grid scored (``target``: "data" or a law of ``planar_impact``,
    then at ``law_mu``, ``law_e``: the engine's pair settings are knobs like the others);
    ``sample`` records which impacts these are (kept in the result). ``replicates`` and
    ``seed``: the bootstrap's resamples and the seed of those and of the held-out split.
    ``progress(text)`` is told each cell as it starts (it may print at most some)."""
    reference = (impacts.speeds_after if target == "data"
                 else predict(impacts, target, law_mu, law_e).speeds_after)
    mus, es = PAIR_GRIDS[grid]
    knobs = {"mu": list(mus), "e": list(es), **engine_knobs(engine, preset)}
    names = list(knobs)
    settings_of = [dict(zip(names, values))
                   for values in itertools.product(*(knobs[name] for name in names))]
    rows = []
    for cell, settings in enumerate(settings_of):
        progress(f"{engine.name} ({preset_label(engine.name, preset)}): cell {cell + 1} of "
                 f"{len(settings_of)}, {len(impacts)} impacts each")
        rows.append(_per_drop_errors(
            engine, preset, impacts, thetas, settings["mu"], settings["e"],
            {k: v for k, v in settings.items() if k not in ("mu", "e")}, reference))
    errors = np.array(rows).reshape(len(settings_of), len(impacts))
    objectives = cell_objectives(errors)
    shares = np.mean(np.isfinite(errors), axis=1)
    cells = [(settings, None if np.isnan(value) else float(value), float(share))
             for settings, value, share in zip(settings_of, objectives, shares)]
    no_knobs_why = (None if type(engine).calibration_knobs
                    else type(engine).no_calibration_knobs_why)
    if np.all(np.isnan(objectives)):
        return Calibration(engine.name, preset, target, "median-error", knobs, cells, None,
                           None, {name: None for name in names}, sample, errors,
                           no_knobs_why=no_knobs_why)
    (best_index,) = fitting.best_cell(objectives)
    best, best_objective, _ = cells[best_index]
    moves = {}
    for name in names:  # the knob's values, the others held at the best cell
        line = [objective for settings, objective, _ in cells
                if objective is not None and all(settings[other] == best[other]
                                                 for other in names if other != name)]
        moves[name] = float(max(line) - min(line)) if len(line) > 1 else None
    return Calibration(engine.name, preset, target, "median-error", knobs, cells, best,
                       best_objective, moves, sample, errors,
                       uncertainty(errors, settings_of, best_index, knobs, replicates, seed),
                       no_knobs_why)


def summary(calibration: Calibration) -> str:
    """Plain lines: the objective, the best settings, and what cannot be calibrated."""
    where = ("the measured drops" if calibration.target == "data"
             else f"{calibration.target} on a population of ellipse drops")
    shown = preset_label(calibration.engine, calibration.preset)  # the name users see
    lines = [f"{calibration.engine} ({shown}) against {where}; objective: "
             f"median normalized error of the centre's velocity (flagged runs not scored)"]
    if calibration.sample is not None:
        drawn = calibration.sample
        lines.append(f"impacts scored: {drawn['drops']} of {drawn['of']}, a random sample "
                     f"drawn with seed {drawn['seed']}")
    if calibration.no_knobs_why is not None:
        lines.append(f"its own settings: cannot be calibrated (no knobs; the pair's mu and e "
                     f"alone are tried): {calibration.no_knobs_why}")
    if calibration.best is None:
        lines.append("cannot be calibrated: no setting tried gives single impacts on half "
                     "of the drops")
        return "\n".join(lines)
    lines.append(f"best: {settings_text(calibration.best)} -> median normalized error "
                 f"{calibration.best_objective:.4f}")
    for knob, value in calibration.best.items():
        tried = calibration.knobs[knob]
        if at_open_edge(knob, value, tried):
            if knob not in BOUNDS:  # an engine's own knob: its class lists the values
                advice = " (the values tried are the engine's calibration_knobs)"
            elif len(tried) < len(PAIR_GRIDS["fine"][0]):
                advice = " (--grid fine tries more)"
            else:
                advice = ""
            lines.append(f"  {knob} {json.dumps(value)} is at an end of the values tried: a "
                         f"value beyond it may score better{advice}")
    for knob, moved in calibration.moves.items():
        if moved is None:
            text = "not scored along this knob"
        elif moved < TOLERANCE:
            text = f"cannot be calibrated: moves the objective by {moved:.2g} < {TOLERANCE}"
        else:
            text = f"moves the objective by {moved:.4f}"
        tried = ", ".join(f"{v:g}" if isinstance(v, float) else str(v)
                          for v in calibration.knobs[knob])  # not Python's list
        lines.append(f"  {knob} (tried {tried}): {text}")
    if calibration.uncertainty is not None:
        lines += uncertainty_lines(calibration.uncertainty, len(calibration.errors[0]),
                                   calibration.cannot())
    return "\n".join(lines)


def settings_text(settings: dict) -> str:
    """``{"mu": 0.3, "e": 0.6}`` as ``mu 0.3, e 0.6``."""
    return ", ".join(f"{knob} {value:g}" if isinstance(value, float) else f"{knob} {value}"
                     for knob, value in settings.items())


#: The ends of a knob's range that are the physics' own bounds (no value lies beyond them).
BOUNDS = {"mu": (0.0, None), "e": (0.0, 1.0)}


def at_open_edge(knob: str, value, tried) -> bool:
    """Whether ``value`` is the smallest or largest of three or more values ``tried`` for
    ``knob``, at an end that is not a bound of the physics (μ ≥ 0, 0 ≤ e ≤ 1): the best may
    then lie beyond the values tried. A list value (MuJoCo's ``solref``) is placed by its one
    entry that varies among the lists tried; others are not placed."""
    if isinstance(value, (list, tuple)):
        lists = [item for item in tried if isinstance(item, (list, tuple))
                 and len(item) == len(value)]
        varying = [index for index in range(len(value))
                   if len({item[index] for item in lists}) > 1]
        if len(varying) != 1:
            return False
        value, tried = value[varying[0]], [item[varying[0]] for item in lists]
    numbers = [item for item in tried
               if isinstance(item, (int, float)) and not isinstance(item, bool)]
    if len(set(numbers)) < 3 or not isinstance(value, (int, float)):
        return False
    low, high = BOUNDS.get(knob, (None, None))
    return ((value == min(numbers) and value != low)
            or (value == max(numbers) and value != high))


def uncertainty_lines(found: Uncertainty, drops: int, cannot=()) -> list[str]:
    """The bootstrap intervals and the held-out error, in plain lines; a knob of ``cannot``
    ties (the first value wins every tie), so its interval is shown as no interval."""
    level = f"{found.confidence:.0%}"
    lines = [f"bootstrap: {found.replicates} resamples of the {drops} drops with seed "
             f"{found.seed}, the best cell re-picked on each"
             + (f" ({found.unscored} with no cell scored, left out)" if found.unscored else "")]
    if found.settings:
        low, high = found.objective.low, found.objective.high
        lines.append(f"  best objective, {level} interval: [{low:.4f}, {high:.4f}]; the best "
                     f"cell above re-picked on {found.agree:.0%} of the resamples")
        lines.append(f"  settings chosen, {level} interval: " + "; ".join(
            f"{knob} any (ties)" if knob in cannot
            else f"{knob} {json.dumps(low)}" if low == high
            else f"{knob} {json.dumps(low)} to {json.dumps(high)}"
            for knob, (low, high) in found.settings.items()))
    else:
        lines.append("  no resample had a scored cell: no interval")
    split = found.split
    sizes = [drops - split.held_out_drops[0], split.held_out_drops[0]]  # fitting, held out
    picks = ["none scored" if best is None else settings_text(best)
             for best in found.split_best]
    lines.append(f"held out: the drops split by drop into halves with seed {found.seed}; the "
                 f"best cell of the fitting half ({sizes[0]} drops: {picks[0]}) scores "
                 f"{found.in_sample:.4f} on it and {found.held_out:.4f} on the held-out half "
                 f"({sizes[1]} drops); fitted on the held-out half instead: {picks[1]}, "
                 f"{split.in_sample[1]:.4f} on it and {split.held_out[1]:.4f} on the other")
    return lines
