"""Oblique impacts of a sphere on a flat anvil (Kharaz, Gorham & Salman 2001), in the plane.

A 5 mm alumina sphere at 3.9 m/s on a thick glass anvil, incidence 5 to 85 degrees from the
normal. In the plane the sphere is a disk with I = 2/5 m r² (exact for a sphere's motion in
a plane through its centre). The contact is the disk's lowest point: ``w_n = (0, 1, 0)``,
``w_t = (1, 0, r)`` for speeds (v_x, v_y, ω), ω anticlockwise.

The three curves the paper plots against incidence, as defined here (centre of mass):
tangential restitution ``e_t = v_x' / v_x`` (v_x the tangential velocity of the centre),
rebound angle ``atan(v_x' / v_y')`` in degrees from the normal, and the forward spin
``−ω'`` in rad/s (positive in the sense of rolling forward: a clockwise ω for v_x > 0).

Here ``m_nt = 0``: every law of ``planar_impact`` gives the same answer (the laws differ
only through the coupling of normal and tangential impulse), so these curves test the
rigid-body picture and μ, e, not the choice of law; engines may differ from it.

``POINTS`` are values recalled from the paper's published figures, NOT digitised from a
copy; each carries a wide uncertainty and ``VERIFIED`` stays False until someone checks
them against the paper. They are shown beside the laws' curves, never used to fit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import planar_impact as pi

from .records import MeasuredImpacts

RADIUS = 2.5e-3  # m (5 mm diameter)
MASS = 1.0  # kg: every curve here is independent of the mass
SPEED = 3.9  # m/s
#: The paper's values for alumina on glass: friction from the sliding regime, normal
#: restitution (nearly constant with incidence).
MU = 0.092
E = 0.98
VERIFIED = False


@dataclass(frozen=True)
class Point:
    incidence_deg: float
    tangential_restitution: float
    rebound_deg: float
    spin: float  # forward spin after impact, rad/s


#: (incidence°, e_t, rebound°, ω rad/s), recalled from the paper's figures (see above).
POINTS = (
    Point(10.0, 0.62, 6.5, 250.0),
    Point(20.0, 0.66, 14.0, 450.0),
    Point(30.0, 0.71, 23.0, 580.0),
    Point(45.0, 0.82, 40.0, 500.0),
    Point(60.0, 0.89, 57.5, 355.0),
    Point(80.0, 0.97, 80.0, 125.0),
)
#: Half-widths of the recalled points' uncertainty (e_t, rebound°, spin rad/s).
UNCERTAINTY = (0.08, 4.0, 80.0)


def impacts(incidence_deg) -> MeasuredImpacts:
    """The disk at ``SPEED`` and each incidence (degrees from the normal), no spin; the
    speeds after are NaN (there is no per-angle measurement record, only ``POINTS``)."""
    angles = np.radians(np.atleast_1d(np.asarray(incidence_deg, dtype=float)))
    rows = angles.size
    before = np.stack([SPEED * np.sin(angles), -SPEED * np.cos(angles), np.zeros(rows)], axis=1)
    inertia = 0.4 * MASS * RADIUS**2
    return MeasuredImpacts(
        "kharaz2001", np.diag([MASS, MASS, inertia]), before, np.full((rows, 3), np.nan),
        np.tile([0.0, 1.0, 0.0], (rows, 1)), np.tile([1.0, 0.0, RADIUS], (rows, 1)),
        np.arange(rows))


@dataclass(frozen=True)
class Curves:
    law: str
    incidence_deg: np.ndarray
    tangential_restitution: np.ndarray
    rebound_deg: np.ndarray
    spin: np.ndarray
    status: np.ndarray


def curves(law: str, incidence_deg, mu: float = MU, e: float = E) -> Curves:
    """The three curves of ``law`` at the paper's μ and e (defaults)."""
    record = impacts(incidence_deg)
    space = record.contact_space()
    result = pi.solve_batch(space.mnn, space.mnt, space.mtt, space.vn, space.vt, mu, e,
                            law=law, delta=space.delta)
    after = record.speeds_from_impulses(result.normal_impulse, result.tangential_impulse)
    return Curves(law, np.atleast_1d(np.asarray(incidence_deg, dtype=float)),
                  after[:, 0] / record.speeds_before[:, 0],
                  np.degrees(np.arctan2(after[:, 0], after[:, 1])), -after[:, 2], result.status)


def sticking_limit_deg(mu: float = MU, e: float = E) -> float:
    """Incidence below which the rigid disk ends its impact rolling (Poisson's law):
    tan θ = 7/2 μ (1 + e) for I = 2/5 m r² (the slip, reduced by 7/2 μ dP_n per unit normal
    impulse, vanishes before the impulse (1 + e) m v_n is complete)."""
    return float(np.degrees(np.arctan(3.5 * mu * (1 + e))))
