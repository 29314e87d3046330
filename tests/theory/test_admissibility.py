"""Admissibility of every m-contact reference on broad families of flat landings, checked by
a checker written here from the rigid body's equations alone (docs/multi-contact.md,
'Admissible references').

The checker takes ``M``, the contact rows, ``u``, ``μ_i``, ``e_i`` and a solution's impulses
per phase; it chains the phases from ``u`` with ``M⁻¹`` (never the code's ``W``, its phase
velocities or its energy) and checks: the friction cone per phase, no penetration, no
impulse at a contact receding at the start of a per-contact impact, complementarity at the
end of every complementarity phase, and no energy gain where the law promises none.

The family (:func:`flat_landing`): one body lying flat on two points of a face: a box, a rod,
or a body whose centre of mass is anywhere over the face with any radius of gyration;
masses, sizes and speeds log-uniform over four decades; spin; ``μ_i`` ∈ [0, 1.5] and
``e_i`` ∈ [0, 1] drawn per contact. ``make test`` draws :data:`DRAWS`; the full search,
10^5 draws::

    ADMISSIBILITY_DRAWS=100000 .venv/bin/python -m pytest -q -p no:xdist --timeout=0 \\
        tests/theory/test_admissibility.py
"""

from __future__ import annotations

import os

import numpy as np
import pytest

from planar_impact import multicontact as mc
from planar_impact import simultaneous as sim
from planar_impact.multicontact import families

#: Draws per test in ``make test``; the environment's ADMISSIBILITY_DRAWS for the full search.
DRAWS = int(os.environ.get("ADMISSIBILITY_DRAWS", "150"))
#: The checker's tolerances: speeds relative to the largest approach speed, impulses to the
#: largest impulse of the solution, energy to ½uᵀMu. The laws solve to rounding (≲ 1e-12).
SPEED, IMPULSE, ENERGY = 1e-7, 1e-7, 1e-8


def flat_landing(rng, shape):
    """``(M, wn, wt, u, μ, e)`` of one flat landing of the family (module docstring)."""
    size = np.exp(rng.uniform(np.log(0.01), np.log(100.0)))
    mass = np.exp(rng.uniform(np.log(0.01), np.log(100.0)))
    if shape == "box":
        height = size * np.exp(rng.uniform(np.log(0.02), np.log(5.0)))
        left, right, depth = -size / 2, size / 2, height / 2
        gyration = (size**2 + height**2) / 12
    elif shape == "rod":
        radius = size * rng.uniform(0.002, 0.2)
        left, right, depth = -size / 2, size / 2, radius
        gyration = size**2 / 12 + radius**2 / 4
    else:  # any body: the centre of mass anywhere over the face, any radius of gyration
        offset = rng.uniform(0.0, 1.0)
        left, right = -offset * size, (1 - offset) * size
        depth = size * np.exp(rng.uniform(np.log(0.01), np.log(3.0)))
        gyration = (size * np.exp(rng.uniform(np.log(0.05), np.log(2.0))))**2
    speed = np.exp(rng.uniform(np.log(0.01), np.log(100.0)))
    while True:
        u = speed * np.array([rng.uniform(-1, 1), rng.uniform(-1, -0.05),
                              rng.uniform(-3, 3) / size])
        if min(u[1] + u[2] * left, u[1] + u[2] * right) < 0:
            break
    wn = np.array([[0.0, 1.0, left], [0.0, 1.0, right]])
    wt = np.array([[1.0, 0.0, depth], [1.0, 0.0, depth]])
    return (np.diag([mass, mass, mass * gyration]), wn, wt, u, rng.uniform(0, 1.5, 2),
            rng.uniform(0, 1, 2))


def landings(seed, count=DRAWS):
    rng = np.random.default_rng(seed)
    for k in range(count):
        problem = flat_landing(rng, ("box", "rod", "body")[k % 3])
        yield problem, sim.contact_system(mass_matrix=problem[0], wn=problem[1],
                                          wt=problem[2], u=problem[3], mu=problem[4],
                                          e=problem[5])


def breaks(problem, phases, no_gain, slack=1.0):
    """What a solution breaks; ``phases`` are ``(kind, impulses (m, 2), base or None)``,
    kind ``compression``, ``restitution``, ``newton`` or ``impact``; ``slack`` multiplies
    the tolerances."""
    mass_matrix, wn, wt, u, mu, e = problem
    approach = wn @ u
    speed = slack * SPEED * np.max(np.abs(np.concatenate([approach, wt @ u])))
    largest = max(np.max(np.abs(impulses)) for _, impulses, _ in phases) if phases else 0.0
    impulse = slack * IMPULSE * max(largest, 1e-300)
    found = []
    current = u.copy()
    for k, (kind, impulses, base) in enumerate(phases):
        start = wn @ current
        current = current + np.linalg.solve(mass_matrix, wn.T @ impulses[:, 0]
                                            + wt.T @ impulses[:, 1])
        end = wn @ current
        owed = np.zeros(len(mu)) if base is None else base
        for i, (normal, tangential) in enumerate(impulses):
            if normal < -impulse or abs(tangential) > mu[i] * normal + impulse:
                found.append("cone")
            target = e[i] * max(-approach[i], 0.0) if kind == "newton" else 0.0
            checked = kind != "impact" or normal > impulse or k == len(phases) - 1
            if checked and end[i] < target - speed:
                found.append("penetration")
            if kind == "impact" and start[i] > speed and normal > impulse:
                found.append("receding impulse")
            if kind != "impact" and normal - owed[i] > impulse and end[i] > target + speed:
                found.append("complementarity")
    gain = 0.5 * (current @ mass_matrix @ current - u @ mass_matrix @ u)
    if no_gain and gain > slack * ENERGY * 0.5 * (u @ mass_matrix @ u):
        found.append("energy gain")
    return found


def per_contact(impulses):
    return np.asarray(impulses, dtype=float).reshape(-1, 2)


def two_phase(answer, system):
    compression = per_contact(answer.compression.impulses)
    return [("compression", compression, None),
            ("restitution", per_contact(answer.restitution.impulses),
             answer.restitution_scale * system.e * compression[:, 0])]


def test_the_checker_finds_each_break_it_checks():
    """Each check can fail: made-up solutions of the worked flat box (2 kg, 1 m × 0.5 m,
    1 m/s down) that break one thing each."""
    box = (np.diag([2.0, 2.0, 5 / 24]), np.array([[0, 1, -0.5], [0, 1, 0.5]], dtype=float),
           np.array([[1, 0, 0.25], [1, 0, 0.25]], dtype=float), np.array([0.0, -1.0, 0.0]),
           np.array([0.5, 0.5]), np.array([0.5, 0.5]))
    stop, half = np.array([[1.0, 0.0], [1.0, 0.0]]), np.array([[0.5, 0.0], [0.5, 0.0]])
    assert breaks(box, [("compression", stop, None), ("restitution", half, half[:, 0])],
                  True) == []
    assert "cone" in breaks(box, [("compression", np.array([[1.0, 0.6], [1.0, -0.6]]), None)],
                            False)
    assert "complementarity" in breaks(box, [("compression", 1.2 * stop, None)], False)
    assert "penetration" in breaks(box, [("compression", 0.8 * stop, None)], False)
    assert "energy gain" in breaks(box, [("impact", 2.5 * stop, None)], True)
    spinning = box[:3] + (np.array([0.0, -1.0, 4.0]),) + box[4:]  # the right end recedes
    assert "receding impulse" in breaks(spinning, [("impact", stop, None)], False)


def test_the_two_phase_law_is_admissible_on_broad_flat_landings():
    """No break of any check, no energy gain, on every answer (both methods)."""
    for problem, system in landings(1):
        for method in mc.METHODS:
            for answer in mc.poisson_two_phase(system, method):
                assert breaks(problem, two_phase(answer, system), True) == [], (problem, method)


def test_the_literal_reading_gives_a_receding_contact_no_impulse():
    """The paper's proposal, every law: an end that does not approach takes no impulse (and
    one that approaches is coherent only where the other end stays out of the ground)."""
    for problem, system in landings(2):
        for law in sim.TYPE_LAWS:
            for solution in sim.coherent_solutions(system, law):
                impulses = np.column_stack([solution.normal_impulse,
                                            solution.tangential_impulse])
                found = breaks(problem, [("impact", impulses, None)], False)
                assert "receding impulse" not in found and "penetration" not in found


def test_newton_coulomb_is_admissible_and_its_gains_are_found():
    """Newton–Coulomb keeps its own complementarity (v_n^S ≥ e|v_n^A|, equal where an
    impulse acts; a receding end only held at 0) and the cone; it can gain energy, a
    property of Newton's law (docs/multi-contact.md, 'Where Newton–Coulomb gains energy')."""
    gains = 0
    for problem, system in landings(3):
        for solution in sim.newton_coulomb_solutions(system):
            impulses = np.column_stack([solution.normal_impulse, solution.tangential_impulse])
            assert breaks(problem, [("newton", impulses, None)], False) == []
            gains += breaks(problem, [("newton", impulses, None)], True) != []
    assert gains < DRAWS / 10


def test_the_run_time_check_agrees_with_this_checker():
    """planar_impact.simultaneous.violations, which the references run on every solution,
    flags what this checker flags, on every reference's solutions (the paper's proposal in
    both readings breaks often; the effective reading gives impulses at receding ends). The
    two scale their tolerances differently, so they are compared outside a band: what this
    checker flags with its tolerances ×100 is flagged, and what is flagged this checker
    flags with its tolerances ×0.01."""
    flagged = 0
    for problem, system in landings(4, max(DRAWS // 3, 30)):
        for name, law, phases in families.reference_solutions(system):
            ours = []
            for phase in phases:
                base = None if phase.base is None else phase.base
                ours.append((phase.kind, per_contact(phase.impulses), base))
            no_gain = sim.promises_no_gain(law)
            found = sim.violations(system, phases, promises_no_gain=no_gain)
            clear = breaks(problem, ours, no_gain, slack=100.0)
            assert not clear or found, (name, clear)
            assert not found or breaks(problem, ours, no_gain, slack=0.01), (name, found)
            flagged += bool(found)
    assert flagged > 0


def test_the_centred_box_of_issue_34_gains_nothing():
    """A centred uniform box (2.01 × 2.93 m, 0.311 kg, μ 0.476, e 0.983): the slip-following
    compression gave one corner impulse in a piece and let it recede by the phase's end
    (P_n > 0 with v̄_n > 0), and the answer gained 5.0% of ½uᵀMu. Its compression is now
    complementary and the answer loses energy."""
    width, height, mass = 2.01, 2.93, 0.311
    problem = (np.diag([mass, mass, mass * (width**2 + height**2) / 12]),
               np.array([[0, 1, -width / 2], [0, 1, width / 2]]),
               np.array([[1, 0, height / 2], [1, 0, height / 2]]),
               np.array([0.586, -1.474, -0.832]), np.array([0.476] * 2), np.array([0.983] * 2))
    system = sim.contact_system(mass_matrix=problem[0], wn=problem[1], wt=problem[2],
                                u=problem[3], mu=problem[4], e=problem[5])
    for method in mc.METHODS:
        (answer,) = mc.poisson_two_phase(system, method)
        assert breaks(problem, two_phase(answer, system), True) == []
        assert answer.energy_change < -0.05 * 0.5 * problem[3] @ problem[0] @ problem[3]


@pytest.mark.parametrize("seed", [1224, 6171, 9541])
def test_the_property_family_seeds_that_gained(seed):
    """Seeds of tests/theory/test_multicontact.py's flat family (unequal e_i) where the
    slip-following law gained energy: admissible now."""
    rng = np.random.default_rng(seed)
    width, height = rng.uniform(0.2, 2.0), rng.uniform(0.02, 1.0)
    while True:
        u = np.array([rng.uniform(-1, 1), rng.uniform(-2, -0.2), rng.uniform(-3, 3)])
        if u[1] - abs(u[2]) * width / 2 < 0:
            break
    mass, mu, e = rng.uniform(0.2, 5.0), rng.uniform(0, 1, 2), rng.uniform(0, 1, 2)
    problem = (np.diag([mass, mass, mass * (width**2 + height**2) / 12]),
               np.array([[0, 1, -width / 2], [0, 1, width / 2]]),
               np.array([[1, 0, height / 2], [1, 0, height / 2]]), u, mu, e)
    system = sim.contact_system(mass_matrix=problem[0], wn=problem[1], wt=problem[2], u=u,
                                mu=mu, e=e)
    for method in mc.METHODS:
        for answer in mc.poisson_two_phase(system, method):
            assert breaks(problem, two_phase(answer, system), True) == []


def test_a_restitution_that_would_gain_is_scaled_down_to_lose_energy():
    """A body whose centre of mass is 0.6 mm from one end of a 35 mm face, spinning fast,
    e = 0.27 and 0.97 (found by this file's full search): the compression stops it, and
    Poisson's restitution e_i P_nc alone would give back 5.3% more than ½uᵀMu (Glocker's
    consistency condition fails for different e_i). The law scales the restitution's base
    by the largest λ that loses no energy (≈ 0.975); the plain law, not scaled, gains."""
    mass, inertia = 0.23544997845, 1.7572188e-06
    problem = (np.diag([mass, mass, inertia]),
               np.array([[0, 1, -0.00055838], [0, 1, 0.03460829]]),
               np.array([[1, 0, 0.0038720416594], [1, 0, 0.0038720416594]]),
               np.array([0.66419303, -0.59843889, -126.39346352]),
               np.array([1.1987958, 1.25749849]), np.array([0.27119267, 0.97354755]))
    system = sim.contact_system(mass_matrix=problem[0], wn=problem[1], wt=problem[2],
                                u=problem[3], mu=problem[4], e=problem[5])
    kinetic = 0.5 * problem[3] @ problem[0] @ problem[3]
    for method in mc.METHODS:
        (answer,) = mc.poisson_two_phase(system, method)
        assert 0.95 < answer.restitution_scale < 0.99
        assert -1e-9 * kinetic < answer.energy_change <= 1e-12 * kinetic
        assert breaks(problem, two_phase(answer, system), True) == []
    (plain,) = mc.poisson_two_phase(system, follow_slip=False)
    assert plain.restitution_scale == 1.0 and plain.energy_change > 0.05 * kinetic


def test_the_scan_runs_as_a_script_and_counts_every_reference():
    """``python -m planar_impact.multicontact admissible DRAWS SEED`` (docs/multi-contact.md,
    'Admissible references'): one line per reference, the two-phase law never inadmissible."""
    import subprocess
    import sys
    from pathlib import Path

    src = Path(__file__).resolve().parents[2] / "src"
    done = subprocess.run([sys.executable, "-m", "planar_impact.multicontact", "admissible",
                           "6", "0"], capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, PYTHONPATH=str(src)))
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == "6 flat landings (boxes, rods, polygons), seed 0"
    rows = dict(line.split(": ", 1) for line in lines[1:])
    assert rows["newton-coulomb"].startswith("{'solutions': 6,")
    assert "'inadmissible': 0," in rows["two-phase/poisson"]
