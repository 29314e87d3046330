"""Newton–Coulomb on m contacts counted by post-impact velocity, against an independent count.

The count here is written separately from ``planar_impact.simultaneous``: it works in the
body's velocities and the impulses together (the impulse–momentum balance (75) plus each
contact's mode equations, a 7 × 7 system for one body and two contacts), not in contact
space with the Delassus matrix, and where the system is singular (a flat face: the impulses
are a one-parameter family) it finds the interval of the family on which every inequality
holds instead of testing one member. Solutions are then clustered by post-impact velocity.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from planar_impact import simultaneous as sim

SEPARATE, STICK, SLIDE_PLUS, SLIDE_MINUS = range(4)


def random_flat_landing(rng):
    """A box or rod lying flat on the ground (both bottom ends touching), random size,
    inertia, speeds, spin, μ and e; at least one end approaches."""
    width = rng.uniform(0.2, 2.0)
    depth = rng.uniform(0.01, 0.5)  # half-height of the box, or the rod's cap radius
    mass = 1.0
    inertia = mass * (width ** 2 + (2 * depth) ** 2) / 12 if rng.random() < 0.5 else (
        mass * width ** 2 / 12)
    while True:
        u = np.array([rng.uniform(-1, 1), rng.uniform(-2, -0.2), rng.uniform(-3, 3)])
        if u[1] - abs(u[2]) * width / 2 < 0:
            break
    corners = [(-width / 2, -depth), (width / 2, -depth)]
    wn = np.array([(0.0, 1.0, rx) for rx, _ in corners])  # n = +y: v_y + ω r_x
    wt = np.array([(1.0, 0.0, -ry) for _, ry in corners])  # t = +x: v_x − ω r_y
    return dict(mass_matrix=np.diag([mass, mass, inertia]), wn=wn, wt=wt, u=u,
                mu=rng.uniform(0, 1, 2), e=rng.uniform(0, 1, 2))


def independent_velocities(problem, tolerance=1e-9):
    """Every distinct post-impact velocity of the Newton–Coulomb law, by modes in (u', λ)."""
    mass, wn, wt, u = (problem[k] for k in ("mass_matrix", "wn", "wt", "u"))
    mu, e = problem["mu"], problem["e"]
    count, size = len(wn), len(u)
    targets = e * np.maximum(-(wn @ u), 0.0)
    speed = float(np.max(np.abs(np.concatenate([wn @ u, wt @ u])))) + float(np.max(np.abs(u)))
    impulse = speed * float(np.max(np.diag(mass)))
    unknowns = size + 2 * count  # u' then (λ_n, λ_t) per contact
    found = []
    for modes in itertools.product(range(4), repeat=count):
        rows, rhs, inequalities = [], [], []  # inequality rows a: a·x ≥ 0 (scaled)
        for r in range(size):  # M u' − Σ (w_n λ_n + w_t λ_t) = M u
            row = np.zeros(unknowns)
            row[:size] = mass[r]
            for i in range(count):
                row[size + 2 * i] = -wn[i, r]
                row[size + 2 * i + 1] = -wt[i, r]
            rows.append(row)
            rhs.append(float(mass[r] @ u))

        def velocity_row(vector):
            row = np.zeros(unknowns)
            row[:size] = vector
            return row

        for i, mode in enumerate(modes):
            n_index, t_index = size + 2 * i, size + 2 * i + 1
            unit_n, unit_t = np.eye(unknowns)[n_index], np.eye(unknowns)[t_index]
            if mode == SEPARATE:
                rows += [unit_n, unit_t]
                rhs += [0.0, 0.0]
                inequalities.append((velocity_row(wn[i]), targets[i], speed))  # v_n ≥ target
                continue
            rows.append(velocity_row(wn[i]))  # v_n' = e|v_n^A|
            rhs.append(targets[i])
            inequalities.append((unit_n, 0.0, impulse))  # λ_n ≥ 0
            if mode == STICK:
                rows.append(velocity_row(wt[i]))  # v_t' = 0
                rhs.append(0.0)
                inequalities.append((mu[i] * unit_n - unit_t, 0.0, impulse))  # |λ_t| ≤ μ λ_n
                inequalities.append((mu[i] * unit_n + unit_t, 0.0, impulse))
            else:
                direction = 1.0 if mode == SLIDE_PLUS else -1.0  # the final slip's sign
                rows.append(unit_t + direction * mu[i] * unit_n)  # λ_t = −direction μ λ_n
                rhs.append(0.0)
                inequalities.append((direction * velocity_row(wt[i]), 0.0, speed))
        matrix, rhs = np.array(rows), np.array(rhs)
        left, values, right = np.linalg.svd(matrix)
        rank = int(np.sum(values > 1e-10 * values[0]))
        particular = right[:rank].T @ ((left[:, :rank].T @ rhs) / values[:rank])
        if np.max(np.abs(matrix @ particular - rhs)) > 1e-9 * (speed + impulse):
            continue
        null = right[rank:]  # at most one direction here (a flat face)
        assert len(null) <= 1
        low, high = -np.inf, np.inf
        feasible = True
        for row, bound, scale in inequalities:  # row·(x0 + s z) ≥ bound − tolerance·scale
            slack = float(row @ particular) - bound + tolerance * scale
            slope = float(row @ null[0]) if len(null) else 0.0
            if abs(slope) < 1e-14:
                feasible &= slack >= 0
            elif slope > 0:
                low = max(low, -slack / slope)
            else:
                high = min(high, -slack / slope)
        if not feasible or low > high:
            continue
        if len(null) and np.max(np.abs(null[0][:size])) > 1e-9:
            raise AssertionError("velocities vary within a mode: not a flat landing")
        point = particular + (0.0 if not len(null) else (
            0.0 if low <= 0 <= high else low if np.isfinite(low) else high) * null[0])
        velocity = point[:size]
        if not any(np.max(np.abs(velocity - other)) <= 1e-7 * speed for other in found):
            found.append(velocity)
    return found


def test_newton_coulomb_counts_distinct_velocities_as_an_independent_count_does():
    """On 300 random flat landings the number of solutions with distinct velocities matches
    the independent enumeration, and the velocities are the same."""
    rng = np.random.default_rng(2024)
    split = several = 0
    for k in range(300):
        problem = random_flat_landing(rng)
        result = sim.newton_coulomb(sim.contact_system(**problem))
        expected = independent_velocities(problem)
        assert len(result.solutions) == len(expected), (k, result.status, expected)
        for solution in result.solutions:
            assert min(np.max(np.abs(solution.u_after - v)) for v in expected) < 1e-7, k
        split += result.status == sim.NC_SPLIT_NOT_UNIQUE
        several += result.status == sim.NC_SEVERAL
    assert split > 50  # flat faces: stick–stick families are common, and reported
    # Distinct velocities are rare on flat landings (docs/multi-contact.md).
    assert several < 15


def test_a_symmetric_flat_box_has_one_velocity_and_a_family_of_impulse_splits():
    problem = dict(mass_matrix=np.diag([2.0, 2.0, 5 / 24]),
                   wn=[(0, 1, -0.5), (0, 1, 0.5)], wt=[(1, 0, 0.25), (1, 0, 0.25)],
                   u=[0.0, -1.0, 0.0], mu=0.5, e=0.5)
    result = sim.newton_coulomb(sim.contact_system(**problem))
    assert result.status == sim.NC_SPLIT_NOT_UNIQUE
    (solution,) = result.solutions
    assert not solution.determinate
    np.testing.assert_allclose(solution.u_after, [0.0, 0.5, 0.0], atol=1e-12)


@pytest.mark.parametrize("seed", [0, 1])
def test_no_solution_is_reported_with_its_reason_never_silently_empty(seed):
    rng = np.random.default_rng(seed)
    empty = 0
    for _ in range(300):
        system = sim.random_two_contact_system(rng, "body")
        result = sim.newton_coulomb(system)
        assert result.status in sim.NC_STATUSES
        if result.status == sim.NC_NONE:
            empty += 1
            assert result.solutions == ()
            assert "none of the 4^2 contact modes holds" in result.explanation
            assert result.gauss_seidel is not None and not result.gauss_seidel.converged
        else:
            assert result.solutions
    assert empty > 0  # random obstacles on one body do jam (docs/multi-contact.md)
