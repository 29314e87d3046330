"""Calibration of an engine's own knobs against measured drops or against a law (issue 25,
item 4).

A small grid over the pair's (μ, e), which every engine takes, times a few values of the
engine's own settings (:data:`ENGINE_KNOBS`), each cell scored by a named objective: the
median over the impacts of the paper's normalized error of the centre's velocity
(:func:`metric.normalized_error`) against the measured speeds (``--to data``) or against a
law's prediction at fixed settings ``law_mu``, ``law_e`` (``--to LAW``, on a population of
ellipse drops generated here, no data needed). Flagged runs are never scored; a cell where
fewer than half of the runs are single impacts has no objective. A knob that moves the
objective by less than :data:`TOLERANCE` across its values (the others at the best cell) is
reported as one the engine cannot be calibrated by.
"""

from __future__ import annotations

import itertools
import json
from dataclasses import dataclass, field

import numpy as np

from harness.scene import ellipse

from . import drops_engines, fazeli, metric
from .engine_curves import judged
from .predict import predict
from .records import MeasuredImpacts

#: A knob whose values move the objective by less than this (absolute, in units of the
#: normalized error) does not calibrate the engine.
TOLERANCE = 1e-3
#: The (μ, e) grids: ``quick`` (the default) and ``fine``.
PAIR_GRIDS = {"quick": ((0.1, 0.3, 0.6), (0.3, 0.6, 0.9)),
              "fine": (tuple(np.round(np.linspace(0.0, 1.0, 11), 2)),
                       tuple(np.round(np.linspace(0.0, 1.0, 11), 2)))}
#: Each engine's own settings tried beside the pair, as ``(setting, values)``; a preset that
#: ignores a setting shows it as "cannot be calibrated" rather than being special-cased.
ENGINE_KNOBS = {
    "mujoco": (("solref", ([0.02, 0.5], [0.02, 1.0], [0.02, 2.0])),),
    "box2d": (("length_scale", (1.0, 8.0, 64.0)),),
}


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


def _score(engine, preset: str, impacts: MeasuredImpacts, thetas, mu: float, e: float,
           overrides: dict, reference: np.ndarray) -> tuple[float | None, float]:
    scenes = [drops_engines.drop_scene(impacts, i, float(thetas[i]), mu, e)
              for i in range(len(impacts))]
    runs = engine.run_many(scenes, preset=preset, overrides=overrides or None)
    ok = np.array([judged(run, scene) == "ok" for run, scene in zip(runs, scenes)])
    after = np.array([np.asarray(run.u_after, dtype=float)[:3] for run in runs])
    errors = metric.normalized_error(after[ok], reference[ok])
    share = float(ok.mean())
    return (float(np.median(errors)) if share >= 0.5 else None), share


def calibrate(engine, preset: str, impacts: MeasuredImpacts, thetas, target: str,
              grid: str = "quick", law_mu: float = 0.3, law_e: float = 0.6,
              sample: dict | None = None) -> Calibration:
    """Every cell of the grid scored (``target``: "data" or a law of ``planar_impact``,
    then at ``law_mu``, ``law_e``: the engine's pair settings are knobs like the others);
    ``sample`` records which impacts these are (kept in the result)."""
    reference = (impacts.speeds_after if target == "data"
                 else predict(impacts, target, law_mu, law_e).speeds_after)
    mus, es = PAIR_GRIDS[grid]
    knobs = {"mu": list(mus), "e": list(es)}
    for setting, values in ENGINE_KNOBS.get(engine.name, ()):
        knobs[setting] = list(values)
    names = list(knobs)
    cells = []
    for values in itertools.product(*(knobs[name] for name in names)):
        settings = dict(zip(names, values))
        overrides = {k: v for k, v in settings.items() if k not in ("mu", "e")}
        objective, share = _score(engine, preset, impacts, thetas, settings["mu"],
                                  settings["e"], overrides, reference)
        cells.append((settings, objective, share))
    scored = [cell for cell in cells if cell[1] is not None]
    if not scored:
        return Calibration(engine.name, preset, target, "median-error", knobs, cells, None,
                           None, {name: None for name in names}, sample)
    best, best_objective, _ = min(scored, key=lambda cell: cell[1])
    moves = {}
    for name in names:  # the knob's values, the others held at the best cell
        line = [objective for settings, objective, _ in cells
                if objective is not None and all(settings[other] == best[other]
                                                 for other in names if other != name)]
        moves[name] = float(max(line) - min(line)) if len(line) > 1 else None
    return Calibration(engine.name, preset, target, "median-error", knobs, cells, best,
                       best_objective, moves, sample)


def summary(calibration: Calibration) -> str:
    """Plain lines: the objective, the best settings, and what cannot be calibrated."""
    where = ("the measured drops" if calibration.target == "data"
             else f"{calibration.target} on a population of ellipse drops")
    lines = [f"{calibration.engine} ({calibration.preset}) against {where}; objective: "
             f"median normalized error of the centre's velocity (flagged runs not scored)"]
    if calibration.sample is not None:
        drawn = calibration.sample
        lines.append(f"impacts scored: {drawn['drops']} of {drawn['of']}, a random sample "
                     f"drawn with seed {drawn['seed']}")
    if calibration.best is None:
        lines.append("cannot be calibrated: no setting tried gives single impacts on half "
                     "of the drops")
        return "\n".join(lines)
    lines.append(f"best: {json.dumps(calibration.best)} -> {calibration.best_objective:.4f}")
    for knob, moved in calibration.moves.items():
        if moved is None:
            text = "not scored along this knob"
        elif moved < TOLERANCE:
            text = f"cannot be calibrated: moves the objective by {moved:.2g} < {TOLERANCE}"
        else:
            text = f"moves the objective by {moved:.4f}"
        lines.append(f"  {knob} {calibration.knobs[knob]}: {text}")
    return "\n".join(lines)
