"""Departures of every run and their statistics per engine × preset × family × collision type.

Departure is the harness's one error measure, ``‖u − u_law‖_M / s`` with ``s`` the frame-free
speed scale (the ground's frame, or the centre of mass's for two free bodies), computed for
every row at once by :func:`harness.run.metrics.departure_batch`; the split of an engine's
departure from Poisson follows harness/run/metrics.py: ``law_part`` = newton-lcp from
Poisson (the same for every engine), ``solve_part`` = the engine from newton-lcp.

Statistics are over the runs whose verdict is one impact (status ``ok``,
harness/run/verdicts/): a flagged run (the engine's status, or a failing verdict check:
a second feature touched, still closing, deep penetration, Δu not one impulse at the
contact, a numerics energy gain, …) is not the answer to one impact, so it is counted under
each reason it fails instead. A run the engine did not finish -- it could not build the
scene (``skipped``) or raised (``error``, harness/survey/engines.py) -- has no speeds: it is
in no group's ``n`` and counted apart (``n_skipped``, ``n_error``). A run *gains energy*
when its kinetic energy after exceeds the energy before by more than
:data:`ENERGY_GAIN_TOLERANCE` of it.
"""

from __future__ import annotations

import math
import zlib

import numpy as np

from harness.run import metrics, verdicts
from harness.survey.engines import ERROR, SKIPPED

#: Relative energy increase above which a run counts as gaining energy: engines' rounding is
#: ~1e-15 of the energy and their iterative solvers stop ~1e-12 from their law; a gain a
#: million times that is the law's or the numerics', not rounding.
ENERGY_GAIN_TOLERANCE = 1e-9
#: Quantiles reported, as (column suffix, quantile).
QUANTILES = (("median", 0.5), ("p90", 0.9), ("p99", 0.99), ("max", 1.0))
ALL_TYPES = 0  # the collision-type column's value for the row over every type
#: Quantiles of the departure from Poisson given a bootstrap interval, over the checked runs
#: and over all runs (flagged included): (column suffix, quantile).
INTERVAL_QUANTILES = (("median", 0.5), ("p90", 0.9))
#: Bootstrap resamples per group and the interval's coverage: 1,000 resamples put the ends
#: of a 95% percentile interval within about ±1 rank of where 10,000 would.
BOOTSTRAP_RESAMPLES = 1000
INTERVAL = 0.95
#: Most resampled values drawn at once (8 bytes each as indices, 8 as values: 16 MB): a
#: group of up to 1,000 runs draws its 1,000 resamples in one block.
BOOTSTRAP_BLOCK = 1_000_000
#: The bootstrap's seed: the intervals are a function of the runs alone (a rerun, or the
#: same runs on another machine, gives the same intervals).
BOOTSTRAP_SEED = 20170529


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
            "error": result.errors,
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


def _sorted_codes(values) -> tuple[np.ndarray, np.ndarray]:
    """``numpy.unique(values, return_inverse=True)`` of a column of few distinct texts: each
    text coded in order of appearance by a dict, then the few codes ranked by sorting the
    distinct texts (numpy sorts every row's text, ~5x the time)."""
    array = np.asarray(values)
    first_seen: dict = {}
    codes = np.fromiter((first_seen.setdefault(value, len(first_seen))
                         for value in array.tolist()), dtype=np.intp, count=len(array))
    distinct = np.asarray(list(first_seen), dtype=array.dtype)
    order = np.argsort(distinct, kind="stable")
    rank = np.empty(len(order), dtype=np.intp)
    rank[order] = np.arange(len(order))
    return distinct[order], rank[codes]


def statistics(runs: dict) -> dict:
    """Columns of ``statistics.parquet``: one row per engine × preset × family × Poisson type,
    plus a row per engine × preset × family over every type (``poisson_type`` = 0)."""
    status = np.asarray(runs["status"])
    not_run = np.isin(status, (SKIPPED, ERROR)) if len(runs["engine"]) else ()
    # the engine could not build the scene (skipped) or raised (error): counted, not judged
    not_run_counts: dict[str, dict[tuple, int]] = {SKIPPED: {}, ERROR: {}}
    if np.any(not_run):
        for key in zip(*(np.asarray(runs[name])[not_run].tolist()
                         for name in ("status", "engine", "preset", "family", "poisson_type"))):
            counts = not_run_counts[key[0]]
            for kind in (key[4], ALL_TYPES):
                group = (*key[1:4], int(kind))
                counts[group] = counts.get(group, 0) + 1
        runs = {name: np.asarray(values)[~not_run] for name, values in runs.items()}
    count = len(runs["engine"])
    if not count:
        return {}
    # Each key column as codes in sorted order, so the groups come out sorted as tuples.
    names, codes = zip(*(_sorted_codes(runs[key]) for key in ("engine", "preset", "family")))
    kinds = np.asarray(runs["poisson_type"]).astype(np.int64)
    kind_names, kind_codes = np.unique(np.concatenate([kinds, np.full(count, ALL_TYPES)]),
                                       return_inverse=True)
    # every run twice: under its Poisson type and under every type
    pair = np.concatenate([codes[0] * len(names[1]) + codes[1]] * 2)
    family = np.concatenate([codes[2]] * 2)
    group = (pair * len(names[2]) + family) * len(kind_names) + kind_codes
    rows_of = np.tile(np.arange(count), 2)
    order = np.argsort(group, kind="stable")
    present, starts, sizes = np.unique(group[order], return_index=True, return_counts=True)
    member = rows_of[order]  # runs, group after group
    # Per run, once: one-impact or not, and each reason it fails (a run failing several
    # reasons counts under each); the reasons' texts are few, each split once.
    ok_runs = np.asarray(runs["status"]) == "ok"
    texts, text_of = _sorted_codes(runs["reasons"])
    failing = [set(filter(None, text.split(","))) for text in texts.tolist()]
    fails = np.array([[name in names_ for names_ in failing] for name in verdicts.REASONS],
                     dtype=bool).reshape(len(verdicts.REASONS), len(texts))[:, text_of]
    group_of = np.repeat(np.arange(len(present)), sizes)
    n_ok = np.bincount(group_of, weights=ok_runs[member], minlength=len(present))
    flagged = [np.bincount(group_of, weights=fails[place][member], minlength=len(present))
               for place in range(len(verdicts.REASONS))]
    ok_member = ok_runs[member]
    gains = np.asarray(runs["gains_energy"])[member]
    gains_ok = np.bincount(group_of, weights=gains & ok_member, minlength=len(present))
    columns = {column: np.asarray(runs[column])[member]
               for column in ("departure_poisson", "departure_stronge", "law_part",
                              "solve_part")}
    rows = []
    pairs, families = len(names[1]), len(names[2])
    for place, (code, start, size) in enumerate(zip(present.tolist(), starts.tolist(),
                                                    sizes.tolist())):
        kind = int(kind_names[code % len(kind_names)])
        rest = code // len(kind_names)
        family_code, pair_code = rest % families, rest // families
        ok_count = int(n_ok[place])
        row = {"engine": str(names[0][pair_code // pairs]),
               "preset": str(names[1][pair_code % pairs]),
               "family": str(names[2][family_code]), "poisson_type": kind,
               "n": size, "n_ok": ok_count, "flagged_fraction": 1.0 - ok_count / size}
        for name, counted in zip(verdicts.REASONS, flagged):
            row[f"flagged_{name}"] = int(counted[place]) / size
        row["energy_gain_fraction"] = (int(gains_ok[place]) / ok_count if ok_count
                                       else math.nan)
        ok_here = ok_member[start:start + size]
        for column, values in columns.items():
            row.update(_quantiles(values[start:start + size][ok_here], column))
        rows.append(row)
    # After every group's own columns (the columns above keep their order and bits): the
    # departure from Poisson over all runs, and bootstrap intervals of its median and p90
    # over the checked runs and over all runs -- a flagged share hides no bad run, and a
    # quantile of 20 runs says how rough it is.
    poisson = columns["departure_poisson"]
    for row, start, size in zip(rows, starts.tolist(), sizes.tolist()):
        values = poisson[start:start + size]
        values_ok = values[ok_member[start:start + size]]
        every = _quantiles(values, "departure_poisson_all")
        row.update({f"departure_poisson_all_{name}": every[f"departure_poisson_all_{name}"]
                    for name, _ in INTERVAL_QUANTILES})
        # each group its own stream, keyed by the group: its intervals do not depend on
        # which other groups the survey has
        key = f"{row['engine']}\0{row['preset']}\0{row['family']}\0{row['poisson_type']}"
        generator = np.random.default_rng([BOOTSTRAP_SEED, zlib.crc32(key.encode())])
        for subset, prefix in ((values_ok, "departure_poisson"),
                               (values, "departure_poisson_all")):
            row.update(bootstrap_interval(subset[np.isfinite(subset)], prefix, generator))
        group = (row["engine"], row["preset"], row["family"], row["poisson_type"])
        row["n_skipped"] = not_run_counts[SKIPPED].get(group, 0)
        row["n_error"] = not_run_counts[ERROR].get(group, 0)
    return {key: np.asarray([row[key] for row in rows]) for key in rows[0]}


def bootstrap_interval(values: np.ndarray, prefix: str, generator) -> dict:
    """Percentile-bootstrap intervals (:data:`INTERVAL`) of the median and p90 of
    ``values``: ``{prefix}_median_low``, ``…_median_high``, ``{prefix}_p90_low`` … (nan for
    fewer than two values, where resampling says nothing)."""
    names = [f"{prefix}_{name}_{end}" for name, _ in INTERVAL_QUANTILES
             for end in ("low", "high")]
    if values.size < 2:
        return dict.fromkeys(names, math.nan)
    # In blocks of resamples of at most BOOTSTRAP_BLOCK values: the memory of a group of
    # any size is bounded (one block for up to BOOTSTRAP_BLOCK / 1,000 values, as before).
    # Each block's quantiles from its draws' counts over the sorted values
    # (:func:`resample_quantiles`: np.quantile's bits, without partitioning every resample).
    block = max(1, BOOTSTRAP_BLOCK // values.size)
    order = np.argsort(values, kind="stable")
    # + 0.0: a -0.0 read as +0.0. Equal to +0.0, it sorts among the zeros anywhere, and
    # np.quantile's partition returns either sign of a tie at its own choice: with one
    # sign of zero the counts' order statistics are np.quantile's bits.
    ordered = values[order] + 0.0
    rank = np.empty(values.size, dtype=np.intp)
    rank[order] = np.arange(values.size)
    quantiles = [q for _, q in INTERVAL_QUANTILES]
    estimates = np.concatenate([
        resample_quantiles(ordered, rank[generator.integers(0, values.size, size=(
            min(block, BOOTSTRAP_RESAMPLES - first), values.size))], quantiles,
            overwrite=True)
        for first in range(0, BOOTSTRAP_RESAMPLES, block)], axis=1)
    tail = (1.0 - INTERVAL) / 2.0
    ends = np.quantile(estimates, [tail, 1.0 - tail], axis=1)  # (2 ends, quantiles)
    return {name: float(ends[end, quantile]) for quantile in range(len(INTERVAL_QUANTILES))
            for end, name in enumerate(names[2 * quantile:2 * quantile + 2])}


def resample_quantiles(ordered: np.ndarray, ranks: np.ndarray, quantiles,
                       overwrite: bool = False) -> np.ndarray:
    """``numpy.quantile(ordered[ranks], quantiles, axis=1)`` (its default, 'linear' method)
    to the last bit, for ``ordered`` finite and sorted, its zeros of one sign (numpy's
    partition picks either of -0.0 and +0.0 at its own choice), and ``ranks`` a ``(resamples, n)``
    block of indices into it, each row as long as ``ordered``: each row's order statistics
    from how often it drew each rank (the counts' running sum over the block, searched), then
    numpy's own interpolation (``_get_indexes``, ``_get_gamma`` and ``_lerp`` of
    numpy/lib/_function_base_impl.py, the same operations on the same values) -- no
    partition of every resample (tests/survey/test_laws_and_statistics.py compares).
    ``overwrite``: ``ranks`` may be overwritten (a block's array fewer: each fresh array of
    a few MB costs its page faults, more than the arithmetic).
    """
    rows, count = ranks.shape
    # running count of draws up to each rank, row after row: row j's counts sum to
    # (j + 1) * count, so the whole block's running sum is one increasing array
    offsets = np.arange(rows, dtype=np.intp)[:, None] * count
    placed = np.add(ranks, offsets, out=ranks if overwrite else None)
    running = np.bincount(placed.ravel(), minlength=rows * count)
    del placed
    np.cumsum(running, out=running)
    virtual = (count - 1) * np.asanyarray(quantiles, dtype=float)  # numpy's 'linear' index
    previous = np.floor(virtual)
    following = previous + 1
    above = virtual >= count - 1
    previous[above] = -1
    following[above] = -1
    gamma = np.asanyarray(virtual - previous, dtype=virtual.dtype)[:, None]
    previous, following = previous.astype(np.intp), following.astype(np.intp)

    def order_statistic(position):
        # the value of sorted rank `position` (-1: the last) of each resample: the first
        # rank whose running count passes it
        position = np.where(position < 0, count + position, position)
        targets = offsets + position[None, :]  # (rows, quantiles)
        found = np.searchsorted(running, targets, side="right") - offsets
        return ordered[found].T  # (quantiles, rows)

    low, high = order_statistic(previous), order_statistic(following)
    step = high - low
    result = np.add(low, step * gamma)
    np.subtract(high, step * (1 - gamma), out=result, where=gamma >= 0.5,
                casting="unsafe", dtype=type(result.dtype))
    return result
