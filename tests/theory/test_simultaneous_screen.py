"""The screened ``coherent_solutions`` against the unscreened one, bit for bit.

``coherent_solutions`` drops most type combinations before their fixed-point solve
(``_candidates``: the literal reading's one orientation per contact, a batched linear solve
for Poisson and Newton; the paper's Stronge is screened after its solve, at its fixed points),
and solves the ones it keeps together (``_fixed_points``: the map evaluated for every combination
and every Jacobian column in one batched call); they are checked by the same code as before.
``unscreened_coherent_solutions`` below is the implementation before the screen and the
batch, one combination at a time on scalars, kept as the reference: both must return the
same solutions in the same order with the same floats. Thousands of problems (and half as many
random flat landings): ``python tests/theory/test_simultaneous_screen.py PROBLEMS SEED``.
"""

from __future__ import annotations

import itertools
import math
import sys

import numpy as np
import pytest

from harness.reference import flat_faces
from harness.run import references
from harness.scenarios import load_scenario
from planar_impact import laws
from planar_impact import simultaneous as sim
from planar_impact.simultaneous import coherent, type_map
from planar_impact.simultaneous.system import frame_sign

TYPE_LAWS = ("poisson", "stronge-paper", "newton")
FIELDS = ("normal_impulse", "tangential_impulse", "delta_u", "u_after", "vn_approach",
          "vt_approach", "vn_separation", "vt_separation")


def scalar_forced_impulses(law, ctype, mnn, mnt, mtt, vn, vt, mu, e, delta=None):
    """One contact's impulses by type ``ctype``'s formulas, on numpy scalars (as before)."""
    scalars = [np.float64(x) for x in (mnn, mnt, mtt, vn, vt, mu)]
    terms = laws.ContactTerms(*scalars, None if delta is None else np.float64(delta))
    with np.errstate(all="ignore"):
        if law == "poisson":
            return laws.poisson_impulses(terms, np.float64(e), ctype)
        if law == "stronge-paper":
            e_i = laws.stronge_paper_restitution(terms, np.float64(e), ctype)
            return laws.poisson_impulses(terms, e_i, ctype)
        vn_abs, target = terms.vn_abs, e * terms.vn_abs
        if ctype == laws.NEWTON_FORWARD:
            normal = (target + vn_abs) / terms.h
            return normal, -mu * normal
        p_g = vt / terms.g
        vn_g = terms.h * p_g - vn_abs
        sticks = ctype == laws.NEWTON_STICK
        slope_n = terms.delta / mtt if sticks else terms.q
        slope_t = -mnt / mtt if sticks else mu
        normal = p_g + (target - vn_g) / slope_n
        return normal, -mu * p_g + slope_t * (normal - p_g)


def scalar_contact_map(system, law, ctypes, signs, coupling="effective"):
    """One combination's map ``I ↦ forced impulses at the effective approach`` (as before)."""

    def apply(impulses):
        if coupling == "literal":
            impulses = np.zeros(2 * system.count)
        out = np.zeros(2 * system.count)
        for i, (ctype, sign) in enumerate(zip(ctypes, signs)):
            if ctype == sim.SEPARATING:
                continue
            mnn, mnt, mtt = system.single_terms(i)
            vn, vt = system.effective_approach(i, impulses)
            normal, tangential = scalar_forced_impulses(law, ctype, mnn, sign * mnt, mtt, vn,
                                                        sign * vt, system.mu[i], system.e[i],
                                                        system.deltas[i])
            out[2 * i], out[2 * i + 1] = float(normal), sign * float(tangential)
        return out

    return apply


def scalar_fixed_point(system, mapping, max_iterations=30):
    """One combination's Newton iteration with a central-difference Jacobian (as before):
    ``(I, converged, determinate)``."""
    size = 2 * system.count
    scale = system.impulse_scale()
    impulses = mapping(np.zeros(size))
    determinate = True
    previous = math.inf
    for _ in range(max_iterations):
        if not np.isfinite(impulses).all():
            return impulses, False, determinate
        residual = impulses - mapping(impulses)
        size_now = np.max(np.abs(residual))
        bound = scale + np.max(np.abs(impulses))
        if size_now <= sim.ROUNDING_RESIDUAL * bound or size_now > 0.5 * previous:
            return impulses, size_now <= sim.FIXED_POINT_TOLERANCE * bound, determinate
        previous = size_now
        step = 1e-6 * (scale + np.max(np.abs(impulses)))
        jacobian = np.eye(size)
        for k in range(size):
            shift = np.zeros(size)
            shift[k] = step
            jacobian[:, k] -= (mapping(impulses + shift) - mapping(impulses - shift)) / (2 * step)
        if not np.isfinite(jacobian).all():
            return impulses, False, determinate
        correction, _, rank, _ = np.linalg.lstsq(jacobian, -residual, rcond=1e-9)
        determinate = rank == size
        impulses = impulses + correction
    residual = np.max(np.abs(impulses - mapping(impulses)))
    bound = scale + np.max(np.abs(impulses))
    return impulses, bool(residual <= sim.FIXED_POINT_TOLERANCE * bound), determinate


def unscreened_coherent_solutions(system, law, coupling="effective", allow_separating=False):
    """``coherent_solutions`` before the screen and the batch: every combination through its
    own scalar fixed point."""
    choices = ((sim.SEPARATING,) if allow_separating else ()) + sim.TYPE_LAWS[law]
    tolerance = sim.VELOCITY_TOLERANCE * system.speed_scale()
    found = []
    for types in itertools.product(choices, repeat=system.count):
        for signs in itertools.product((1.0, -1.0), repeat=system.count):
            if any(t == sim.SEPARATING and s < 0 for t, s in zip(types, signs)):
                continue
            mapping = scalar_contact_map(system, law, types, signs, coupling)
            impulses, converged, determinate = scalar_fixed_point(system, mapping)
            if not converged:
                continue
            solution = coherent._check_combination(system, law, types, signs, impulses,
                                              determinate, tolerance, coupling)
            if solution is not None and not coherent._already_found(found, solution, system):
                found.append(solution)
    return found


def differences(system, law, coupling, allow_separating=False) -> list[str]:
    """What differs between the screened and the unscreened solutions (empty if nothing)."""
    expected = unscreened_coherent_solutions(system, law, coupling, allow_separating)
    got = sim.coherent_solutions(system, law, coupling=coupling,
                                 allow_separating=allow_separating)
    if [s.types for s in got] != [s.types for s in expected]:
        return [f"types {[s.types for s in got]} != {[s.types for s in expected]}"]
    out = []
    for new, old in zip(got, expected):
        out += [f"{new.types} {name}" for name in FIELDS
                if not np.array_equal(getattr(new, name), getattr(old, name))]
        if new.energy_change != old.energy_change or new.determinate != old.determinate:
            out.append(f"{new.types} energy or determinate")
    return out


def compare_random(problems: int, seed: int) -> tuple[int, int, list[str]]:
    """``(cases, solutions, failures)`` over ``problems`` random two-contact systems
    (alternating the generic and the one-body family), every law and reading; every fifth
    problem also with separating contacts allowed."""
    rng = np.random.default_rng(seed)
    cases, solutions, failures = 0, 0, []
    for k in range(problems):
        system = sim.random_two_contact_system(rng, "generic" if k % 2 == 0 else "body")
        for law in TYPE_LAWS:
            for coupling in sim.COUPLINGS:
                for separating in (False, True) if k % 5 == 0 else (False,):
                    cases += 1
                    solutions += len(sim.coherent_solutions(
                        system, law, coupling=coupling, allow_separating=separating))
                    failures += [f"problem {k} {law} {coupling} separating={separating}: {d}"
                                 for d in differences(system, law, coupling, separating)]
    return cases, solutions, failures


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_random_two_contact_problems_match_the_unscreened_path(seed):
    cases, solutions, failures = compare_random(12, seed)
    assert failures == []
    assert solutions > 0  # the comparison saw solutions to compare


def flat_systems() -> list[sim.ContactSystem]:
    """The contact systems of the library's flat-face and tilted-landing points, as the
    references build them (every point of flat-*.toml and sweep-tilted-*.toml)."""
    names = ["flat-box", "flat-box-receding-end", "flat-box-slip", "flat-box-spin",
             "flat-rod", "sweep-tilted-box", "sweep-tilted-rod"]
    systems = []
    original = sim.coherent_solutions

    def record(system, law="poisson", **options):
        if law == "poisson" and options.get("coupling") == "effective":
            systems.append(system)  # once per point: the first law and reading it is asked
        return original(system, law, **options)

    sim.coherent_solutions = record
    try:
        for name in names:
            scenario = load_scenario(f"scenarios/{name}.toml")
            for point in scenario.point_list():
                references.point_reference(scenario, point)
    finally:
        sim.coherent_solutions = original
    return systems


def test_library_flat_and_tilted_points_match_the_unscreened_path():
    systems = flat_systems()
    assert len(systems) >= 7
    failures, solutions = [], 0
    for k, system in enumerate(systems):
        for law in TYPE_LAWS:
            for coupling in sim.COUPLINGS:
                solutions += len(sim.coherent_solutions(system, law, coupling=coupling))
                failures += [f"system {k} {law} {coupling}: {d}"
                             for d in differences(system, law, coupling)]
    assert failures == []
    assert solutions > 0


def compare_flat(problems: int, seed: int) -> tuple[int, list[str]]:
    """``(solutions, failures)`` over random flat landings (harness.reference.flat_faces:
    a box or a rod lying flat, both ends on the ground), every law and reading."""
    rng = np.random.default_rng(seed)
    solutions, failures = 0, []
    for k in range(problems):
        system = flat_faces.flat_system(flat_faces.random_flat_scene(rng))
        for law in TYPE_LAWS:
            for coupling in sim.COUPLINGS:
                solutions += len(sim.coherent_solutions(system, law, coupling=coupling))
                failures += [f"flat {k} {law} {coupling}: {d}"
                             for d in differences(system, law, coupling)]
    return solutions, failures


def test_random_flat_landings_match_the_unscreened_path():
    solutions, failures = compare_flat(12, 0)
    assert failures == []
    assert solutions > 0


def test_the_screen_drops_most_combinations(monkeypatch):
    # The point of the screen: a handful of the 100 combinations reach the solve (Poisson,
    # Newton) or the checks (the paper's Stronge, screened at its fixed points).
    rng = np.random.default_rng(9)  # a problem with two or three solutions per law
    system = sim.random_two_contact_system(rng)
    tolerance = sim.VELOCITY_TOLERANCE * system.speed_scale()
    checked = []
    original = coherent._check_combination

    def counted(*args, **options):
        checked.append(args[2:4])
        return original(*args, **options)

    monkeypatch.setattr(coherent, "_check_combination", counted)
    for law in TYPE_LAWS:
        every = list(coherent._combinations(sim.TYPE_LAWS[law], 2))
        literal = coherent._candidates(system, law, sim.TYPE_LAWS[law], "literal", tolerance)
        effective = coherent._candidates(system, law, sim.TYPE_LAWS[law], "effective", tolerance)
        checked.clear()
        sim.coherent_solutions(system, law, coupling="effective")
        assert len(literal) == len(sim.TYPE_LAWS[law]) ** 2  # the paper's 5^m (3^m)
        if law in sim.AFFINE_LAWS:
            assert len(effective) < len(every) / 2
        else:
            assert effective == every
        assert 0 < len(checked) < len(every) / 10


def random_system(rng, count):
    """A random approaching system of ``count`` contacts on ``2 count`` generalized speeds."""
    size = 2 * count
    root = rng.normal(size=(size, size))
    wn, wt = rng.normal(size=(count, size)), rng.normal(size=(count, size))
    while True:
        u = rng.normal(size=size)
        if np.all(wn @ u < 0):
            break
    return sim.contact_system(mass_matrix=root @ root.T + 0.1 * np.eye(size), wn=wn, wt=wt, u=u,
                              mu=rng.uniform(0, 1, count), e=rng.uniform(0, 1, count))


def whole_map_jacobian(mapping, impulses, rows, step):
    """The central-difference Jacobian as formed before the block structure: both shifted
    points of every column through the whole map."""
    number, size = impulses.shape
    jacobian = np.broadcast_to(np.eye(size), (number, size, size)).copy()
    for k in range(size):
        shift = np.zeros((number, size))
        shift[:, k] = step
        jacobian[:, :, k] -= (mapping(impulses + shift, rows)
                              - mapping(impulses - shift, rows)) / (2 * step)[:, None]
    return mapping(impulses, rows), jacobian


def assert_same_floats(got, expected):
    np.testing.assert_array_equal(got, expected)  # NaN where NaN (its sign bit is free)
    numbers = ~np.isnan(expected)
    assert np.array_equal(np.signbit(got[numbers]), np.signbit(expected[numbers]))


@pytest.mark.parametrize("count", [2, 3])
def test_the_block_jacobian_is_the_whole_map_jacobian_bit_for_bit(count):
    # _map_and_jacobian evaluates a contact only at the other contacts' shifts; its own
    # columns must still come out as the whole map's differences, NaN rows included.
    rng = np.random.default_rng(count)
    for _ in range(4):
        system = random_system(rng, count)
        for law in TYPE_LAWS:
            combinations = list(coherent._combinations((sim.SEPARATING,) + sim.TYPE_LAWS[law],
                                                  count))
            types = np.array([t for t, _ in combinations], dtype=np.int64)
            signs = np.array([s for _, s in combinations], dtype=float)
            mapping = type_map.contact_map(system, law, types, signs)
            impulses = rng.normal(size=(len(combinations), 2 * count)) * system.impulse_scale()
            impulses[::7, 0] = np.nan
            impulses[1::7, 1] = 0.0
            rows = rng.permutation(len(combinations))
            step = 1e-6 * (system.impulse_scale() + np.max(np.abs(impulses), axis=1))
            got = type_map.map_and_jacobian(mapping, impulses, rows, step)
            expected = whole_map_jacobian(mapping, impulses, rows, step)
            assert np.isfinite(got[1]).any() and np.isnan(got[1]).any()
            for new, old in zip(got, expected):
                assert_same_floats(new, old)


def test_the_batched_map_is_each_contacts_scalar_formulas():
    # One batched call for every contact gives each contact's scalar answer, bit for bit.
    rng = np.random.default_rng(11)
    for count in (2, 3):
        system = random_system(rng, count)
        for law in TYPE_LAWS:
            combinations = list(coherent._combinations((sim.SEPARATING,) + sim.TYPE_LAWS[law],
                                                  count))
            types = np.array([t for t, _ in combinations], dtype=np.int64)
            signs = np.array([s for _, s in combinations], dtype=float)
            impulses = rng.normal(size=(len(combinations), 2 * count)) * system.impulse_scale()
            got = type_map.contact_map(system, law, types, signs)(impulses,
                                                               np.arange(len(combinations)))
            for row, (ctypes, csigns) in enumerate(combinations):
                expected = scalar_contact_map(system, law, ctypes, csigns)(impulses[row])
                assert_same_floats(got[row], expected)


@pytest.mark.parametrize("separating", [False, True])
def test_literal_candidates_are_the_orientation_filtered_enumeration(separating):
    # The literal reading's candidates: every type tuple (the paper's 5^m), each contact's
    # tangent oriented by its own v^A(i), in enumeration order.
    rng = np.random.default_rng(3)
    for k in range(20):
        system = sim.random_two_contact_system(rng, "generic" if k % 2 else "body")
        tolerance = sim.VELOCITY_TOLERANCE * system.speed_scale()
        for law in TYPE_LAWS:
            choices = ((sim.SEPARATING,) if separating else ()) + sim.TYPE_LAWS[law]
            own = [frame_sign(float(system.approach[2 * i + 1]), system.single_terms(i)[1])
                   for i in range(system.count)]
            expected = [(types, signs) for types, signs in coherent._combinations(choices, 2)
                        if all(t == sim.SEPARATING or s == own[i]
                               for i, (t, s) in enumerate(zip(types, signs)))]
            got = coherent._candidates(system, law, choices, "literal", tolerance)
            assert got == expected
            assert len(expected) == len(choices) ** 2


if __name__ == "__main__":  # python tests/theory/test_simultaneous_screen.py PROBLEMS SEED
    count, found, failed = compare_random(int(sys.argv[1]), int(sys.argv[2]))
    print(f"random: {count} cases, {found} solutions, {len(failed)} differences")
    flat_found, flat_failed = compare_flat(int(sys.argv[1]) // 2, int(sys.argv[2]))
    print(f"flat landings: {flat_found} solutions, {len(flat_failed)} differences")
    for line in failed + flat_failed:
        print(line)
