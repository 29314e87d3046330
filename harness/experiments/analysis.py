"""The comparison with measured drops: the paper's six models scored by its metric, every
law fitted with a named objective (held-out error, bootstrap intervals), and whether the
data can tell Poisson's law from Stronge's.

Only aggregates leave this module's results (medians, quantiles, counts, fitted values):
the Fazeli data carry no licence, so no per-drop number is written anywhere.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import planar_impact as pi

from .. import processes
from . import fitting, metric
from .predict import predict
from .records import MeasuredImpacts

QUANTILES = (0.25, 0.5, 0.75, 0.9)
#: Error distributions are kept as their quantiles at these levels (a curve, no drop).
CDF_LEVELS = tuple(np.round(np.linspace(0.0, 1.0, 101), 2))
#: Two laws whose objectives differ by less than this fraction are the same in practice.
PRACTICAL_BAND = 0.01


def error_summary(errors: np.ndarray) -> dict:
    """Aggregates of per-drop normalized errors: count, mean, quantiles."""
    errors = np.asarray(errors, dtype=float)
    valid = errors[np.isfinite(errors)]
    summary = {"drops": int(valid.size), "unsolved": int(errors.size - valid.size),
               "mean": float(np.mean(valid)) if valid.size else float("nan")}
    for q in QUANTILES:
        summary[f"q{round(q * 100)}"] = float(np.quantile(valid, q)) if valid.size else None
    return summary


def quantiles(errors) -> dict:
    """The distribution of per-drop errors as quantiles at :data:`CDF_LEVELS` (finite ones;
    ``drops`` counts them)."""
    errors = np.asarray(errors, dtype=float)
    valid = errors[np.isfinite(errors)]
    values = np.quantile(valid, CDF_LEVELS).tolist() if valid.size else []
    return {"drops": int(valid.size), "levels": list(CDF_LEVELS), "values": values}


def paper_models(model_speeds: dict[str, np.ndarray], impacts: MeasuredImpacts) -> dict:
    """The six published models' normalized errors (the paper's metric), per model."""
    return {name: error_summary(metric.normalized_error(speeds, impacts.speeds_after))
            for name, speeds in model_speeds.items()}


@dataclass(frozen=True)
class LawResult:
    law: str
    objective: str
    fit: fitting.Fit
    held_out: fitting.HeldOut
    bootstrap: fitting.Bootstrap
    errors: dict  # error_summary of the normalized error at the fitted (μ, e)
    collision_types: dict[int, int]  # Routh's diagram: drops per collision type at the fit
    unsolved_cells: int
    per_drop: dict  # quartiles of the drops' own best μ and e (aggregates only)


# What the forked workers read (set before forking, never pickled).
_SHARED: dict = {}


def _fit_law(item: tuple[str, str, int, int]) -> LawResult:
    law, objective, replicates, seed = item
    drop_errors = _SHARED["drop_errors"]
    table = fitting.error_table(drop_errors, law, _SHARED["mus"], _SHARED["es"])
    fitted = fitting.fit(drop_errors, table, objective)
    unsolved = table.unsolved
    held = fitting.held_out(table, objective, seed=seed)
    own = fitting.per_drop_fits(table, objective)
    per_drop = {name: {f"q{q}": float(np.percentile(own[:, k], q)) for q in (25, 50, 75)}
                for k, name in enumerate(("mu", "e"))}
    del table
    boot = fitting.bootstrap(drop_errors, fitted, replicates=replicates, seed=seed)
    errors, status = drop_errors(law, fitted.mu, fitted.e)
    normalized = np.where(status == 0, errors["median-error"], np.nan)
    space = drop_errors.space
    result = pi.solve_batch(space.mnn, space.mnt, space.mtt, space.vn, space.vt, fitted.mu,
                            fitted.e, law=law, delta=space.delta)
    types, counts = np.unique(result.collision_type[result.status == 0], return_counts=True)
    return LawResult(law, objective, fitted, held, boot, error_summary(normalized),
                     {int(t): int(c) for t, c in zip(types, counts)}, unsolved, per_drop)


def fit_laws(impacts: MeasuredImpacts, objective: str, laws=pi.LAWS, *, replicates: int = 200,
             seed: int = 0, workers: int | None = None, mus=fitting.MU_GRID,
             es=fitting.E_GRID) -> dict[str, LawResult]:
    """Every law fitted to ``impacts`` by ``objective``, one law per forked worker."""
    if objective not in metric.OBJECTIVES:
        raise ValueError(f"objective: unknown {objective!r}; allowed: "
                         f"{', '.join(metric.OBJECTIVES)}")
    _SHARED.update(drop_errors=fitting.DropErrors(impacts), mus=mus, es=es)
    try:
        items = [(law, objective, replicates, seed) for law in laws]
        workers = processes.default_workers() if workers is None else workers
        return dict(zip(laws, processes.map_forked(_fit_law, items, workers)))
    finally:
        _SHARED.clear()


@dataclass(frozen=True)
class LawDifference:
    """Law A against law B, each at its own fitted (μ, e), on the same drops."""

    law_a: str
    law_b: str
    objective_difference: float  # objective(A) − objective(B), all drops
    interval: fitting.Interval  # bootstrap percentile interval of that difference
    confidence: float
    prediction_gap_median: float  # median over drops of ‖v̂_A − v̂_B‖ / ‖v‖ (centre of mass)
    prediction_gap_q99: float
    measurement_scale: float  # median normalized error of the better law: the data's noise
    objective_value: float  # objective(B): the scale of the practical band

    def verdict(self, band: float | None = None) -> str:
        """Whether the data tell the laws apart, decided with a stated band: a difference
        whose whole interval lies within ``band`` × objective(B) is no practical difference."""
        band = PRACTICAL_BAND if band is None else band
        low, high = self.interval.low, self.interval.high
        if low <= 0 <= high:
            return (f"the data do not tell {self.law_a} from {self.law_b} (the interval "
                    "contains 0)")
        limit = band * abs(self.objective_value)
        better = self.law_a if high < 0 else self.law_b
        if -limit <= low and high <= limit:
            return (f"{better} is better by a resolvable amount, but the whole interval lies "
                    f"within {band:.0%} of the objective: no practical difference")
        return (f"{better} is better: the interval excludes 0 and exceeds {band:.0%} of the "
                "objective")


def compare_laws(impacts: MeasuredImpacts, objective: str, fit_a: fitting.Fit,
                 fit_b: fitting.Fit, replicates: int = 1000, seed: int = 0,
                 confidence: float = 0.95) -> LawDifference:
    """Do the data tell ``fit_a.law`` from ``fit_b.law``? A paired bootstrap (the same
    resampled drops for both laws) of the difference of their objectives."""
    drop_errors = fitting.DropErrors(impacts)
    errors_a, _ = drop_errors(fit_a.law, fit_a.mu, fit_a.e)
    errors_b, _ = drop_errors(fit_b.law, fit_b.mu, fit_b.e)
    a, b = errors_a[objective], errors_b[objective]
    rng = np.random.default_rng(seed)
    samples = rng.integers(0, a.size, (replicates, a.size))
    differences = (metric.aggregate(objective, a[samples])
                   - metric.aggregate(objective, b[samples]))
    tails = 100 * (1 - confidence) / 2, 100 * (1 + confidence) / 2
    speeds_a = _speeds(impacts, fit_a)
    speeds_b = _speeds(impacts, fit_b)
    gap = metric.normalized_error(speeds_a, speeds_b) * np.hypot(
        speeds_b[:, 0], speeds_b[:, 1]) / np.hypot(impacts.speeds_after[:, 0],
                                                    impacts.speeds_after[:, 1])
    better = min(np.median(errors_a["median-error"]), np.median(errors_b["median-error"]))
    return LawDifference(fit_a.law, fit_b.law,
                         float(metric.aggregate(objective, a) - metric.aggregate(objective, b)),
                         fitting.Interval(*np.percentile(differences, tails)), confidence,
                         float(np.nanmedian(gap)), float(np.nanquantile(gap, 0.99)),
                         float(better), float(metric.aggregate(objective, b)))


def _speeds(impacts: MeasuredImpacts, fitted: fitting.Fit) -> np.ndarray:
    return predict(impacts, fitted.law, fitted.mu, fitted.e).speeds_after


def routh_position(impacts: MeasuredImpacts, mu: float) -> dict:
    """Where the drops lie on Routh's diagram beside the collision types of each law's fit:
    the incidence ratio |v_t|/|v_n|, the coupling μ|m_nt|/m_nn (how much a sliding friction
    impulse changes v_n, relative to the normal impulse: the laws differ only through it)
    and how many drops have m_nt opposing the slip."""
    space = impacts.contact_space()
    ratio = np.abs(space.vt) / np.abs(space.vn)
    coupling = mu * np.abs(space.mnt) / space.mnn
    return {
        "incidence_ratio": {f"q{round(q * 100)}": float(np.quantile(ratio, q))
                            for q in QUANTILES},
        "mu_coupling": {f"q{round(q * 100)}": float(np.quantile(coupling, q))
                        for q in QUANTILES},
        "coupling_opposes_slip": int(np.count_nonzero(space.mnt * np.sign(space.vt) < 0)),
        "drops": len(impacts),
    }


def law_gap(impacts: MeasuredImpacts, law_a: str, law_b: str, mus, e: float) -> dict:
    """How far two laws' predictions lie apart at the same (μ, e), per μ: the median and
    99th percentile over drops of ‖v̂_A − v̂_B‖ / ‖v‖ (centre of mass, measured |v|).
    Where this is far below the measurement error, no fit of these data can separate them."""
    mus = np.asarray(mus, dtype=float)
    a = predict(impacts, law_a, mus[:, None], e).speeds_after
    b = predict(impacts, law_b, mus[:, None], e).speeds_after
    gap = metric.normalized_error(a, b) * np.hypot(b[..., 0], b[..., 1]) / np.hypot(
        impacts.speeds_after[:, 0], impacts.speeds_after[:, 1])
    return {float(mu): {"median": float(np.nanmedian(g)), "q99": float(np.nanquantile(g, 0.99))}
            for mu, g in zip(mus, gap)}
