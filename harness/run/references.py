"""The reference each engine run is compared with, chosen by the situation of the scene.

Three situations (docs/multi-contact.md, 'Which reference a run is compared with'):

* ``single-contact``: one contact point, verified by the scenario checks. The single-contact
  laws of ``planar_impact`` are the references (the law records); the engines' own law is
  ``newton-lcp``.
* ``simultaneous``: a face lying flat, declared with ``contacts = "simultaneous"``. The
  references are the m-contact laws of :mod:`planar_impact.simultaneous` on the contact rows
  of every touching point: the velocity-level Newton–Coulomb law (the engines' law, the
  primary reference, counted by post-impact velocity), every coherent solution of the paper's
  proposal after eq. (75) for Poisson, the paper's Stronge and Newton (the literal reading;
  0, 1 or several each), the same under the effective reading (an extension that counts
  restitution twice), the sequential reading in every order, and the two-phase Poisson law
  for m contacts (:func:`planar_impact.multicontact.poisson_two_phase`,
  ``two-phase/poisson``): a reference that leaves a symmetric flat box at ``e|v_y|`` with no
  spin, which the paper's proposal does not.
* ``event-driven``: a tilt, declared with ``expect_sequence = true``. The primary reference
  is the event-driven sequence of :func:`harness.reference.event_driven.event_sequence` with
  ``newton-lcp`` at each impact; the sequence with every other law of the scenario, and the
  m-contact laws on the features the sequence strikes (taken at the tilted pose, as if they
  touched at once), show how far the tilt is from its flat limit. The sequence cut after
  each of its impacts (``event-driven/newton-lcp/after-k``) is kept too: an engine run ends
  when its contact separates, which at larger tilts is before the next feature strikes, and
  the record names the cut its run is nearest (``nearest_cut``).

:func:`point_reference` builds a point's reference once; :func:`annotate` writes it into the
point's records (``diagnostics["reference"]``; an engine record also gets its departure from
every reference, ``‖u − u_ref‖_M`` over the frame-free scale of
:func:`harness.run.metrics.departure`); :func:`collect` gathers a scenario's references for
its scenario info.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from harness.reference.event_driven import event_sequence
from harness.run import metrics
from harness.scenarios.schema import ONE_POINT_TOLERANCE
from harness.scene import Contact, geometry
from planar_impact import ImpactInputError
from planar_impact import multicontact as mc
from planar_impact import simultaneous as sim

SINGLE, SIMULTANEOUS, EVENT_DRIVEN, UNAVAILABLE = (
    "single-contact", "simultaneous", "event-driven", "unavailable")
#: The engines' own law (sequential impulses on a velocity-level Newton–Coulomb problem).
ENGINE_LAW = "newton-lcp"
#: Laws of the paper's proposal (``planar_impact.simultaneous.TYPE_LAWS``); its literal reading
#: and the effective extension.
COHERENT_LAWS = ("poisson", "stronge-paper", "newton")
#: The literal reading is the paper's proposal; "effective" is the named extension that
#: counts restitution twice (docs/multi-contact.md, 'The paper's proposal').
COUPLINGS = ("literal", "effective")
#: Laws of the sequential reading of a flat face (one contact at a time, every order).
SEQUENTIAL_LAWS = ("newton-lcp", "poisson")
NEWTON_COULOMB = "newton-coulomb"
#: The two-phase Poisson law for m contacts (planar_impact.multicontact).
TWO_PHASE_POISSON = "two-phase/poisson"


def kind_of(scenario) -> str:
    """The situation a scenario declares: simultaneous, event-driven or single-contact."""
    if scenario.system != "bodies":
        return SINGLE
    if getattr(scenario, "contacts", "one") == "simultaneous":
        return SIMULTANEOUS
    if scenario.expect_sequence:
        return EVENT_DRIVEN
    return SINGLE


def point_reference(scenario, point) -> dict:
    """The reference of one sweep point as a JSON-able dict (module docstring).

    Keys: ``kind``, ``contacts`` (how many contact points the reference has), ``primary``
    (the name of the reference the engines are judged against), ``why`` (one line),
    ``speeds`` (name -> ``u`` after), ``energy_change`` (name -> J), ``solutions`` (law and
    reading -> how many solutions), ``departure_from_primary`` (name -> departure of that
    reference from the primary) and, for a tilt, ``sequences`` (law -> impacts).
    """
    kind = kind_of(scenario)
    if kind == SINGLE:
        return scene_reference(kind, None, None)
    return scene_reference(kind, scenario.scene(point), PointLaws.of(scenario.at(point)))


@dataclass(frozen=True)
class PointLaws:
    """What a several-contact reference reads of the scenario at a point besides its scene:
    plain values, so that a reference can be computed in another process."""

    friction: float
    restitution: float
    laws: tuple[str, ...]

    @classmethod
    def of(cls, fixed) -> PointLaws:
        """The friction, restitution and laws of ``fixed`` (a scenario at one point)."""
        return cls(fixed.friction, fixed.restitution, tuple(fixed.laws))


def scene_reference(kind: str, scene, fixed: PointLaws | None) -> dict:
    """:func:`point_reference` from the situation ``kind`` (:func:`kind_of`), the scene at
    the point and its :class:`PointLaws` (both unused for a single-contact point)."""
    if kind == SINGLE:
        return {"kind": SINGLE, "contacts": 1, "primary": ENGINE_LAW,
                "why": "one contact point (verified by the scenario checks): the "
                       "single-contact laws"}

    if kind == SIMULTANEOUS:
        contacts = geometry.scene_contacts(scene, tolerance=ONE_POINT_TOLERANCE)
        reference = {"kind": SIMULTANEOUS, "contacts": len(contacts),
                     "why": f"a face lying flat ({len(contacts)} contact points): the "
                            "m-contact laws, eq. (75)"}
        reference.update(_simultaneous(scene, contacts, fixed, prefix=""))
        reference["primary"] = _first_admissible(reference, NEWTON_COULOMB)
        if reference["primary"] is None:  # Newton–Coulomb broke admissibility (or had none)
            reference["primary"] = _first_admissible(reference, TWO_PHASE_POISSON)
        if reference["primary"] is None:
            reference["why"] += ("; no admissible Newton–Coulomb or two-phase Poisson "
                                 "solution: no primary reference")
        elif reference["primary"] in reference["gains_energy"]:
            reference["why"] += (f"; {reference['primary']} gains energy here (a property of "
                                 "Newton's law, flagged)")
    else:
        reference = _event_driven(scene, fixed)
    if reference.get("primary") is not None:
        mass_matrix, u_before = scene.mass_matrix(), scene.state()
        primary = reference["speeds"][reference["primary"]]
        reference["departure_from_primary"] = {
            name: metrics.departure(mass_matrix, speeds, primary, u_before,
                                    free_bodies=not scene.ground)
            for name, speeds in reference["speeds"].items()}
    return reference


def _first_admissible(reference: dict, stem: str) -> str | None:
    """The first solution named ``stem`` (or ``stem#k``) that breaks no admissibility check:
    a reference that breaks one is never primary (docs/multi-contact.md, 'Admissible
    references')."""
    names = [name for name in reference["speeds"] if (name == stem or name.startswith(stem + "#"))
             and name not in reference.get("inadmissible", {})]
    return names[0] if names else None


def _named(stem: str, count: int, k: int) -> str:
    """``stem`` for a unique solution, ``stem#k`` (k from 1) when there are several."""
    return stem if count == 1 else f"{stem}#{k + 1}"


def _simultaneous(scene, contacts, fixed, prefix: str) -> dict:
    """Every m-contact law on the rows of ``contacts``: Newton–Coulomb, the two-phase
    Poisson law, the coherent solutions of the paper's proposal, the sequential reading in
    every order."""
    wn, wt = geometry.contact_rows(scene, contacts)
    system = sim.contact_system(mass_matrix=scene.mass_matrix(), wn=wn, wt=wt, u=scene.state(),
                                mu=fixed.friction, e=fixed.restitution)
    speeds, energy, counts, inadmissible, gains = {}, {}, {}, {}, []
    kinetic = 0.5 * float(system.u @ system.mass_matrix @ system.u)

    def keep(name, u_after, energy_change, law, phases):
        """Keep one solution, with what it breaks of admissibility checked on it here
        (planar_impact.simultaneous.violations; docs/multi-contact.md, 'Admissible
        references') and whether it gains energy (a property of some laws, flagged)."""
        speeds[prefix + name] = [float(v) for v in u_after]
        energy[prefix + name] = float(energy_change)
        broken = sim.violations(system, phases, promises_no_gain=sim.promises_no_gain(law))
        if broken:
            inadmissible[prefix + name] = [f"{law}: {line}" for line in broken]
        if energy_change > sim.ADMISSIBLE_ENERGY * kinetic:
            gains.append(prefix + name)

    outcome = sim.newton_coulomb(system)
    found = outcome.solutions
    counts[NEWTON_COULOMB] = len(found)
    for k, solution in enumerate(found):
        keep(_named(NEWTON_COULOMB, len(found), k), solution.u_after, solution.energy_change,
             NEWTON_COULOMB, sim.solution_phases(system, solution))
    # Several answers only where the frictional LCP has several, or where W lets the
    # compression's normal split vary (never on one body lying flat).
    found = mc.poisson_two_phase(system)
    counts[TWO_PHASE_POISSON] = len(found)
    for k, solution in enumerate(found):
        keep(_named(TWO_PHASE_POISSON, len(found), k), solution.u_after, solution.energy_change,
             TWO_PHASE_POISSON, mc.two_phase_phases(system, solution))
    for law in COHERENT_LAWS:
        for coupling in COUPLINGS:
            try:
                found = sim.coherent_solutions(system, law, coupling=coupling)
            except ImpactInputError:  # a law that refuses the problem has no solution here
                found = []
            stem = f"coherent/{law}/{coupling}"
            # Counted apart: the clearly coherent solutions, and those with a decision inside
            # the boundary band (planar_impact.simultaneous.BOUNDARY_BAND), which the last
            # bit would otherwise keep or drop.
            clear = [s for s in found if not s.at_boundary]
            boundary = [s for s in found if s.at_boundary]
            counts[stem] = len(clear)
            counts[f"{stem}/at-boundary"] = len(boundary)
            for k, solution in enumerate(clear):
                keep(_named(stem, len(clear), k), solution.u_after, solution.energy_change,
                     law, sim.solution_phases(system, solution))
            for k, solution in enumerate(boundary):
                keep(_named(f"{stem}/at-boundary", len(boundary), k), solution.u_after,
                     solution.energy_change, law, sim.solution_phases(system, solution))
    for law in SEQUENTIAL_LAWS:
        results, spread = sim.all_orders(system, law)
        counts[f"sequential/{law}/order-spread"] = float(spread)
        for result in results:
            order = "-".join(str(i) for i in result.order)
            keep(f"sequential/{law}/{order}", result.u_after, result.energy_change, law,
                 tuple(sim.Phase(sim.IMPACT, start, impulse) for start, impulse in result.steps))
    return {"speeds": speeds, "energy_change": energy, "solutions": counts,
            "inadmissible": inadmissible, "gains_energy": gains,
            "newton_coulomb": {"status": outcome.status, "explanation": outcome.explanation}}


def _event_driven(scene, fixed) -> dict:
    """The tilt's references: the event sequence per law, and the m-contact laws on the
    features it strikes, taken at the tilted pose."""
    if not scene.ground:
        return {"kind": UNAVAILABLE, "contacts": None, "primary": None,
                "why": "a tilt between two bodies: the event-driven reference is built for one "
                       "body on the ground only (docs/multi-contact.md, 'Event-driven "
                       "reference')"}
    laws = tuple(dict.fromkeys((ENGINE_LAW, *fixed.laws)))
    speeds, energy, sequences = {}, {}, {}
    mass_matrix, u_before = scene.mass_matrix(), scene.state()
    struck: list[int] = []
    shared: dict = {}  # the laws' sequences start alike: their common flights worked out once
    for law in laws:
        sequence = event_sequence(scene, law, shared=shared)
        after = sequence.speeds()
        speeds[f"event-driven/{law}"] = [float(v) for v in after]
        energy[f"event-driven/{law}"] = 0.5 * float(after @ mass_matrix @ after
                                                    - u_before @ mass_matrix @ u_before)
        sequences[law] = {"impacts": [[int(e.feature), float(e.time), int(e.collision_type)]
                                      for e in sequence.events],
                          "finished": sequence.finished}
        struck += [e.feature for e in sequence.events]
        if law == ENGINE_LAW:  # the sequence cut after k impacts: an engine run may stop there
            for k in range(1, len(sequence.events)):  # the prefix of the whole sequence
                cut = np.array(sequence.events[k - 1].speeds_after)
                speeds[f"event-driven/{law}/after-{k}"] = [float(v) for v in cut]
                energy[f"event-driven/{law}/after-{k}"] = 0.5 * float(
                    cut @ mass_matrix @ cut - u_before @ mass_matrix @ u_before)
    reference = {"kind": EVENT_DRIVEN, "primary": f"event-driven/{ENGINE_LAW}",
                 "sequences": sequences, "speeds": speeds, "energy_change": energy}
    features = sorted(set(struck))
    reference["contacts"] = len(features)
    reference["why"] = (f"a tilt (expect_sequence): the event-driven sequence with {ENGINE_LAW}; "
                        f"features {features} struck")
    if len(features) >= 2:  # the flat limit: the struck features as if they touched at once
        world, radius = geometry.world_core(scene.bodies[0])
        contacts = [Contact(point=np.array([world[k, 0], world[k, 1] - radius]),
                            normal=np.array([0.0, 1.0]), gap=float(world[k, 1] - radius))
                    for k in features]
        extra = _simultaneous(scene, contacts, fixed, prefix="at-pose/")
        speeds.update(extra["speeds"])
        energy.update(extra["energy_change"])
        reference["inadmissible"] = extra["inadmissible"]
        reference["gains_energy"] = extra["gains_energy"]
        reference["solutions"] = extra["solutions"]
    return reference


def annotate(scenario, point, records: Sequence, reference: dict | None = None, *,
             keep_full: bool = False) -> dict:
    """Write the point's reference into ``records`` and return it (built when None).

    With ``keep_full`` the first record also carries the whole reference
    (``diagnostics["reference_full"]``, read by :func:`collect`). Law records get
    ``diagnostics["reference"] = {"kind", "primary", "applies"}``: the single-contact laws
    apply only to a single-contact point. Engine records get the reference's kind and
    primary and ``departure_from_primary``; at a point whose reference is not the
    single-contact laws, the record's ``departure`` holds only the references that apply to
    its situation (:func:`applicable`), never the single-contact laws.
    """
    if reference is None:
        reference = point_reference(scenario, point)
    for record in records:
        summary = {"kind": reference["kind"], "primary": reference.get("primary")}
        if record.source == "analytic":
            summary["applies"] = reference["kind"] == SINGLE
        elif record.u_after is not None and reference.get("speeds"):
            u_before = np.asarray(record.u_before, dtype=float)
            mass_matrix = _mass_matrix(scenario, point)
            departure = metrics.departures(
                mass_matrix, record.u_after, applicable(reference), u_before,
                free_bodies=scenario.system == "bodies" and not scenario.ground)
            record.departure = departure  # the single-contact laws' do not apply here
            primary = departure.get(reference.get("primary"), math.nan)
            summary["departure_from_primary"] = primary
            if reference["kind"] == EVENT_DRIVEN:  # which cut of the sequence the run is nearest
                cuts = {name: value for name, value in departure.items()
                        if name.startswith(reference["primary"])}
                nearest = min(cuts, key=lambda name: cuts[name])
                summary["nearest_cut"] = [nearest, cuts[nearest]]
        elif record.source != "analytic" and reference["kind"] != SINGLE:
            record.departure = {}  # no reference for this situation, and not the laws'

        if record.diagnostics is None:
            record.diagnostics = {}
        record.diagnostics["reference"] = summary
    if keep_full and records:
        records[0].diagnostics["reference_full"] = reference
    return reference


def applicable(reference: dict) -> dict:
    """The reference speeds that apply to an engine run in the reference's situation, by
    name: at a flat face every m-contact law (Newton–Coulomb, the paper's proposal, the
    sequential reading), at a tilt the event-driven sequences and their cuts (not the
    ``at-pose/`` answers, which are the flat limit's: a face that is not there)."""
    speeds = reference.get("speeds") or {}
    if reference["kind"] == EVENT_DRIVEN:
        return {name: value for name, value in speeds.items()
                if name.startswith("event-driven/")}
    return dict(speeds)


def _mass_matrix(scenario, point) -> np.ndarray:
    scene = scenario.scene(point)
    return scene.mass_matrix()


def collect(records: Sequence) -> list[dict]:
    """A scenario's references per point (for its scenario info), from the points' records:
    ``[{"point": label, **reference}]`` in point order; the full reference is carried by the
    first record of each point (:func:`annotate` with ``keep_full=True``)."""
    seen, out = set(), []
    for record in records:
        full = (record.diagnostics or {}).get("reference_full")
        if full is None or record.point["index"] in seen:
            continue
        seen.add(record.point["index"])
        out.append({"point": record.point["label"], **full})
    return out


__all__ = ["COHERENT_LAWS", "COUPLINGS", "EVENT_DRIVEN", "SIMULTANEOUS", "SINGLE",
           "TWO_PHASE_POISSON", "PointLaws", "annotate", "applicable", "collect", "kind_of",
           "point_reference", "scene_reference"]
