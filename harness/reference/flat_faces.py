"""How many coherent solutions the paper's proposal has on random flat landings.

A flat landing is a box or a rod lying flat on the ground (two contacts, one rigid body) with
random size, speeds, spin, ``μ`` and ``e``. For each, the solutions of
:func:`planar_impact.simultaneous.coherent_solutions` (Poisson, the paper's Stronge, Newton;
the paper's literal reading and the effective extension) and of
:func:`~planar_impact.simultaneous.newton_coulomb_solutions` (by post-impact velocity) are
counted (0, 1, 2+ clearly coherent; at the boundary apart), and the first scene of each count
is kept as an example: this is how the library's flat-box-receding-end was found.
docs/multi-contact.md, 'Counting on flat landings', has the numbers::

    PYTHONPATH=src:. python -m harness.reference.flat_faces 200 0
"""

from __future__ import annotations

import numpy as np

from harness.scene import Body, Box, Rod, Scene, geometry
from planar_impact import multicontact as mc
from planar_impact import simultaneous as sim

LAWS = ("poisson", "stronge-paper", "newton")
COUPLINGS = ("literal", "effective")  # the paper's proposal, then the extension


def random_flat_scene(rng: np.random.Generator) -> Scene:
    """One box or rod (equal odds) lying flat, with at least one contact approaching.

    Width 0.2–2 m, height 0.05–1 m (rod radius 0.005–0.1 m), 1 kg; ``v_x`` ∈ [−1, 1],
    ``v_y`` ∈ [−2, −0.2] m/s, ``ω`` ∈ [−3, 3] rad/s (redrawn until a contact approaches);
    ``μ``, ``e`` ∈ [0, 1].
    """
    width = rng.uniform(0.2, 2.0)
    shape = Box(width, rng.uniform(0.05, 1.0)) if rng.random() < 0.5 else Rod(
        width, rng.uniform(0.005, 0.1))
    while True:
        velocity = (rng.uniform(-1.0, 1.0), rng.uniform(-2.0, -0.2))
        omega = rng.uniform(-3.0, 3.0)
        if velocity[1] - abs(omega) * width / 2 < 0.0:  # the lower of the two ends approaches
            break
    body = geometry.place_on_ground(Body("body", shape, 1.0, (0.0, 0.0), velocity=velocity,
                                         angular_velocity=omega))
    return Scene((body,), float(rng.uniform(0, 1)), float(rng.uniform(0, 1)), ground=True,
                 name="random-flat")


def flat_system(scene: Scene) -> sim.ContactSystem:
    """The two-contact system of a flat scene (both ends, eq. (75))."""
    contacts = geometry.scene_contacts(scene)
    wn, wt = geometry.contact_rows(scene, contacts)
    return sim.contact_system(mass_matrix=scene.mass_matrix(), wn=wn, wt=wt, u=scene.state(),
                              mu=scene.friction, e=scene.restitution)


def count_flat(problems: int = 1000, seed: int = 0) -> tuple[dict, dict]:
    """``(counts, examples)``: per ``"law/coupling"`` (and ``"newton-coulomb"``,
    ``"two-phase/poisson"``) how many of ``problems`` random flat landings have 0, 1, 2+
    solutions, how many have a solution that breaks admissibility
    (:func:`planar_impact.simultaneous.violations`) or gains energy, and the first scene of
    each count."""
    rng = np.random.default_rng(seed)
    keys = ([f"{law}/{coupling}" for law in LAWS for coupling in COUPLINGS]
            + ["newton-coulomb", "two-phase/poisson"])
    # 0/1/2+: clearly coherent solutions (Newton–Coulomb and the two-phase law: distinct
    # post-impact velocities); "boundary": draws with a solution at the boundary of a
    # decision (not in 0/1/2+); "split": Newton–Coulomb draws whose impulse split is not
    # unique; "inadmissible", "gains": draws with a solution (any) that breaks an
    # admissibility check, or that gains energy; "max-gain": the largest gain of a
    # solution, a fraction of ½uᵀMu (0 where none gains).
    counts = {key: dict.fromkeys(("0", "1", "2+", "boundary", "split", "inadmissible",
                                  "gains", "max-gain"), 0) for key in keys}
    examples: dict[str, dict[str, Scene]] = {key: {} for key in keys}
    for _ in range(problems):
        scene = random_flat_scene(rng)
        system = flat_system(scene)
        kinetic = 0.5 * float(system.u @ system.mass_matrix @ system.u)
        for key in keys:
            if key == "newton-coulomb":
                outcome = sim.newton_coulomb(system)
                number = len(outcome.solutions)
                counts[key]["split"] += outcome.status == sim.NC_SPLIT_NOT_UNIQUE
                checked = [(s.energy_change, sim.solution_phases(system, s), key)
                           for s in outcome.solutions]
            elif key == "two-phase/poisson":
                answers = mc.poisson_two_phase(system)
                number = len(answers)
                checked = [(a.energy_change, mc.two_phase_phases(system, a), key)
                           for a in answers]
            else:
                law, coupling = key.split("/")
                found = sim.coherent_solutions(system, law, coupling=coupling)
                number = sum(not s.at_boundary for s in found)
                counts[key]["boundary"] += any(s.at_boundary for s in found)
                checked = [(s.energy_change, sim.solution_phases(system, s), law)
                           for s in found]
            counts[key]["inadmissible"] += any(
                sim.violations(system, phases, promises_no_gain=sim.promises_no_gain(law))
                for _, phases, law in checked)
            counts[key]["gains"] += any(gain > sim.ADMISSIBLE_ENERGY * kinetic
                                        for gain, _, _ in checked)
            counts[key]["max-gain"] = max([counts[key]["max-gain"]]  # of ½uᵀMu
                                          + [gain / kinetic for gain, _, _ in checked])
            bucket = "0" if number == 0 else "1" if number == 1 else "2+"
            counts[key][bucket] += 1
            examples[key].setdefault(bucket, scene)
    return counts, examples


def describe(scene: Scene) -> str:
    body = scene.bodies[0]
    size = (f"box {body.shape.width:.3f} x {body.shape.height:.3f} m" if body.shape.kind == "box"
            else f"rod {body.shape.length:.3f} m, r {body.shape.radius:.3f} m")
    return (f"{size}, v = ({body.velocity[0]:.3f}, {body.velocity[1]:.3f}) m/s, "
            f"ω = {body.angular_velocity:.3f} rad/s, μ = {scene.friction:.3f}, "
            f"e = {scene.restitution:.3f}")


if __name__ == "__main__":  # python -m harness.reference.flat_faces [problems] [seed]
    import sys

    number = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    table, found = count_flat(number, seed)
    print(f"{number} random flat landings, seed {seed}")
    for key, row in table.items():
        print(f"{key:24s} 0: {row['0']:5d}  1: {row['1']:5d}  2+: {row['2+']:5d}  "
              f"at boundary: {row['boundary']:5d}  split not unique: {row['split']:5d}  "
              f"inadmissible: {row['inadmissible']:5d}  gains: {row['gains']:5d} "
              f"(largest {row['max-gain']:.1%})")
    for key in ("poisson/literal", "poisson/effective"):
        for bucket, scene in found[key].items():
            print(f"first {key} with {bucket}: {describe(scene)}")
