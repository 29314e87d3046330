"""The screened ``coherent_solutions`` against the unscreened one, bit for bit.

``coherent_solutions`` drops most type combinations before their fixed-point solve
(``_candidates``: the literal reading's single candidate, a batched linear solve for Poisson
and Newton, a batched Newton iteration for the paper's Stronge); the combinations it keeps
are solved and checked by the same code as before. ``unscreened_coherent_solutions`` below
is the implementation before the screen, kept as the reference: both must return the same
solutions in the same order with the same floats. Thousands of problems (and half as many
random flat landings): ``python tests/theory/test_simultaneous_screen.py PROBLEMS SEED``.
"""

from __future__ import annotations

import itertools
import sys

import numpy as np
import pytest

from harness.reference import flat_faces
from harness.run import references
from harness.scenarios import load_scenario
from planar_impact import simultaneous as sim

TYPE_LAWS = ("poisson", "stronge-paper", "newton")
FIELDS = ("normal_impulse", "tangential_impulse", "delta_u", "u_after", "vn_approach",
          "vt_approach", "vn_separation", "vt_separation")


def unscreened_coherent_solutions(system, law, coupling="effective", allow_separating=False):
    """``coherent_solutions`` before the screen: every combination through the fixed point."""
    choices = ((sim.SEPARATING,) if allow_separating else ()) + sim.TYPE_LAWS[law]
    tolerance = sim.VELOCITY_TOLERANCE * system.speed_scale()
    found = []
    for types in itertools.product(choices, repeat=system.count):
        for signs in itertools.product((1.0, -1.0), repeat=system.count):
            if any(t == sim.SEPARATING and s < 0 for t, s in zip(types, signs)):
                continue
            mapping = sim._contact_map(system, law, types, signs, coupling)
            impulses, converged, determinate = sim._fixed_point(system, mapping)
            if not converged:
                continue
            solution = sim._check_combination(system, law, types, signs, impulses,
                                              determinate, tolerance, coupling)
            if solution is not None and not sim._already_found(found, solution, system):
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
    names = ["flat-box", "flat-box-several-poisson", "flat-box-slip", "flat-box-spin",
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


def test_the_screen_drops_most_combinations():
    # The point of the screen: a handful of the 100 Poisson combinations reach the solve.
    rng = np.random.default_rng(5)
    system = sim.random_two_contact_system(rng)
    tolerance = sim.VELOCITY_TOLERANCE * system.speed_scale()
    for law in TYPE_LAWS:
        every = list(sim._combinations(sim.TYPE_LAWS[law], 2))
        literal = sim._candidates(system, law, sim.TYPE_LAWS[law], "none", tolerance)
        effective = sim._candidates(system, law, sim.TYPE_LAWS[law], "effective", tolerance)
        assert len(literal) <= 1
        assert len(effective) < len(every) / 2


if __name__ == "__main__":  # python tests/theory/test_simultaneous_screen.py PROBLEMS SEED
    count, found, failed = compare_random(int(sys.argv[1]), int(sys.argv[2]))
    print(f"random: {count} cases, {found} solutions, {len(failed)} differences")
    flat_found, flat_failed = compare_flat(int(sys.argv[1]) // 2, int(sys.argv[2]))
    print(f"flat landings: {flat_found} solutions, {len(flat_failed)} differences")
    for line in failed + flat_failed:
        print(line)
