"""What a verdict says: the reasons a run fails, the remarks, the tolerances, the verdict.

The names and order of the reasons (:data:`REASONS`: the first failing one names the run's
status), the remarks that never fail (:data:`REMARKS`), the named tolerances
(:class:`Tolerances`), one :class:`Reason` and the :class:`Verdict` of a run; the laws a gain
of energy is attributed to; and the count of reasons over many runs the reports show
(docs/verdicts.md).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from itertools import chain
from typing import Any

#: Reason name -> what it says. Ordered: the first failing reason names the run's status.
REASONS: dict[str, str] = {
    "blow-up": "the engine's status: non-finite or exploding velocities",
    "no-contact": "the engine's status: it never reported a contact",
    "no-separation": "the engine's status: still in contact at its step cap",
    "out-of-plane": "the engine's status: a body left the plane",
    "clipped": "a speed sits at the engine's velocity cap: the engine did not simulate the "
    "scene's speeds",
    "multi-contact": "a second feature touched within the run (which, at which step)",
    "truncated-sequence": "the run ended while a feature still reaches the ground: it is only "
    "the first impacts of the sequence its reference is",
    "not-simultaneous": "on a face declared to strike at once, the declared contacts were "
    "first struck at different steps: a sequence of impacts, not the simultaneous impact",
    "not-separated": "the contact still closes at the end: v_n^S < -tolerance",
    "penetration": "the deepest overlap exceeds the bound scaled to the bodies' size",
    "impulse-residual": "the change of speeds is not one impulse at the contact point",
    "impulse-mismatch": "the engine's impulse differs from the impulse the change of speeds "
    "implies",
    "energy-gain": "kinetic energy grew (attributed to the law when newton-lcp predicts a "
    "gain, else to the numerics; only a numerics gain fails the run)",
}


#: Remarks a verdict lists after its reasons, never failures (not counted as reasons).
REMARKS: dict[str, str] = {
    "at-boundary": "a check's value lies within its rounding band of the check's bound: the "
    "decision (named, with the other) could go either way on another CPU",
}


#: The rounding band of a verdict check (docs/verdicts.md, 'Decisions at a boundary'): a
#: measured value within BOUNDARY_BAND of the larger of its magnitude and its bound's (for
#: not-separated, of the sum of the products forming v_n^S) is at the boundary. The
#: tolerances themselves are 1e-6 to 0.1 of their scales; rounding moves a value by ~1e-16.
BOUNDARY_BAND = 1e-9


#: Reason name -> its place in :data:`REASONS` (a verdict lists its reasons in that order).
REASON_ORDER = {name: place for place, name in enumerate(chain(REASONS, REMARKS))}


ENGINE_STATUS_REASONS = ("blow-up", "no-contact", "no-separation", "out-of-plane",
                         "multi-contact")


SINGLE_IMPACT = "single-impact"


#: The law a single-contact run's energy gain is attributed to: the engines' own.
ENGINE_LAW = "newton-lcp"


#: The law a run on declared simultaneous contacts is attributed to (the m-contact reference).
NEWTON_COULOMB = "Newton–Coulomb"


#: The law a run of a tilt's sequence of impacts is attributed to (its reference sequence).
SEQUENCE_LAW = "the event-driven sequence with newton-lcp"


FLAGGED = "flagged"


@dataclass(frozen=True)
class Tolerances:
    """The verdict's named settings, each relative to a scale of the scene (docs/verdicts.md).

    Attributes
    ----------
    separation : float
        ``not-separated`` when ``v_n^S < −separation·|v_n^A|``.
    penetration : float
        ``penetration`` when the deepest overlap exceeds ``penetration`` times the smallest
        body extent (largest distance from a body's centre of mass to its surface: the
        lever-arm scale of the contact, :func:`body_extent`).
    impulse_residual : float
        ``impulse-residual`` when ``‖Δu − M⁻¹(w_n I_n + w_t I_t)‖_M`` exceeds this fraction of
        the frame-free speed scale (:func:`harness.run.metrics.frame_free_scale`).
    impulse : float
        ``impulse-mismatch`` when ``|I_engine − I_implied|`` exceeds this fraction of the
        impulse scale ``|v_n^A| / m_nn`` (a plastic frictionless impact's impulse).
    energy : float
        ``energy-gain`` when ``ΔE`` exceeds this fraction of the frame-free kinetic energy.
    energy_beyond_law : float
        A gain is the law's when ``newton-lcp`` gains energy too and the engine's gain exceeds
        the law's by at most this fraction of the frame-free kinetic energy; beyond it (or
        with no gain of the law) it is the numerics'.
    cap : float
        A speed counts as at a cap when ``|v| >= (1 − cap)·cap_value``.
    """

    separation: float = 1e-3
    penetration: float = 0.1
    impulse_residual: float = 2e-2
    impulse: float = 5e-2
    energy: float = 1e-6
    energy_beyond_law: float = 1e-2
    cap: float = 1e-9


DEFAULT_TOLERANCES = Tolerances()


@dataclass(frozen=True)
class Reason:
    """One check a run fails (or, for a law-attributed energy gain, a remark)."""

    name: str  # a key of REASONS
    value: float | None  # what was measured (units in ``detail``)
    tolerance: float | None  # the bound it was held against (same units)
    detail: str  # one line: where, which feature, which step, units
    attribution: str | None = None  # energy-gain: "law" or "numerics"
    fails: bool = True  # False: reported, not a failure (a gain the law predicts)

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class Verdict:
    """Every check of one engine run: a single impact only if no reason fails."""

    reasons: tuple[Reason, ...] = ()

    @property
    def failing(self) -> tuple[Reason, ...]:
        return tuple(r for r in self.reasons if r.fails)

    @property
    def single_impact(self) -> bool:
        return not self.failing

    @property
    def label(self) -> str:
        """``"single-impact"`` or ``"flagged"``."""
        return SINGLE_IMPACT if self.single_impact else FLAGGED

    @property
    def names(self) -> tuple[str, ...]:
        """Failing reasons' names, in :data:`REASONS` order."""
        return tuple(r.name for r in self.failing)

    def status(self, engine_status: str) -> str:
        """The record status: the engine's when the verdict keeps it, else the first failing
        reason's name, else ``ok``. (The verdict drops the engine's ``multi-contact`` where it
        judges the features touched instead of counting points.)"""
        return status_of(engine_status, self.names)

    def as_list(self) -> list[dict]:
        return [reason.as_dict() for reason in self.reasons]


def status_of(engine_status: str, names: Sequence[str]) -> str:
    """:meth:`Verdict.status` of a verdict whose failing reasons are ``names``."""
    judged = engine_status == "ok" or (engine_status in ENGINE_STATUS_REASONS
                                       and engine_status not in names)
    if not judged:
        return engine_status
    return names[0] if names else "ok"


def reason_counts(reasons_per_run: Sequence[Sequence[Mapping[str, Any]]]) -> dict[str, int]:
    """``{reason: runs failing it}`` over many runs' ``reasons`` lists (law-attributed
    energy gains counted as ``energy-gain (law)``, not failing; remarks such as
    ``at-boundary`` under their own name)."""
    counts: dict[str, int] = {}
    for reasons in reasons_per_run:
        for reason in reasons:
            name = (reason["name"] if reason.get("fails", True) or reason["name"] in REMARKS
                    else f"{reason['name']} (law)")
            counts[name] = counts.get(name, 0) + 1
    return counts


__all__ = ["BOUNDARY_BAND", "DEFAULT_TOLERANCES", "ENGINE_LAW", "ENGINE_STATUS_REASONS", "FLAGGED",
           "NEWTON_COULOMB", "REASONS", "REASON_ORDER", "REMARKS", "Reason", "SEQUENCE_LAW",
           "SINGLE_IMPACT", "Tolerances", "Verdict", "reason_counts", "status_of"]
