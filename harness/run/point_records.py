"""The records of one sweep point: each law's solution, and each engine run's record from its
raw output -- departures from every law, the impulses, the contact history, and the verdict
(:mod:`harness.run.verdicts`: is the run the single impact its reference describes).

A fault of the harness on a point costs that point's records (status ``"error: internal:
..."``), never the run (:func:`point_records_or_errors`).
"""

from __future__ import annotations

import math
import time
from typing import Sequence

import numpy as np

from harness.laws import broken_promises
from harness.run import metrics, references, verdicts
from harness.run.history import contact_history
from harness.run.plan import engine_scene, point_reference_cached
from harness.run.records import ANALYTIC, Record
from harness.scenarios import Scenario


def point_dict(point) -> dict:
    return {"index": point.index, "parameter": point.parameter, "value": point.value,
            "label": point.label}


def point_records_or_errors(scenario: Scenario, point, engine_entries: Sequence, *,
                             cache=None, reference: dict | None = None) -> list[Record]:
    """:func:`point_records`, or, when the harness fails on this point, one record per law
    and engine run with status ``"error: internal: ..."``: one bad point costs its records,
    not the run."""
    try:
        return point_records(scenario, point, engine_entries, cache=cache,
                             reference=reference)
    except Exception as error:  # noqa: BLE001 - a harness bug: in the records, exit status 3
        status = f"error: internal: {type(error).__name__}: {error}"
        info = point_dict(point)
        return ([Record(scenario=scenario.name, point=info, source=ANALYTIC, law=law,
                        status=status) for law in scenario.laws]
                + [Record(scenario=scenario.name, point=info, source=engine_name, preset=preset,
                          status=status, cached=bool(item.get("cached", False)))
                   for _, _, engine_name, preset, item in engine_entries])


def point_records(scenario: Scenario, point, engine_entries: Sequence, *,
                  cache=None, reference: dict | None = None) -> list[Record]:
    """The law records and the engine records of one sweep point.

    ``cache`` (a :class:`harness.store.cache.ResultCache`, or None) keeps the point's
    reference (:func:`point_reference_cached`) between runs. ``reference``: the point's
    reference already computed (a :func:`harness.run.tasks.reference_task` of the run); None:
    read from the cache or computed here.
    """
    fixed = scenario.at(point)
    mu, e = fixed.friction, fixed.restitution
    problem = scenario.analytic_problem(point)
    mass_matrix, u_before = problem.mass_matrix, problem.u
    free_bodies = fixed.system == "bodies" and not fixed.ground
    vn_approach, vt_approach = metrics.contact_velocities(problem, u_before)
    point_info = point_dict(point)
    mnn, mnt, mtt = metrics.delassus(problem)
    contact_space = {"mnn": mnn, "mnt": mnt, "mtt": mtt, "mu": mu, "e": e}

    law_records: list[Record] = []
    law_speeds: dict[str, np.ndarray | None] = {}
    law_gains: dict[str, float] = {}  # the energy change of each law solved
    solve_law = problem.law_solver(mu=mu, e=e)  # problem.solve, the problem checked once
    for law in scenario.laws:
        tick = time.perf_counter()
        try:
            result = solve_law(law)
        except ValueError as error:
            law_speeds[law] = None
            law_records.append(Record(
                scenario=scenario.name, point=point_info, source=ANALYTIC, law=law,
                u_before=u_before.tolist(), vn_approach=vn_approach, vt_approach=vt_approach,
                status=f"error: {error}", wall_time_s=time.perf_counter() - tick,
                diagnostics=dict(contact_space)))
            continue
        law_speeds[law] = result.u_after
        law_gains[law] = result.energy_change
        broken = broken_promises(law, result, mu)  # the registry's promises, on every solution
        law_records.append(Record(
            scenario=scenario.name, point=point_info, source=ANALYTIC, law=law,
            u_before=u_before.tolist(), u_after=result.u_after.tolist(),
            vn_approach=result.vn_approach, vt_approach=result.vt_approach,
            vn_separation=result.vn_separation, vt_separation=result.vt_separation,
            energy_change=result.energy_change, collision_type=result.collision_type,
            normal_impulse=result.normal_impulse, tangential_impulse=result.tangential_impulse,
            status=f"error: {'; '.join(broken)}" if broken else "ok",
            wall_time_s=time.perf_counter() - tick,
            diagnostics={**contact_space, "case": result.case,
                         "restitution_poisson": result.restitution_poisson,
                         "restitution_in_range": result.restitution_in_range}))
    for record, law in zip(law_records, scenario.laws):
        if law_speeds[law] is not None:
            record.departure = metrics.departures(mass_matrix, law_speeds[law], law_speeds,
                                                  u_before, free_bodies=free_bodies)

    if reference is None:
        reference = point_reference_cached(scenario, point, cache)
    reference = references.annotate(scenario, point, law_records, reference, keep_full=True)
    if not engine_entries:
        return law_records
    scene = engine_scene(scenario, point)
    # the engines' own law, to attribute an energy gain (docs/verdicts.md)
    if verdicts.ENGINE_LAW in law_speeds:  # solved above (or failed: it fails again)
        lcp_gain = law_gains.get(verdicts.ENGINE_LAW)
    else:
        try:
            lcp_gain = solve_law(verdicts.ENGINE_LAW).energy_change
        except ValueError:
            lcp_gain = None
    declared = verdicts.declared_contacts(scenario, scene)  # a flat face: judged against all
    struck = verdicts.sequence_contacts(scenario, scene)  # a tilt: the features its sequence
    sequence = struck is not None  # strikes, the run judged on finishing it
    if sequence:
        declared = struck
    primary = None
    if declared is not None:  # a gain is the law's when the m-contact or sequence reference
        lcp_gain = reference.get("energy_change", {}).get(reference.get("primary"))  # gains
        primary = None if sequence else reference.get("primary")  # admissible, or None
    # What judging any run of the point's scene needs: worked out once, not once per run.
    terms = verdicts.prepare(scene, problem) if declared is None else None
    engine_records = [
        engine_record(scenario, point_info, engine_name, preset, item, problem, law_speeds,
                      scene=scene, law_energy_change=lcp_gain, contacts=declared,
                      terms=terms, sequence=sequence, reference_name=primary)
        for _, _, engine_name, preset, item in engine_entries
    ]
    references.annotate(scenario, point, engine_records, reference)
    return law_records + engine_records


def engine_record(scenario: Scenario, point_info: dict, engine_name: str, preset: str,
                  item: dict, problem, law_speeds: dict, *, scene=None,
                  law_energy_change: float | None = None, contacts=None,
                  terms=None, sequence: bool = False, reference_name: str | None = None
                  ) -> Record:
    """An engine's record from its raw output and the point's law solutions.

    With ``scene`` (the engine's scene at this point) the record gets its verdict
    (:func:`harness.run.verdicts.judge`): ``verdict`` and ``reasons``, and a run that fails
    a check has the first failing reason as its ``status`` (never ``ok``).
    ``law_energy_change`` is ``newton-lcp``'s energy change, to attribute a gain;
    ``contacts``: a flat face's declared contacts (:func:`verdicts.declared_contacts`), or
    with ``sequence`` the features a tilt's sequence strikes (:func:`verdicts.sequence_contacts`);
    ``terms``: ``verdicts.prepare(scene, problem)`` when the caller has it (None: worked out
    by the verdict); ``reference_name``: a flat face's primary reference, the one
    ``law_energy_change`` is of.
    """
    output = item["output"]
    free_bodies = scene is not None and not scene.ground
    mass_matrix, u_before = problem.mass_matrix, problem.u
    vn_approach, vt_approach = metrics.contact_velocities(problem, u_before)
    record = Record(scenario=scenario.name, point=point_info, source=engine_name, preset=preset,
                    u_before=u_before.tolist(), vn_approach=vn_approach,
                    vt_approach=vt_approach, status=output["status"],
                    wall_time_s=float(output.get("wall_time_s", 0.0)),
                    cached=bool(item.get("cached", False)))
    if "velocities" not in output:
        return record
    u_after = np.array([value for body in output["velocities"] for value in body], dtype=float)
    record.u_after = u_after.tolist()
    finite = all(map(math.isfinite, record.u_after))  # np.isfinite(u_after).all(), cheaper
    diagnostics = {key: output.get(key) for key in (
        "steps", "contact_steps", "first_contact_step", "max_contact_points", "max_penetration",
        "separated", "step_cap_hit", "out_of_plane_drift", "contact_normal",
        "engine_normal_impulse", "engine_tangential_impulse", "derived", "notes",
        "engine_wall_time_s")}
    diagnostics["settings_overrides"] = item.get("overrides", {})
    implied = None  # the impulse Δu implies, for the verdict when its residual is finite
    if finite and item.get("history") and scene is not None:
        diagnostics["history"] = contact_history(problem, output, scene,
                                                 float(output.get("time_step") or 0.0))
    if finite:
        vn, vt = metrics.contact_velocities(problem, u_after)
        record.vn_separation, record.vt_separation = vn, vt
        record.energy_change = metrics.energy_change(mass_matrix, u_before, u_after)
        record.collision_type = metrics.classify_end_state(vt_approach, vt, vn_approach)
        normal, tangential, residual = metrics.impulses_from_velocities(
            problem, u_after, free_bodies=free_bodies)
        diagnostics["impulse_from_velocities"] = [normal, tangential]
        diagnostics["impulse_residual"] = residual
        if math.isfinite(residual):
            implied = normal, tangential, residual
        if output.get("engine_normal_impulse") is not None:
            record.normal_impulse = output["engine_normal_impulse"]
            record.tangential_impulse = output.get("engine_tangential_impulse")
            diagnostics["impulse_source"] = "engine"
        else:
            record.normal_impulse, record.tangential_impulse = normal, tangential
            diagnostics["impulse_source"] = "velocities"
    record.departure = metrics.departures(mass_matrix, u_after, law_speeds, u_before,
                                          free_bodies=free_bodies)
    record.diagnostics = diagnostics
    if scene is not None:
        verdict = verdicts.judge(scene, problem,
                                 verdicts.numbers_from_output(engine_name, output),
                                 law_energy_change=law_energy_change, contacts=contacts,
                                 terms=terms, implied=implied, sequence=sequence,
                                 reference=reference_name)
        record.verdict, record.reasons = verdict.label, verdict.as_list()
        record.status = verdict.status(record.status)
    return record


__all__ = ["engine_record", "point_dict", "point_records", "point_records_or_errors"]
