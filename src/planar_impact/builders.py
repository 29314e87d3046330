"""Builders of impact problems: ``M``, ``w_n``, ``w_t`` and ``u`` for common systems.

* A free planar rigid body against the fixed ground, and two free planar bodies, with
  ``u = (v_x, v_y, ω)`` per body and ``M = diag(m, m, I_G)`` (docs/theory.md,
  'Contact terms').
* The paper's two-sled system (Section 5), a nonholonomic system with independent speeds
  ``(u1, u3, u4, u6)``.

The tangent is ``t = (n_y, −n_x)``, the normal turned clockwise by 90° (for the ground's
``n = (0, 1)`` that is ``+x``). The solver accepts either orientation of ``t``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .solver import ImpactResult, law_solver, solve


@dataclass(frozen=True)
class PlanarBody:
    """A free rigid body in the plane: mass (kg), moment of inertia about its centre of mass
    (kg m²), centre-of-mass position (m), velocity (m/s) and angular velocity (rad/s, CCW)."""

    mass: float
    inertia: float
    position: tuple[float, float]
    velocity: tuple[float, float] = (0.0, 0.0)
    angular_velocity: float = 0.0

    def speeds(self) -> np.ndarray:
        return np.array([self.velocity[0], self.velocity[1], self.angular_velocity], dtype=float)

    def partial_velocities(self, point, direction) -> np.ndarray:
        """``v_r·d`` for ``u = (v_x, v_y, ω)``.

        The point moves at ``(v_x − ω r_y, v_y + ω r_x)``.
        """
        r_x = point[0] - self.position[0]
        r_y = point[1] - self.position[1]
        d_x, d_y = direction
        return np.array([d_x, d_y, r_x * d_y - r_y * d_x])


@dataclass(frozen=True)
class ImpactProblem:
    """An impact in generalized speeds, ready for :func:`planar_impact.solve`."""

    mass_matrix: np.ndarray
    wn: np.ndarray
    wt: np.ndarray
    u: np.ndarray

    def solve(self, *, mu: float, e: float, law: str = "poisson") -> ImpactResult:
        return solve(mass_matrix=self.mass_matrix, wn=self.wn, wt=self.wt, u=self.u, mu=mu, e=e,
                     law=law)

    def law_solver(self, *, mu: float, e: float) -> Callable[[str], ImpactResult]:
        """``solve_law(law)``, :meth:`solve` with ``law``: the problem checked once for all
        the laws asked (:func:`planar_impact.solver.law_solver`)."""
        return law_solver(mass_matrix=self.mass_matrix, wn=self.wn, wt=self.wt, u=self.u,
                          mu=mu, e=e)

    def kinetic_energy(self, speeds=None) -> float:
        speeds = self.u if speeds is None else np.asarray(speeds, dtype=float)
        return 0.5 * float(speeds @ self.mass_matrix @ speeds)


def _unit(normal) -> tuple[np.ndarray, np.ndarray]:
    n = np.asarray(normal, dtype=float)
    length = float(np.hypot(n[0], n[1]))
    if not length > 0 or not math.isfinite(length):
        raise ValueError(f"normal: must be a finite non-zero 2-vector, got {normal!r}")
    n = n / length
    return n, np.array([n[1], -n[0]])


def rigid_body_against_ground(body: PlanarBody, contact_point, normal=(0.0, 1.0)) -> ImpactProblem:
    """A body (B) hitting fixed ground (A) at ``contact_point``; ``normal`` points into the body."""
    n, t = _unit(normal)
    return ImpactProblem(
        mass_matrix=np.diag([body.mass, body.mass, body.inertia]),
        wn=body.partial_velocities(contact_point, n),
        wt=body.partial_velocities(contact_point, t),
        u=body.speeds(),
    )


def two_bodies(body_a: PlanarBody, body_b: PlanarBody, contact_point, normal) -> ImpactProblem:
    """Two free bodies; ``normal`` points from A into B. ``u`` stacks A's speeds, then B's.

    ``v^R = v^{B_c} − v^{A_c}``, so A's partial velocities enter with a minus sign.
    """
    n, t = _unit(normal)
    return ImpactProblem(
        mass_matrix=np.diag([body_a.mass, body_a.mass, body_a.inertia,
                             body_b.mass, body_b.mass, body_b.inertia]),
        wn=np.concatenate([-body_a.partial_velocities(contact_point, n),
                           body_b.partial_velocities(contact_point, n)]),
        wt=np.concatenate([-body_a.partial_velocities(contact_point, t),
                           body_b.partial_velocities(contact_point, t)]),
        u=np.concatenate([body_a.speeds(), body_b.speeds()]),
    )


# The paper's Section 5 data: m = 3 kg, l = 1 m, s = 0.75 m, c = −0.5 m, q3 = π/4,
# q6 = 7π/4, u1 = u4 = 1 m/s, u3 = u6 = 0.1 rad/s.
TWO_SLED_PARAMETERS = dict(m=3.0, l=1.0, s=0.75, c=-0.5, q3=math.pi / 4, q6=7 * math.pi / 4,
                           u=(1.0, 0.1, 1.0, 0.1))


def two_sleds(gamma: float, delta: float, m: float = 3.0,
              l: float = 1.0,  # noqa: E741 -- the paper's name for the sled length
              s: float = 0.75, c: float = -0.5, q3: float = math.pi / 4,
              q6: float = 7 * math.pi / 4,
              u=(1.0, 0.1, 1.0, 0.1)) -> ImpactProblem:
    """The two-sled collision of the paper's Section 5 (docs/theory.md, 'The two-sled
    example').

    Independent speeds ``u = (u1, u3, u4, u6)``; steering angles ``gamma`` (sled A) and
    ``delta`` (sled B) in rad. Per sled ``M = m [[1/cos²γ, −s tanγ], [−s tanγ, l²/3 + s²]]``.
    With ``λ = q3 − q6``, ``n = a2`` and B's contact at its rod end ``B* + l b1``:
    ``w_n = (−tanγ, −(c − s), −(sinλ − tanδ cosλ), (l − s) cosλ)`` and
    ``w_t = ±(−1, 0, cosλ + tanδ sinλ, (l − s) sinλ)``, the sign making ``v_t^A ≥ 0`` as in
    the paper (``t = ±a1``).
    """
    lam = q3 - q6

    def block(angle):
        return m * np.array([[1.0 / math.cos(angle) ** 2, -s * math.tan(angle)],
                             [-s * math.tan(angle), l * l / 3.0 + s * s]])

    mass_matrix = np.zeros((4, 4))
    mass_matrix[:2, :2] = block(gamma)
    mass_matrix[2:, 2:] = block(delta)
    wn = np.array([-math.tan(gamma), -(c - s), -(math.sin(lam) - math.tan(delta) * math.cos(lam)),
                   (l - s) * math.cos(lam)])
    wt = np.array([-1.0, 0.0, math.cos(lam) + math.tan(delta) * math.sin(lam),
                   (l - s) * math.sin(lam)])
    speeds = np.asarray(u, dtype=float)
    if wt @ speeds < 0:
        wt = -wt
    return ImpactProblem(mass_matrix=mass_matrix, wn=wn, wt=wt, u=speeds)
