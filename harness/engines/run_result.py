"""What an engine run returns, and how its status is decided.

:class:`EngineRun` (one impact simulated by one engine), its per-step contact records
(:data:`RawContacts` as the adapters give them, :class:`ContactStep` typed on demand), and
:class:`Status` with :func:`decide_status`, the order in which a finished run's status is
decided (harness/engines/contract.py documents the contract around them).
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

# Kinetic-energy-norm growth that counts as a blow-up (an impact cannot multiply it by 1e3).
BLOW_UP_FACTOR = 1e3
# Out-of-plane displacement (m) above which a run is flagged: planar joints keep it at 0.
OUT_OF_PLANE_TOLERANCE = 1e-9

_BLOW_UP_SQUARED = BLOW_UP_FACTOR**2


class Status(enum.StrEnum):
    """How a run ended, decided in this order (the first that applies wins).

    A ``str``: a status compares equal to, and serialises as, its value (``"ok"``).
    """

    BLOW_UP = "blow-up"
    NO_CONTACT = "no-contact"
    NO_SEPARATION = "no-separation"
    OUT_OF_PLANE = "out-of-plane"
    MULTI_CONTACT = "multi-contact"
    OK = "ok"

    @property
    def meaning(self) -> str:
        """What the status says about a run, in one line."""
        return _MEANINGS[self]


_MEANINGS: dict[Status, str] = {
    Status.BLOW_UP: "non-finite velocities, or kinetic-energy norm above 1e3 times the input's",
    Status.NO_CONTACT: "the engine never reported a contact within the step cap",
    Status.NO_SEPARATION: "still in contact when the step cap was hit",
    Status.OUT_OF_PLANE: "a body left the plane by more than 1e-9 m (pybullet/MuJoCo)",
    Status.MULTI_CONTACT: "more than one distinct contact point in the plane at once: the scene "
    "is outside one-point impact theory",
    Status.OK: "one contact point, separated within the cap, finite results",
}

#: ``status value -> meaning``, in the order statuses are decided.
STATUSES: dict[str, str] = {status.value: status.meaning for status in Status}

#: One body's ``(x, y, θ, v_x, v_y, ω)``: m, m, rad, m/s, m/s, rad/s.
BodyState = tuple[float, float, float, float, float, float]
#: One body's ``(x, y, θ)`` (m, m, rad) and ``(v_x, v_y, ω)`` (m/s, m/s, rad/s).
Pose = tuple[float, float, float]
Velocity = tuple[float, float, float]

#: What an adapter's ``_step`` returns for a step with contact, in the run frame:
#: ``(points, normal, impulse, normal_impulse)`` --
#: ``points``: tuple of ``(x, y, depth)`` per contact point the engine reports (m; depth > 0
#: is overlap), where the bodies touch (on either surface or across the overlap: the
#: verdicts read the touching feature from it, check_engine holds it there); ``normal``:
#: unit ``(n_x, n_y)`` from body A (or the ground) into body B (the last body); ``impulse``:
#: ``(p_x, p_y)`` the contact impulse on body B in this step (N s), or ``None`` where the
#: engine does not expose it; ``normal_impulse``: the engine's own measure of the step's
#: normal impulse (N s, >= 0; exactly 0 when it applies none), or ``None`` when the adapter
#: knows without measuring that the contact still pushes.
RawContacts = tuple[tuple[tuple[float, float, float], ...], tuple[float, float],
                    "tuple[float, float] | None", float]


class ContactPoint(NamedTuple):
    """One contact point of one step, in the scene frame."""

    x: float  # m
    y: float  # m
    depth: float  # m, overlap (> 0) or gap (< 0) as the engine reports it


class ContactStep(NamedTuple):
    """What the engine reported in one step with contact, in the scene frame."""

    step: int  # 1-based step number
    points: tuple[ContactPoint, ...]
    normal: tuple[float, float]  # unit, from body A (or the ground) into body B
    impulse: tuple[float, float] | None  # N s on body B in this step; None: not exposed
    normal_impulse: float | None  # N s, the engine's own measure (>= 0); None: not measured
    poses: tuple[Pose, ...]  # every body's (x, y, θ) after the step



class ContactRecord(NamedTuple):
    """The raw per-step records of a run: kept as the adapter gave them (run frame), typed
    on demand (the run's hot path does not build a record object per step)."""

    shift: tuple[float, float]  # run frame = scene frame + shift
    raw: tuple[tuple[int, RawContacts, tuple[Pose, ...]], ...]  # (step, contacts, poses)

    def steps(self) -> tuple[ContactStep, ...]:
        """The records as :class:`ContactStep` values in the scene frame."""
        shift_x, shift_y = self.shift
        return tuple(
            ContactStep(
                step,
                tuple(ContactPoint(x - shift_x, y - shift_y, depth) for x, y, depth in points),
                normal, impulse, pressure,
                tuple((x - shift_x, y - shift_y, angle) for x, y, angle in poses),
            )
            for step, (points, normal, impulse, pressure), poses in self.raw
        )


@dataclass(frozen=True)
class EngineRun:
    """One impact simulated by one engine.

    Equality compares everything but ``wall_time_s``: two runs of identical inputs compare
    equal (bit-identical floats).
    """

    engine: str
    engine_version: str
    scene_name: str
    preset: str | None  # None when a custom settings dict was passed
    settings: Mapping[str, Any]  # the settings actually used (complete, JSON-able)
    velocities: tuple[tuple[float, float, float], ...]  # per body (v_x m/s, v_y m/s, ω rad/s)
    status: Status
    status_reason: str  # why this run got its status, with its numbers
    steps: int  # steps simulated
    contact_steps: int  # steps in which the engine reported a contact
    first_contact_step: int | None  # 1-based step of the first contact, None if never
    max_contact_points: int  # most distinct in-plane contact points seen in one step
    max_penetration: float  # m, largest penetration depth seen (>= 0)
    separated: bool  # contact began and then ended within the cap
    step_cap_hit: bool
    # First contact's unit normal in the scene frame, from body A (or the ground) into body B
    # (the single body of a ground scene, else bodies[1]).
    contact_normal: tuple[float, float] | None
    # Contact impulse on body B (N s) summed over the run, along contact_normal and along
    # t = (n_y, -n_x) (so +x for the ground); None when there was no contact.
    normal_impulse: float | None
    tangential_impulse: float | None
    impulse_source: str | None  # "engine" (summed per step) | "momentum" (m_B·Δv_B) | None
    out_of_plane_drift: float | None  # m; None for 2-D engines
    energy_before: float  # J, kinetic energy of the scene's input state
    energy_after: float  # J, kinetic energy after the run
    # Every step with contact as the adapter reported it, ``(shift, ((step, RawContacts,
    # states), ...))`` in the run frame (scene frame + shift); ``contacts`` is the typed view.
    contact_record: tuple = ((0.0, 0.0), ())
    derived: Mapping[str, Any] = field(default_factory=dict)  # values computed from settings
    notes: tuple[str, ...] = ()
    wall_time_s: float = field(default=0.0, compare=False)  # s, build/reuse + stepping + readout

    @property
    def u_after(self) -> np.ndarray:
        """Post-impact generalised speeds, ``(v_x, v_y, ω)`` per body in scene order."""
        return np.array([value for body in self.velocities for value in body], dtype=float)

    @property
    def flagged(self) -> bool:
        return self.status is not Status.OK

    @property
    def contacts(self) -> tuple[ContactStep, ...]:
        """Every step with contact, in order, in the scene frame."""
        return ContactRecord(*self.contact_record).steps()


def decide_status(
    before: float,
    after: float,
    velocities: Sequence[Sequence[float]],
    *,
    steps: int,
    contact_seen: bool,
    separated: bool,
    max_contact_points: int,
    out_of_plane_drift: float | None,
) -> tuple[Status, str]:
    """The :class:`Status` of a finished run and its reason.

    ``before``, ``after``: twice the kinetic energy of the input and of ``velocities``.
    """
    # With positive masses and inertias a finite sum means finite velocities: test them
    # one by one only when it is not.
    if not math.isfinite(after) and not all(math.isfinite(v) for body in velocities for v in body):
        return Status.BLOW_UP, "non-finite velocities"
    if after > _BLOW_UP_SQUARED * max(before, 1e-300):
        return Status.BLOW_UP, (f"kinetic energy grew {after / max(before, 1e-300):.3g}-fold "
                                f"(norm above {BLOW_UP_FACTOR:g} times the input's)")
    if not contact_seen:
        return Status.NO_CONTACT, f"no contact in {steps} steps"
    if not separated:
        return Status.NO_SEPARATION, f"still in contact at the step cap ({steps} steps)"
    if out_of_plane_drift is not None and out_of_plane_drift > OUT_OF_PLANE_TOLERANCE:
        return Status.OUT_OF_PLANE, (f"a body left the plane by {out_of_plane_drift:.3g} m "
                                     f"(> {OUT_OF_PLANE_TOLERANCE:g} m)")
    if max_contact_points > 1:
        return Status.MULTI_CONTACT, multi_contact_note(max_contact_points)
    return Status.OK, _MEANINGS[Status.OK]


def multi_contact_note(points: int) -> str:
    """The run note when a step saw more than one contact point (outside one-point theory)."""
    return f"{points} distinct in-plane contact points in one step"


def run_from_fields(values: dict) -> EngineRun:
    """An :class:`EngineRun` from a dict holding every field, for the hot path.

    The frozen dataclass ``__init__`` sets each field through ``object.__setattr__`` (about
    as much as a whole pymunk impact costs); this takes the dict as the instance's
    attributes, a tenth of that. The result is an ordinary EngineRun.
    """
    run = _new_object(EngineRun)
    _set_attribute(run, "__dict__", values)
    return run


_new_object: Callable = object.__new__
_set_attribute: Callable = object.__setattr__
