"""planar_impact.solver.law_solver (one problem checked once, solved under every law) against
solve, law by law: the same results bit for bit and the same errors."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import planar_impact as pi
from planar_impact.solver import law_solver

GROUND = pi.builders.rigid_body_against_ground(
    pi.PlanarBody(mass=2.0, inertia=0.3, position=(0.1, 0.4), velocity=(0.7, -1.3),
                  angular_velocity=2.1), contact_point=(0.35, 0.0))


def _inputs(problem, mu, e):
    return dict(mass_matrix=problem.mass_matrix, wn=problem.wn, wt=problem.wt, u=problem.u,
                mu=mu, e=e)


def _same(first, second):
    for field in dataclasses.fields(first):
        a, b = getattr(first, field.name), getattr(second, field.name)
        if isinstance(a, np.ndarray):
            assert a.tobytes() == b.tobytes(), field.name
        else:
            assert a == b and type(a) is type(b), field.name


@pytest.mark.parametrize("problem, mu, e", [
    (GROUND, 0.3, 0.8), (GROUND, 0.0, 0.0), (GROUND, 2.0, 1.0),
    (pi.builders.two_sleds(0.3, -0.2), 0.4, 0.6),
])
def test_every_law_bit_for_bit_as_solve(problem, mu, e):
    solve_law = problem.law_solver(mu=mu, e=e)
    for law in pi.LAWS:
        _same(solve_law(law), pi.solve(**_inputs(problem, mu, e), law=law))


def _error(call):
    with pytest.raises(ValueError) as caught:
        call()
    return type(caught.value), str(caught.value)


@pytest.mark.parametrize("change", [
    dict(mu=-0.1), dict(e=1.5), dict(u=-GROUND.u),  # receding: no approach
    dict(mass_matrix=np.diag([2.0, 2.0, -0.3])),  # not positive definite
    dict(wt=GROUND.wn),  # w_n, w_t parallel
    dict(wn=np.array([0.0, np.nan, 1.0])),
])
def test_every_bad_input_raises_what_solve_raises_for_each_law(change):
    inputs = {**_inputs(GROUND, 0.3, 0.8), **change}
    solve_law = law_solver(**inputs)
    for law in (*pi.LAWS, "no-such-law"):
        assert (_error(lambda law=law: solve_law(law))
                == _error(lambda law=law: pi.solve(**inputs, law=law)))
