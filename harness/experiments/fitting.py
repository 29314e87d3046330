"""Global (μ, e) per law against measured impacts, with a named objective, its held-out
value (split by drop) and bootstrap intervals.

Every law is solved on a (μ, e) grid for every drop once (``solve_batch``); the per-drop
errors of the grid (``ErrorTable``) serve the fit, the held-out folds and the bootstrap
alike. The fit is the grid's best cell, then refined on a grid ten times finer around it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import planar_impact as pi

from . import metric
from .records import ContactSpace, MeasuredImpacts

#: The default grid: μ in [0, 1] and e in [0, 1], steps of 0.01.
MU_GRID = np.round(np.linspace(0.0, 1.0, 101), 12)
E_GRID = np.round(np.linspace(0.0, 1.0, 101), 12)


@dataclass(frozen=True)
class ErrorTable:
    """Per-drop errors of one law on a grid: ``errors[objective]`` is (len(mus), len(es),
    N) float32, NaN where the law did not solve the row."""

    law: str
    mus: np.ndarray
    es: np.ndarray
    errors: dict[str, np.ndarray]
    unsolved: int  # rows (cells × drops) with status != 0

    def objective_grid(self, objective: str, rows=None) -> np.ndarray:
        table = self.errors[objective] if rows is None else self.errors[objective][..., rows]
        return metric.aggregate(objective, table)


class DropErrors:
    """Per-drop errors of a law for any (μ, e), computed without forming full speed
    vectors: only what the two objectives need."""

    def __init__(self, impacts: MeasuredImpacts):
        self.space: ContactSpace = impacts.contact_space()
        inverse = np.linalg.inv(impacts.mass_matrix)
        # velocity of the centre of mass per unit normal / tangential impulse
        self.per_normal = (impacts.wn @ inverse.T)[:, :2]
        self.per_tangential = (impacts.wt @ inverse.T)[:, :2]
        self.before = impacts.speeds_before[:, :2]
        self.after = impacts.speeds_after[:, :2]
        self.after_norm = np.hypot(self.after[:, 0], self.after[:, 1])
        self.impulses = impacts.measured_impulses()  # (N, 2): P_t, P_n

    def __call__(self, law: str, mu, e) -> tuple[dict[str, np.ndarray], np.ndarray]:
        space = self.space
        result = pi.solve_batch(space.mnn, space.mnt, space.mtt, space.vn, space.vt, mu, e,
                                law=law, delta=space.delta)
        normal, tangential = result.normal_impulse, result.tangential_impulse
        vx = self.before[:, 0] + normal * self.per_normal[:, 0] + tangential * \
            self.per_tangential[:, 0] - self.after[:, 0]
        vy = self.before[:, 1] + normal * self.per_normal[:, 1] + tangential * \
            self.per_tangential[:, 1] - self.after[:, 1]
        errors = {
            "median-error": np.hypot(vx, vy) / self.after_norm,  # metric.normalized_error
            "impulse": np.hypot(tangential - self.impulses[:, 0],
                                normal - self.impulses[:, 1]),  # metric.impulse_error
        }
        return errors, result.status


def error_table(drop_errors: DropErrors, law: str, mus=MU_GRID, es=E_GRID) -> ErrorTable:
    mus, es = np.asarray(mus, dtype=float), np.asarray(es, dtype=float)
    drops = drop_errors.space.vn.size
    tables = {name: np.empty((mus.size, es.size, drops), dtype=np.float32)
              for name in metric.OBJECTIVES}
    unsolved = 0
    for i, mu in enumerate(mus):
        errors, status = drop_errors(law, mu, es[:, None])
        unsolved += int(np.count_nonzero(status))
        for name, table in tables.items():
            table[i] = errors[name]
    return ErrorTable(law, mus, es, tables, unsolved)


@dataclass(frozen=True)
class Fit:
    law: str
    objective: str
    mu: float
    e: float
    value: float  # the objective at (mu, e), all drops
    on_grid_edge: bool  # the best μ is the grid's largest (the optimum may lie beyond it)


def best_cell(grid: np.ndarray) -> tuple[int, ...]:
    """The index of the grid's smallest value (NaN cells left out), on any number of axes:
    the first minimum in C order (on a law's grid, (μ, e) order), so ties are deterministic.
    The grid must hold a number."""
    flat = np.nanargmin(grid)
    return tuple(int(i) for i in np.unravel_index(int(flat), np.shape(grid)))


def fit(drop_errors: DropErrors, table: ErrorTable, objective: str, refine: int = 10) -> Fit:
    """The best (μ, e) of ``objective``: the grid's best cell, then a grid ``refine`` times
    finer over the neighbouring cells."""
    grid = table.objective_grid(objective)
    i, j = best_cell(grid)
    # μ = 0 and e in {0, 1} are the physical bounds; only the grid's largest μ is arbitrary.
    edge = i == table.mus.size - 1
    mus = _finer(table.mus, i, refine)
    es = _finer(table.es, j, refine)
    fine = error_table(drop_errors, table.law, mus, es)
    fine_grid = fine.objective_grid(objective)
    k, m = best_cell(fine_grid)
    return Fit(table.law, objective, float(mus[k]), float(es[m]), float(fine_grid[k, m]), edge)


def _finer(values: np.ndarray, index: int, refine: int) -> np.ndarray:
    low = values[max(index - 1, 0)]
    high = values[min(index + 1, values.size - 1)]
    step = (values[1] - values[0]) / refine
    return np.round(np.arange(low, high + step / 2, step), 12)


def per_drop_fits(table: ErrorTable, objective: str) -> np.ndarray:
    """(N, 2): each drop's own best (μ, e) on the grid (first minimum in (μ, e) order).
    A single drop rarely pins both: the spread of these is the data's, not the fit's."""
    per_drop = table.errors[objective].reshape(-1, table.errors[objective].shape[-1])
    cells = np.argmin(np.where(np.isnan(per_drop), np.inf, per_drop), axis=0)
    rows, cols = np.divmod(cells, table.es.size)
    return np.stack([table.mus[rows], table.es[cols]], axis=1)


@dataclass(frozen=True)
class CrossValidation:
    """Per fold: the objective at the cell fitted on the other folds, on those fitting drops
    (``in_sample``) and on the fold's own drops (``held_out``), and that cell (None, and
    NaN values, where no cell scored on the fitting drops)."""

    folds: int
    seed: int
    in_sample: tuple[float, ...]
    held_out: tuple[float, ...]
    cells: tuple[tuple[int, ...] | None, ...]
    held_out_drops: tuple[int, ...]  # drops in each fold (the rest fit it)


def fold_splits(drops: int, folds: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """``(fitting rows, held-out rows)`` per fold: the drops shuffled with ``seed`` and cut
    into ``folds`` parts as equal as can be (split by drop: a drop is never on both sides)."""
    order = np.random.default_rng(seed).permutation(drops)
    return [(np.setdiff1d(order, fold), fold) for fold in np.array_split(order, folds)]


def cross_validate(errors: np.ndarray, aggregate, folds: int, seed: int) -> CrossValidation:
    """K-fold by drop over any grid of cells: ``errors`` is (cells..., N) per-drop errors,
    ``aggregate(errors[..., rows])`` the objective per cell over those rows (NaN for a cell
    that cannot be scored on them); each fold's cell is the best on the other folds."""
    inside, outside, cells = [], [], []
    splits = fold_splits(errors.shape[-1], folds, seed)
    for train, fold in splits:
        grid = np.asarray(aggregate(errors[..., train]), dtype=float)
        if np.all(np.isnan(grid)):
            inside.append(float("nan"))
            outside.append(float("nan"))
            cells.append(None)
            continue
        cell = best_cell(grid)
        inside.append(float(grid[cell]))
        outside.append(float(aggregate(errors[cell][fold])))
        cells.append(cell)
    return CrossValidation(folds, seed, tuple(inside), tuple(outside), tuple(cells),
                           tuple(fold.size for _, fold in splits))


@dataclass(frozen=True)
class HeldOut:
    folds: int
    in_sample: float  # mean over folds of the objective on the fitting drops
    held_out: float  # mean over folds of the objective on the held-out drops
    fold_fits: tuple[tuple[float, float], ...]  # (μ, e) fitted per fold (grid resolution)


def held_out(table: ErrorTable, objective: str, folds: int = 5, seed: int = 0) -> HeldOut:
    """K-fold by drop (:func:`cross_validate`): fit on the other folds (grid resolution),
    score the held-out one."""
    folded = cross_validate(table.errors[objective],
                            lambda errors: metric.aggregate(objective, errors), folds, seed)
    fits = tuple((float(table.mus[i]), float(table.es[j])) for i, j in folded.cells)
    return HeldOut(folds, float(np.mean(folded.in_sample)), float(np.mean(folded.held_out)),
                   fits)


@dataclass(frozen=True)
class Interval:
    low: float
    high: float


def percentile_interval(values, confidence: float = 0.95,
                        method: str = "linear") -> Interval:
    """The central ``confidence`` percentile interval of ``values`` (bootstrap replicates);
    ``method`` as numpy's percentile (``"inverted_cdf"`` keeps both ends on values taken)."""
    tails = 100 * (1 - confidence) / 2, 100 * (1 + confidence) / 2
    return Interval(*(float(x) for x in np.percentile(values, tails, method=method)))


def resampled_rows(drops: int, replicates: int, seed: int):
    """``replicates`` bootstrap samples of ``drops`` row indices, drawn with replacement
    with ``seed``, one array at a time."""
    rng = np.random.default_rng(seed)
    for _ in range(replicates):
        yield rng.integers(0, drops, drops)


@dataclass(frozen=True)
class Bootstrap:
    replicates: int
    confidence: float
    mu: Interval
    e: Interval
    value: Interval
    step: float  # the local grid's step: the intervals' resolution
    at_window_edge: int  # replicates whose optimum hit the local grid's edge (interval clipped)
    fits: np.ndarray  # (replicates, 2) the refitted (μ, e)


def bootstrap(drop_errors: DropErrors, fitted: Fit, replicates: int = 200, seed: int = 0,
              span: float = 0.03, step: float = 0.002, confidence: float = 0.95) -> Bootstrap:
    """Percentile intervals of (μ, e) and the objective: drops resampled with replacement,
    each sample refitted on a local grid of ``step`` within ``span`` of the full-data fit
    (kept inside μ ≥ 0, 0 ≤ e ≤ 1). Replicates whose optimum reaches the local grid's edge
    inside those bounds are counted: with any, the interval is clipped and says so."""
    def local(centre, high):
        return np.round(np.arange(max(centre - span, 0.0), min(centre + span, high) + step / 2,
                                  step), 12)

    mus, es = local(fitted.mu, np.inf), local(fitted.e, 1.0)
    table = error_table(drop_errors, fitted.law, mus, es).errors[fitted.objective]
    fits, values, edge = np.empty((replicates, 2)), np.empty(replicates), 0
    for r, rows in enumerate(resampled_rows(table.shape[-1], replicates, seed)):
        grid = metric.aggregate(fitted.objective, table[..., rows])
        a, b = best_cell(grid)
        edge += bool((a == 0 and mus[0] > 0) or a == mus.size - 1
                     or (b == 0 and es[0] > 0) or (b == es.size - 1 and es[-1] < 1))
        fits[r] = mus[a], es[b]
        values[r] = grid[a, b]
    interval = [percentile_interval(x, confidence) for x in (fits[:, 0], fits[:, 1], values)]
    return Bootstrap(replicates, confidence, *interval, step, edge, fits)
