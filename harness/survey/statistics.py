"""Departures of every run and their statistics per engine × preset × family × collision type.

Departure is the harness's one error measure, ``‖u − u_law‖_M / s`` with ``s`` the frame-free
speed scale (the ground's frame, or the centre of mass's for two free bodies), computed for
every row at once by :func:`harness.run.metrics.departure_batch`; the split of an engine's
departure from Poisson follows harness/run/metrics.py: ``law_part`` = newton-lcp from
Poisson (the same for every engine), ``solve_part`` = the engine from newton-lcp.

Statistics are over the runs whose verdict is one impact (status ``ok``,
harness/run/verdicts.py): a flagged run (the engine's status, or a failing verdict check:
a second feature touched, still closing, deep penetration, Δu not one impulse at the
contact, a numerics energy gain, …) is not the answer to one impact, so it is counted under
each reason it fails instead. A run *gains energy* when its kinetic energy after exceeds
the energy before by more than :data:`ENERGY_GAIN_TOLERANCE` of it.
"""

from __future__ import annotations

import math

import numpy as np

from harness.run import metrics, verdicts

#: Relative energy increase above which a run counts as gaining energy: engines' rounding is
#: ~1e-15 of the energy and their iterative solvers stop ~1e-12 from their law; a gain a
#: million times that is the law's or the numerics', not rounding.
ENERGY_GAIN_TOLERANCE = 1e-9
#: Quantiles reported, as (column suffix, quantile).
QUANTILES = (("median", 0.5), ("p90", 0.9), ("p99", 0.99), ("max", 1.0))
ALL_TYPES = 0  # the collision-type column's value for the row over every type


def row_departures(terms, u, u_law, scales=None) -> np.ndarray:
    """``departure(u[i], u_law[i])`` for every row (:func:`metrics.departure_batch`);
    ``scales``: :func:`row_scales` of ``terms``, for many departures of the same rows."""
    scales = row_scales(terms) if scales is None else scales
    return scales.departures(u, u_law)


def row_scales(terms) -> metrics.RowScales:
    """The mass matrices and frame-free scales of every row, computed once."""
    return metrics.RowScales(terms.mass, terms.u, free_bodies=terms.free_bodies)


def relative_energy_change(terms, u_after) -> np.ndarray:
    """``(E_after − E_before) / E_before`` per row (kinetic energies ``½ uᵀMu``)."""
    before = np.sum(terms.mass * terms.u**2, axis=1)
    after = np.sum(terms.mass * u_after**2, axis=1)
    return (after - before) / before


def run_columns(family, sample_index, terms, laws, routh, engine_results) -> dict:
    """One row per (sample, engine, preset): the columns of ``runs.parquet``."""
    u_poisson, u_stronge = laws["poisson"].u_after, laws["stronge"].u_after
    u_lcp = laws["newton-lcp"].u_after
    scales = row_scales(terms)
    law_part = row_departures(terms, u_lcp, u_poisson, scales)
    poisson_type = laws["poisson"].batch.collision_type.astype(np.int64)
    columns: dict[str, list] = {}
    for result in engine_results:
        gain = relative_energy_change(terms, result.velocities)
        block = {
            "family": family,
            "sample": sample_index,
            "engine": np.full(len(terms), result.engine),
            "preset": np.full(len(terms), result.preset),
            "status": result.status,
            "engine_status": result.engine_status,
            "reasons": result.reasons,
            "steps": result.steps,
            "poisson_type": poisson_type,
            "alpha": routh["alpha"],
            "r_m": routh["r_m"],
            "alpha_over_rm": routh["alpha_over_rm"],
            "mu": terms.mu,
            "e": terms.e,
            "departure_poisson": row_departures(terms, result.velocities, u_poisson, scales),
            "departure_stronge": row_departures(terms, result.velocities, u_stronge, scales),
            "law_part": law_part,
            "solve_part": row_departures(terms, result.velocities, u_lcp, scales),
            "energy_change_relative": gain,
            "gains_energy": gain > ENERGY_GAIN_TOLERANCE,
        }
        for key, values in block.items():
            columns.setdefault(key, []).append(np.asarray(values))
    return {key: np.concatenate(parts) for key, parts in columns.items()}


def _quantiles(values: np.ndarray, prefix: str) -> dict:
    finite = np.sort(values[np.isfinite(values)]).tolist()
    if not finite:
        return {f"{prefix}_{name}": math.nan for name, _ in QUANTILES}
    return {f"{prefix}_{name}": linear_quantile(finite, q) for name, q in QUANTILES}


def linear_quantile(ordered: list, q: float) -> float:
    """``numpy.quantile(values, q)`` (its default, 'linear' method) of ``ordered``, the
    values sorted, to the last bit: the value at the virtual index ``(n − 1) q``, between
    its neighbours ``a``, ``b`` with weight ``γ``, as ``a + (b − a) γ`` below ``γ = ½`` and
    ``b − (b − a)(1 − γ)`` from it; at or beyond the last index, the last value (numpy's
    index −1 and ``γ = virtual + 1``). numpy spends ~20x the arithmetic on dispatch for the
    few values of one group (tests/survey/test_laws_and_statistics.py compares).
    """
    count = len(ordered)
    virtual = (count - 1) * q
    if virtual >= count - 1:
        below = above = -1
    else:
        below = math.floor(virtual)
        above = below + 1
    low, high = ordered[below], ordered[above]
    gamma = virtual - below
    step = high - low
    return high - step * (1 - gamma) if gamma >= 0.5 else low + step * gamma


def statistics(runs: dict) -> dict:
    """Columns of ``statistics.parquet``: one row per engine × preset × family × Poisson type,
    plus a row per engine × preset × family over every type (``poisson_type`` = 0)."""
    keys = list(zip(runs["engine"].tolist(), runs["preset"].tolist(), runs["family"].tolist(),
                    runs["poisson_type"].tolist()))
    groups: dict[tuple, list[int]] = {}
    for row, (engine, preset, family, kind) in enumerate(keys):
        groups.setdefault((engine, preset, family, int(kind)), []).append(row)
        groups.setdefault((engine, preset, family, ALL_TYPES), []).append(row)
    # Per run, once: one-impact or not, and each reason it fails (a run failing several
    # reasons counts under each).
    ok_runs = runs["status"] == "ok"
    failing = [set(filter(None, text.split(","))) for text in runs["reasons"].tolist()]
    fails = np.array([[name in names for names in failing] for name in verdicts.REASONS],
                     dtype=bool).reshape(len(verdicts.REASONS), len(failing))
    rows = []
    for (engine, preset, family, kind), indices in sorted(groups.items()):
        index = np.asarray(indices)
        size = int(index.size)
        ok = ok_runs[index]
        n_ok = int(ok.sum())
        row = {"engine": engine, "preset": preset, "family": family, "poisson_type": kind,
               "n": size, "n_ok": n_ok, "flagged_fraction": 1.0 - n_ok / size}
        for name, count in zip(verdicts.REASONS, fails[:, index].sum(axis=1).tolist()):
            row[f"flagged_{name}"] = count / size
        ok_index = index[ok]
        row["energy_gain_fraction"] = (int(runs["gains_energy"][ok_index].sum()) / n_ok
                                       if n_ok else math.nan)
        for column in ("departure_poisson", "departure_stronge", "law_part", "solve_part"):
            row.update(_quantiles(runs[column][ok_index], column))
        rows.append(row)
    return {key: np.asarray([row[key] for row in rows]) for key in rows[0]} if rows else {}
