"""The verdicts of many engine runs at once (:func:`judge_many`): :func:`judge`'s status and
reasons, the same to the last run, its checks done as arrays over every run.

A run the arrays cannot settle the same way as :func:`judge` (an engine status other than
ok or multi-contact, non-finite speeds, a mass matrix that is not diagonal, a value within
:data:`NEAR` of its bound) goes through :func:`judge` itself. :func:`prepare_many` works out
many scenes' :class:`SceneTerms` with their Delassus solves stacked.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from harness.engines import Status
from harness.run import metrics
from harness.run.verdicts.checks import (
    RUN_CAP_BAND,
    numbers_from_run,
    reported_caps,
    speed_caps,
)
from harness.run.verdicts.reasons import DEFAULT_TOLERANCES, REASONS, Tolerances, status_of
from harness.run.verdicts.single import SceneTerms, judge, prepare_from
from harness.run.verdicts.touching import second_features_many


def prepare_many(scenes: Sequence, problems: Sequence) -> list[SceneTerms]:
    """:func:`prepare` of every scene."""
    return [prepare_from(scene, problem, delassus) for scene, problem, delassus
            in zip(scenes, problems, _delassus_many(problems), strict=True)]


def _delassus_many(problems: Sequence) -> list[tuple[float, float, float]]:
    """``metrics.delassus`` of every problem, its solves stacked by the mass matrix's size:
    numpy's stacked solve makes the same LAPACK call per matrix as a single one, and each
    product is the same 1-D product on the same operands, so the values are the same."""
    found: list = [None] * len(problems)
    sizes: dict[tuple[int, ...], list[int]] = {}
    for row, problem in enumerate(problems):
        sizes.setdefault(np.shape(problem.mass_matrix), []).append(row)
    for shape, rows in sizes.items():
        if len(shape) != 2:  # not a matrix: metrics.delassus says what is wrong
            for row in rows:
                found[row] = metrics.delassus(problems[row])
            continue
        matrices = np.array([problems[row].mass_matrix for row in rows], dtype=float)
        columns = np.array([np.stack([problems[row].wn, problems[row].wt], axis=1)
                            for row in rows], dtype=float)
        for row, inverse_w in zip(rows, np.linalg.solve(matrices, columns)):
            wn, wt = problems[row].wn, problems[row].wt
            wn_inv, wt_inv = inverse_w[:, 0], inverse_w[:, 1]
            found[row] = float(wn @ wn_inv), float(wn @ wt_inv), float(wt @ wt_inv)
    return found


#: Columns of :class:`TermArrays` (two bodies × ``(v_x, v_y, ω)``; a ground scene is padded).
ARRAY_WIDTH = 6


#: How near its bound (relative to the rounding scale of the quantity) a value of the batched
#: checks sends its run to :func:`judge`: the batched arithmetic (sums over the padded
#: columns, a diagonal ``M`` divided out) rounds differently from :func:`judge`'s in the last
#: bits, ~1e-16 of that scale; 1e-9 is a wide margin, and rarely reached (a value must lie
#: within 1e-9 of its bound).
NEAR = 1e-9


@dataclass(frozen=True)
class TermArrays:
    """The :class:`SceneTerms` and impacts of many scenes as row arrays (:func:`term_arrays`),
    for :func:`judge_many`. Rows whose mass matrix is not diagonal are ``diagonal`` False."""

    mass: np.ndarray  # (n, 6) diagonal of M, 1 where padded
    u: np.ndarray  # (n, 6) speeds before, 0 where padded
    wn: np.ndarray  # (n, 6)
    wt: np.ndarray  # (n, 6)
    dofs: np.ndarray  # (n,) 3 or 6
    diagonal: np.ndarray  # (n,) bool
    delassus: np.ndarray  # (n, 3) SceneTerms.delassus
    approach: np.ndarray  # (n,) SceneScales fields
    impulse: np.ndarray
    speed_norm: np.ndarray
    energy: np.ndarray
    size: np.ndarray
    norm_before: np.ndarray  # (n,) SceneTerms.norm_before
    one_feature: np.ndarray  # (n,) bool

    def rows(self, begin: int, end: int) -> TermArrays:
        """Rows ``begin:end``."""
        return TermArrays(*(getattr(self, name)[begin:end] for name in self.__dataclass_fields__))


def term_arrays(problems: Sequence, terms: Sequence[SceneTerms]) -> TermArrays:
    """The :class:`TermArrays` of ``problems`` and their :func:`prepare` ``terms``."""
    count = len(problems)
    mass = np.ones((count, ARRAY_WIDTH))
    u, wn, wt = (np.zeros((count, ARRAY_WIDTH)) for _ in range(3))
    dofs = np.zeros(count, dtype=np.int64)
    diagonal = np.zeros(count, dtype=bool)
    for row, problem in enumerate(problems):
        matrix = np.asarray(problem.mass_matrix, dtype=float)
        size = len(problem.u)
        if size > ARRAY_WIDTH:
            continue  # not diagonal: judged one by one
        dofs[row] = size
        diagonal[row] = not np.count_nonzero(matrix - np.diag(np.diag(matrix)))
        mass[row, :size] = np.diag(matrix)
        u[row, :size], wn[row, :size], wt[row, :size] = problem.u, problem.wn, problem.wt
    scales = [term.scales for term in terms]
    return TermArrays(
        mass, u, wn, wt, dofs, diagonal & np.all(mass > 0, axis=1),
        np.array([term.delassus for term in terms], dtype=float).reshape(count, 3),
        *(np.array([getattr(s, name) for s in scales], dtype=float)
          for name in ("approach_speed", "impulse", "speed_norm", "energy", "size")),
        np.array([term.norm_before for term in terms], dtype=float),
        np.array([term.one_feature for term in terms], dtype=bool))


def judge_many(scenes: Sequence, problems: Sequence, runs: Sequence, u_after: np.ndarray,
               terms: Sequence[SceneTerms], arrays: TermArrays, *,
               law_energy_change=None,
               tolerances: Tolerances = DEFAULT_TOLERANCES) -> list[tuple[str, str]]:
    """``(status, failing reasons comma-separated)`` of every engine run (``EngineRun``) of
    ``scenes``: :func:`judge`'s ``Verdict.status`` and ``names``, the same to the last run.

    The checks of :func:`judge` on every run at once, as arrays (``u_after``: the runs'
    speeds, ``(n, 6)`` padded like :class:`TermArrays`; ``arrays``: :func:`term_arrays` of the
    scenes). A run goes through :func:`judge` itself when the batch cannot settle it the same
    way: an engine status other than ok or multi-contact, non-finite speeds, a mass matrix
    that is not diagonal, or a value within :data:`NEAR` of its bound (where the batch's
    roundings could decide otherwise). The second-feature check (``multi-contact``) is
    :func:`judge`'s own, run by run.
    """
    count = len(runs)
    if not count:
        return []
    tol = tolerances
    # str(status) is a Python-level call per run; the values by status, one lookup each
    status = [_STATUS_VALUES.get(run.status) or run.status.value for run in runs]
    depths = [run.max_penetration for run in runs]
    penetration = np.array([math.nan if depth is None else depth for depth in depths],
                           dtype=float)
    engine_impulse = np.full((count, 2), np.nan)
    impulse_checked = np.zeros(count, dtype=bool)
    run_caps = np.full((count, 2), np.nan)
    # gathered in lists and written at once (an array's item assignment is a slow
    # Python call each)
    impulse_rows, impulses, cap_rows, caps_found = [], [], [], []
    for row, run in enumerate(runs):
        if run.normal_impulse is not None and run.impulse_source != "momentum":
            impulse_rows.append(row)
            impulses.append((run.normal_impulse, run.tangential_impulse or 0.0))
        caps = reported_caps(run.derived or {})
        if caps is not None:
            cap_rows.append(row)
            caps_found.append(caps)
    if impulse_rows:
        impulse_checked[impulse_rows] = True
        engine_impulse[impulse_rows] = impulses
    if cap_rows:
        run_caps[cap_rows] = caps_found
    batched = (np.isin(status, ("ok", "multi-contact")) & np.isfinite(u_after).all(axis=1)
               & arrays.diagonal & np.isfinite(penetration))
    near = np.zeros(count, dtype=bool)
    fails = {}
    with np.errstate(all="ignore"):
        # clipped: the run's own caps on |v| and |ω| (Box2D), else the engine's fixed ones
        clipped = np.zeros(count, dtype=bool)
        has_caps = ~np.isnan(run_caps[:, 0])
        band = 1.0 - max(tol.cap, RUN_CAP_BAND)
        for speeds in (arrays.u, u_after):
            for body in range(ARRAY_WIDTH // 3):
                present = has_caps & (arrays.dofs > 3 * body)
                speed = np.hypot(speeds[:, 3 * body], speeds[:, 3 * body + 1])
                rate = np.abs(speeds[:, 3 * body + 2])
                for value, cap in ((speed, band * run_caps[:, 0]), (rate, band * run_caps[:, 1])):
                    clipped |= present & (value >= cap)
                    near |= present & (np.abs(value - cap) <= NEAR * np.abs(cap))
        engines = {run.engine for run in runs}
        for name in sorted(engines):
            caps = speed_caps(name)
            if caps is None:
                continue
            rows = np.array([run.engine == name for run in runs]) & ~has_caps
            linear, angular = caps
            bounds = np.array([linear, linear, angular] * (ARRAY_WIDTH // 3)) * (1.0 - tol.cap)
            for speeds in (arrays.u, u_after):
                clipped |= rows & (np.abs(speeds) >= bounds).any(axis=1)
        fails["clipped"] = clipped
        # not-separated
        products = arrays.wn * u_after
        vn_after = products.sum(axis=1)
        bound = tol.separation * arrays.approach
        fails["not-separated"] = vn_after < -bound
        near |= np.abs(vn_after + bound) <= NEAR * (np.abs(products).sum(axis=1) + bound)
        # penetration: the same product and comparison as penetration_reasons
        fails["penetration"] = ~(penetration <= tol.penetration * arrays.size)
        # impulse-residual: (A22)/(A23) with M diagonal
        delta = u_after - arrays.u
        dvn, dvt = (arrays.wn * delta).sum(axis=1), (arrays.wt * delta).sum(axis=1)
        mnn, mnt, mtt = arrays.delassus.T
        det = mnn * mtt - mnt * mnt
        conditioning = 1.0 + (mnn * mtt + mnt * mnt) / np.abs(det)
        normal = (mtt * dvn - mnt * dvt) / det
        tangential = (mnn * dvt - mnt * dvn) / det
        explained = (arrays.wn * normal[:, None] + arrays.wt * tangential[:, None]) / arrays.mass
        rest = np.sqrt(np.sum(arrays.mass * (delta - explained) ** 2, axis=1))
        residual = rest / arrays.speed_norm
        fails["impulse-residual"] = residual > tol.impulse_residual
        spread = (np.sqrt(np.sum(arrays.mass * delta**2, axis=1))
                  + np.sqrt(np.sum(arrays.mass * explained**2, axis=1))) / arrays.speed_norm
        near |= ~(np.abs(residual - tol.impulse_residual) > NEAR * conditioning * (1.0 + spread))
        # impulse-mismatch: the engine's own impulse against the implied one
        gap = np.hypot(engine_impulse[:, 0] - normal, engine_impulse[:, 1] - tangential)
        relative = gap / arrays.impulse
        fails["impulse-mismatch"] = impulse_checked & (relative > tol.impulse)
        sizes = (np.abs(engine_impulse).sum(axis=1) + np.abs(normal)
                 + np.abs(tangential)) / arrays.impulse
        near |= impulse_checked & ~(np.abs(relative - tol.impulse)
                                    > NEAR * conditioning * (1.0 + sizes))
        # energy-gain: only a gain beyond the law's fails
        after = np.sum(arrays.mass * u_after**2, axis=1)
        before = arrays.norm_before**2
        gain = 0.5 * (after - before)
        energy_bound = tol.energy * arrays.energy
        rounding = NEAR * (after + before)
        gains = gain > energy_bound
        near |= ~(np.abs(gain - energy_bound) > rounding)
        if law_energy_change is not None:
            law = np.asarray(law_energy_change, dtype=float)
            beyond = law + tol.energy_beyond_law * arrays.energy
            by_law = (law > energy_bound) & (gain <= beyond)
            near |= (law > energy_bound) & ~(np.abs(gain - beyond) > rounding + NEAR * np.abs(law))
            gains &= ~by_law
        fails["energy-gain"] = gains
    batched &= ~near
    checked = {name: flags.tolist() for name, flags in fails.items()}
    featured = np.flatnonzero(batched & ~arrays.one_feature).tolist()
    checked["multi-contact"] = [False] * count
    for row, second in zip(featured, second_features_many(
            [runs[row].contact_record for row in featured],
            [terms[row].features for row in featured], tol,
            [scenes[row] for row in featured])):
        checked["multi-contact"][row] = second
    failing = np.zeros(count, dtype=bool)  # a batched reason fails (names to list)
    for flags in fails.values():
        failing |= flags
    failing |= np.asarray(checked["multi-contact"], dtype=bool)
    unjudged = (~batched).tolist()
    failing = failing.tolist()
    results = []
    for row, run in enumerate(runs):
        if unjudged[row]:
            gain = None if law_energy_change is None else float(law_energy_change[row])
            verdict = judge(scenes[row], problems[row], numbers_from_run(run),
                            law_energy_change=gain, tolerances=tol, terms=terms[row])
            results.append((verdict.status(status[row]), ",".join(verdict.names)))
        elif failing[row]:
            names = tuple(name for name in _BATCHED_REASONS if checked[name][row])
            results.append((status_of(status[row], names), ",".join(names)))
        else:
            results.append((status_of(status[row], ()), ""))
    return results


#: Every engine status's value, by status (:func:`judge_many`).
_STATUS_VALUES = {status: status.value for status in Status}


#: The reasons :func:`judge_many` checks as arrays, in :data:`REASONS` order.
_BATCHED_REASONS = tuple(name for name in REASONS
                         if name in ("clipped", "multi-contact", "not-separated", "penetration",
                                     "impulse-residual", "impulse-mismatch", "energy-gain"))


__all__ = ["ARRAY_WIDTH", "NEAR", "TermArrays", "judge_many", "prepare_many", "term_arrays"]
