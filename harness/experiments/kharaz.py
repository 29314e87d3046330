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

``MEASURED`` holds the paper's points as others digitised them, cited as such (no one here
has read them off a copy of the paper). They are the arrays ``IMPT_ANGLE`` / ``EXP_COEFF``,
``EXP_ANGLE`` and ``EXP_OMEGA`` of ``tests/dem/DEM05/write_usr0.f`` of the MFIX DEM05
verification test ("DEM05: Oblique particle collision"), in the GitHub copy
``CurtinIDS/mfix`` at commit aa5da900933766e158dd4188220765689855bde7, whose comments say
they are "Data taken from Figure 6 [tangential restitution], 7(b) [rebound angle], 8
[angular velocity] of Di Renzo and Di Maio (2004)" (Chem. Eng. Sci. 59:525-541), which plot
Kharaz et al.'s measurements; NETL's V&V manual
(https://mfix.netl.doe.gov/doc/vvuq-manual/main/html/dem/dem-05.html) says the test
"utilizes the experimental data of Kharaz, Gorham, and Salman". ``CROSS_CHECK`` is a second
digitisation, the lists ``*_exp`` of
``examples/dem/3d-oblique-wall-impact/oblique_wall_impact_postprocessing.py`` in
``chaos-polymtl/lethe`` at commit 255b519263fbb22f758d40763a12290296d53200, commented
"Experimental data from A.H. Kharaz, D.A. Gorham, and A.D. Salman" (which figure it read is
not stated). The two agree to a fraction of a degree and of a percent (a test checks it):
that bounds the reading of the figures and catches a transcription slip, not the
measurements' scatter, which neither source gives. The points are shown beside the curves,
never used to fit.
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
#: Where ``MEASURED`` and ``CROSS_CHECK`` were read (see the module's docstring).
SOURCE = ("MFIX DEM05 verification test, tests/dem/DEM05/write_usr0.f (github.com/"
          "CurtinIDS/mfix @ aa5da90): Kharaz et al. 2001's measurements digitised from "
          "Di Renzo & Di Maio 2004, Figs. 6, 7(b), 8")
CROSS_CHECK_SOURCE = ("Lethe, examples/dem/3d-oblique-wall-impact/"
                      "oblique_wall_impact_postprocessing.py (github.com/chaos-polymtl/lethe "
                      "@ 255b519)")
#: The three quantities the paper plots against incidence, in the order of its figures here.
QUANTITIES = ("tangential_restitution", "rebound_deg", "spin")


@dataclass(frozen=True)
class Digitised:
    """One quantity's points: incidence (degrees from the normal) and value, as the source
    tabulates them (its own rounding)."""

    quantity: str
    incidence_deg: tuple[float, ...]
    values: tuple[float, ...]


#: From SOURCE, column by column as tabulated there.
MEASURED = {
    "tangential_restitution": Digitised(
        "tangential_restitution",
        (2.0275, 3.9282, 9.6304, 20.0845, 30.2218, 39.3031, 49.5459, 59.8416),
        (0.7938, 0.7450, 0.6728, 0.5964, 0.6883, 0.7719, 0.8469, 0.9019)),
    "rebound_deg": Digitised(
        "rebound_deg",
        (0.2397, 2.2945, 4.2922, 9.9429, 20.5594, 30.3767, 39.6233, 49.7831, 60.0571),
        (0.1194, 1.7630, 2.9577, 6.6917, 12.3645, 21.7809, 32.5455, 45.1051, 57.3652)),
    "spin": Digitised(
        "spin",
        (6.0025, 10.9840, 21.1931, 31.0947, 39.0283, 50.2214, 60.2460),
        (135.5703, 264.5493, 577.0096, 612.6481, 595.4843, 452.9444, 381.3185)),
}
#: From CROSS_CHECK_SOURCE (the same figures read by other hands), as tabulated there.
CROSS_CHECK = {
    "tangential_restitution": Digitised(
        "tangential_restitution",
        (1.84, 3.703, 9.496, 20.012, 30.127, 39.382, 49.694, 60.02),
        (0.79344, 0.74533, 0.67257, 0.59691, 0.68756, 0.77148, 0.84761, 0.90142)),
    "rebound_deg": Digitised(
        "rebound_deg",
        (0.016, 2.15, 4.096, 9.826, 20.567, 30.29, 39.535, 49.747, 60.208),
        (0.074, 1.733, 2.962, 6.518, 12.208, 21.67, 32.613, 45.125, 57.474)),
    "spin": Digitised(
        "spin",
        (6.143, 10.991, 21.251, 31.157, 39.143, 50.348, 60.328),
        (136.18, 265.69, 577.65, 612.88, 595.49, 453.21, 382.09)),
}


def digitisation_gaps() -> dict[str, tuple[float, float]]:
    """Per quantity, the largest differences between ``MEASURED`` and ``CROSS_CHECK``, point
    by point: (incidence in degrees, value in the quantity's unit)."""
    gaps = {}
    for quantity in QUANTITIES:
        first, second = MEASURED[quantity], CROSS_CHECK[quantity]
        gaps[quantity] = (
            float(np.max(np.abs(np.subtract(first.incidence_deg, second.incidence_deg)))),
            float(np.max(np.abs(np.subtract(first.values, second.values)))))
    return gaps


def impacts(incidence_deg) -> MeasuredImpacts:
    """The disk at ``SPEED`` and each incidence (degrees from the normal), no spin; the
    speeds after are NaN (the sources give the quantities of ``MEASURED``, not the speeds)."""
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
