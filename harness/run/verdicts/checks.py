"""The checks every verdict makes, and what they read of a run and of its scene.

:class:`RunNumbers` (the numbers of one engine run the verdicts need, from the runner's task
output or an ``EngineRun``) and :class:`SceneScales` (the scales the tolerances are relative
to); the checks both :func:`harness.run.verdicts.judge` and
:func:`harness.run.verdicts.judge_declared` make, each giving 0 or 1 reason: a speed at an
engine's cap (``clipped``), the deepest overlap (``penetration``), the engine's impulse
against the implied one (``impulse-mismatch``), a gain of energy (``energy-gain``), and a
value at its bound within the rounding band (the ``at-boundary`` remark).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from harness.engines import engine_trait
from harness.run import metrics
from harness.run.verdicts.reasons import BOUNDARY_BAND, Reason, Tolerances
from harness.run.verdicts.tracks import ContactTrack, StepContacts
from harness.scene.features import body_extent


def speed_caps(engine: str) -> tuple[float, float] | None:
    """Measured velocity cap of ``engine`` (largest |v_x|, |v_y| in m/s, largest |ω| in
    rad/s), its adapter's ``speed_caps``; None when it clamps nothing (pybullet clamps at
    100: docs/verdicts.md, 'Velocity caps')."""
    return engine_trait(engine, "speed_caps")


#: A cap an engine computes in single precision (Box2D) holds a clipped speed within a few
#: float32 roundings (6e-8 each) of it: a run-reported cap counts from this fraction below.
RUN_CAP_BAND = 1e-6


@dataclass(frozen=True)
class RunNumbers:
    """What a verdict needs from one engine run (all in the scene frame, SI units)."""

    engine: str
    status: str
    u_after: np.ndarray
    max_penetration: float | None = None
    normal_impulse: float | None = None  # engine's, N s on body B along the contact normal
    tangential_impulse: float | None = None
    impulse_source: str | None = None  # "engine" | "momentum" | None (unknown: engine)
    contact_normal: tuple[float, float] | None = None
    # Per-step contact records (a ContactTrack: the same as arrays); None: the engine kept none
    contacts: tuple[StepContacts, ...] | ContactTrack | None = None
    notes: tuple[str, ...] = field(default_factory=tuple)
    # The run's own caps on each body's speed |v| (m/s) and rate |ω| (rad/s), where they
    # depend on the settings (Box2D: per step); None: the engine's caps, if any, are fixed.
    speed_caps: tuple[float, float] | None = None


def numbers_from_output(engine: str, output: Mapping[str, Any]) -> RunNumbers:
    """:class:`RunNumbers` from the runner's engine-task output (see ``engine_task``)."""
    contacts = output.get("contacts")
    steps = None if contacts is None else ContactTrack.from_output(contacts)
    normal = output.get("contact_normal")
    return RunNumbers(
        engine=engine, status=str(output["status"]),
        u_after=np.array([v for body in output["velocities"] for v in body], dtype=float),
        max_penetration=output.get("max_penetration"),
        normal_impulse=output.get("engine_normal_impulse"),
        tangential_impulse=output.get("engine_tangential_impulse"),
        impulse_source=output.get("impulse_source"),
        contact_normal=None if normal is None else tuple(normal),
        contacts=steps, notes=tuple(output.get("notes") or ()),
        speed_caps=reported_caps(output.get("derived") or {}))


def numbers_from_run(run) -> RunNumbers:
    """:class:`RunNumbers` from an ``EngineRun`` itself (the survey and the stress grid, which
    judge runs without going through the runner's task output)."""
    return RunNumbers(
        engine=run.engine, status=str(run.status), u_after=np.asarray(run.u_after, dtype=float),
        max_penetration=run.max_penetration, normal_impulse=run.normal_impulse,
        tangential_impulse=run.tangential_impulse, impulse_source=run.impulse_source,
        contact_normal=run.contact_normal,
        contacts=ContactTrack.from_record(run.contact_record),
        notes=tuple(run.notes), speed_caps=reported_caps(run.derived or {}))


def reported_caps(derived: Mapping[str, Any]) -> tuple[float, float] | None:
    """The run's own ``(speed, rate)`` caps from its ``derived`` values, if it reports them."""
    if "speed_cap" not in derived:
        return None
    return float(derived["speed_cap"]), float(derived["angular_speed_cap"])


@dataclass(frozen=True)
class SceneScales:
    """The scales the tolerances are relative to (see :func:`scene_scales`)."""

    approach_speed: float  # |v_n^A|, m/s
    impulse: float  # |v_n^A| / m_nn, N s
    speed_norm: float  # frame-free ‖u_before‖_M, sqrt(kg) m/s
    energy: float  # frame-free kinetic energy, J
    size: float  # smallest body extent, m


def scene_scales(scene, problem) -> SceneScales:
    """Scales of one scene's impact: approach speed, impulse, speed norm, energy, size."""
    mnn, _, _ = metrics.delassus(problem)
    return scales_from(scene, problem, mnn, [body_extent(body.shape) for body in scene.bodies])


def scales_from(scene, problem, mnn: float, extents: Sequence[float]) -> SceneScales:
    """:func:`scene_scales` from the scene's ``m_nn`` and its bodies' extents."""
    vn_approach, _ = metrics.contact_velocities(problem, problem.u)
    speed_norm = metrics.frame_free_scale(problem.mass_matrix, problem.u,
                                          free_bodies=not scene.ground)
    return SceneScales(approach_speed=abs(vn_approach), impulse=abs(vn_approach) / mnn,
                       speed_norm=speed_norm, energy=0.5 * speed_norm**2, size=min(extents))


def impulse_mismatch_reasons(run: RunNumbers, implied_n: float, implied_t: float,
                      scales: SceneScales, tolerances: Tolerances, *, engine: str,
                      implied: str, scale: str) -> list[Reason]:
    """``impulse-mismatch`` when the engine's own impulse (not one rebuilt from momentum)
    differs from the one Δu implies by more than the tolerance, relative to ``scales.impulse``
    (``engine``, ``implied`` and ``scale`` name the quantities in the message)."""
    if run.normal_impulse is None or run.impulse_source == "momentum":
        return []
    engine_t = run.tangential_impulse or 0.0
    gap = math.hypot(run.normal_impulse - implied_n, engine_t - implied_t)
    relative = gap / scales.impulse if scales.impulse > 0 else math.inf
    if relative <= tolerances.impulse:
        return []
    return [Reason(
        "impulse-mismatch", relative, tolerances.impulse,
        f"engine {engine} = ({run.normal_impulse:.4g}, {engine_t:.4g}) N s, implied "
        f"{implied} ({implied_n:.4g}, {implied_t:.4g}) N s: differ by {relative:.3g} of "
        f"{scale} = {scales.impulse:.3g} N s")]


def boundary_remarks(check: str, value: float, bound: float, what: str, unit: str,
                 scale: float = 0.0) -> list[Reason]:
    """An ``at-boundary`` remark (never a failure) when ``value`` lies within
    :data:`BOUNDARY_BAND` of ``bound`` (relative to the larger of their magnitudes and
    ``scale``), naming the check and both outcomes; else nothing."""
    if not (math.isfinite(value) and math.isfinite(bound)):
        return []
    band = BOUNDARY_BAND * max(abs(value), abs(bound), scale)
    if abs(value - bound) > band:
        return []
    return [Reason("at-boundary", value, bound,
                   f"{check}: {what} = {value!r} {unit} is within {band:.3g} of the bound "
                   f"{bound!r}: passes | fails {check} on the last bit", fails=False)]


def penetration_reasons(run: RunNumbers, scales: SceneScales,
                        tolerances: Tolerances) -> list[Reason]:
    """``penetration`` when the deepest overlap exceeds its bound (0 or 1 reason)."""
    if run.max_penetration is None:
        return []
    bound = tolerances.penetration * scales.size
    if run.max_penetration <= bound:
        return []
    return [Reason("penetration", run.max_penetration, bound,
                   f"deepest overlap {run.max_penetration:.3g} m > {bound:.3g} m "
                   f"({tolerances.penetration:g} of the smallest body extent "
                   f"{scales.size:g} m)")]


def energy_gain_reasons(gain: float, scales: SceneScales, law_energy_change: float | None,
                 tolerances: Tolerances, *, law: str) -> list[Reason]:
    """``energy-gain`` when kinetic energy grew by ``gain`` (J), attributed to ``law`` (the
    reference the run is judged against) when it gains too, else to the numerics (0 or 1
    reason)."""
    bound = tolerances.energy * scales.energy
    if gain <= bound:
        return []
    by_law = (law_energy_change is not None and law_energy_change > bound
              and gain <= law_energy_change + tolerances.energy_beyond_law * scales.energy)
    return [Reason(
        "energy-gain", gain, bound,
        f"ΔE = +{gain:.4g} J ({gain / scales.energy:.3g} of the frame-free kinetic energy); "
        + (f"{law} gains {law_energy_change:.4g} J on this problem" if by_law
           else f"{law} does not gain energy here" if not law_energy_change
           or law_energy_change <= bound
           else f"beyond {law}'s own gain of {law_energy_change:.4g} J"),
        attribution="law" if by_law else "numerics", fails=not by_law)]


def clipped_reasons(engine: str, u_before: np.ndarray, u_after: np.ndarray,
             tolerances: Tolerances) -> list[Reason]:
    caps = speed_caps(engine)
    if caps is None:
        return []
    found = []
    for when, u in (("before", u_before), ("after", u_after)):
        for index, value in enumerate(u):
            cap = caps[1] if index % 3 == 2 else caps[0]
            if abs(value) >= (1.0 - tolerances.cap) * cap:
                name = ("v_x", "v_y", "ω")[index % 3]
                unit = "rad/s" if index % 3 == 2 else "m/s"
                found.append((when, index // 3, name, float(value), cap, unit))
    if not found:
        return []
    when, body, name, value, cap, unit = found[0]
    more = f" (and {len(found) - 1} more)" if len(found) > 1 else ""
    return [Reason("clipped", abs(value), cap,
                   f"body {body} {name} {when} = {value:.6g} {unit}, at {engine}'s cap "
                   f"{cap:g} {unit}{more}")]


def clipped_magnitude_reasons(engine: str, caps: tuple[float, float], u_before: np.ndarray,
                        u_after: np.ndarray, tolerances: Tolerances) -> list[Reason]:
    """``clipped`` for caps on each body's speed ``|v|`` and rate ``|ω|`` (Box2D's)."""
    band = 1.0 - max(tolerances.cap, RUN_CAP_BAND)
    speed_cap, rate_cap = caps
    found = []
    for when, u in (("before", u_before), ("after", u_after)):
        values = np.asarray(u, dtype=float).tolist()
        for body in range(len(values) // 3):
            vx, vy, omega = values[3 * body : 3 * body + 3]
            if math.hypot(vx, vy) >= band * speed_cap:
                found.append((when, body, "|v|", math.hypot(vx, vy), speed_cap, "m/s"))
            if abs(omega) >= band * rate_cap:
                found.append((when, body, "|ω|", abs(omega), rate_cap, "rad/s"))
    if not found:
        return []
    when, body, name, value, cap, unit = found[0]
    more = f" (and {len(found) - 1} more)" if len(found) > 1 else ""
    return [Reason("clipped", value, cap,
                   f"body {body} {name} {when} = {value:.6g} {unit}, at {engine}'s cap "
                   f"{cap:.6g} {unit} for this run's settings{more}")]


__all__ = ["RUN_CAP_BAND", "RunNumbers", "SceneScales", "boundary_remarks",
           "clipped_magnitude_reasons", "clipped_reasons", "energy_gain_reasons",
           "impulse_mismatch_reasons", "numbers_from_output", "numbers_from_run",
           "penetration_reasons", "reported_caps", "scales_from", "scene_scales", "speed_caps"]
