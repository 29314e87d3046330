"""Every sample through every law at once: contact terms as arrays, one ``solve_batch`` per law.

For a sample with generalised speeds ``u`` (``(v_x, v_y, ω)`` per body), diagonal mass matrix
``M`` and partial velocities ``w_n``, ``w_t`` of its contact (docs/theory.md, 'Setting and
conventions'), the inverse-inertia terms are (A20) ``m_nn = w_nᵀM⁻¹w_n``,
``m_nt = w_nᵀM⁻¹w_t``, ``m_tt = w_tᵀM⁻¹w_t`` and the approach velocities ``v_n = w_n·u``,
``v_t = w_t·u``. A law's impulses ``(I_n, I_t)`` give the post-impact speeds through (A16):
``u_after = u + M⁻¹(w_n I_n + w_t I_t)``.

Ground samples have 3 speeds, two-body samples 6; the arrays are padded to 6 columns with
zero speeds and partial velocities (and unit masses), which add nothing to any sum.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import planar_impact
from harness.scene import geometry
from planar_impact import builders

WIDTH = 6  # columns of the padded speed arrays (two bodies × (v_x, v_y, ω))


@dataclass(frozen=True)
class ContactTerms:
    """Per-sample arrays (``n`` rows): speeds, masses and the contact's terms."""

    dofs: np.ndarray  # (n,) 3 or 6: the sample's number of speeds
    mass: np.ndarray  # (n, 6) the diagonal of M (kg, kg, kg m² per body); 1 where padded
    u: np.ndarray  # (n, 6) speeds before the impact
    wn: np.ndarray  # (n, 6)
    wt: np.ndarray  # (n, 6)
    mnn: np.ndarray
    mnt: np.ndarray
    mtt: np.ndarray
    vn: np.ndarray  # m/s, < 0
    vt: np.ndarray  # m/s, in the harness's t = (n_y, −n_x)
    mu: np.ndarray
    e: np.ndarray
    free_bodies: np.ndarray  # (n,) bool: two free bodies (departures in the centre-of-mass frame)
    problems: tuple  # per sample, its planar_impact ImpactProblem (the verdicts' input)

    def __len__(self) -> int:
        return len(self.dofs)

    def mass_matrix(self, row: int) -> np.ndarray:
        dofs = int(self.dofs[row])
        return np.diag(self.mass[row, :dofs])


def contact_terms(samples) -> ContactTerms:
    """The arrays of :class:`ContactTerms` for a sequence of :class:`Sample`.

    The rows' impact problems are :func:`harness.scene.geometry.impact_problem`'s (the
    builders' ``M``, ``w_n``, ``w_t``, ``u``), formed for every row at once: the same
    operations on the same floats, element by element (tests/survey/test_laws_and_statistics.py
    compares them bit for bit), for a quarter of the builders' cost per row.
    """
    count = len(samples)
    free_bodies = np.zeros(count, dtype=bool)
    # Per row: contact point and normal, then (m, I, x, y, v_x, v_y, ω) of the body in
    # columns 0-2 and of the one in columns 3-5 (zeros for a ground row's absent body).
    points, normals, bodies = np.empty((count, 2)), np.empty((count, 2)), np.zeros((count, 14))
    mu, e = np.empty(count), np.empty(count)
    for row, sample in enumerate(samples):
        scene, contact = sample.scene, sample.contact
        free_bodies[row] = not scene.ground
        points[row], normals[row] = contact.point, contact.normal
        values = []
        for body in scene.bodies:
            values += [body.mass, body.moment_of_inertia, *body.position, *body.velocity,
                       body.angular_velocity]
        bodies[row, :len(values)] = values
        mu[row], e[row] = scene.friction, scene.restitution
    lengths = np.hypot(normals[:, 0], normals[:, 1])
    if not (np.all(lengths > 0) and np.all(np.isfinite(lengths))):
        bad = int(np.flatnonzero(~((lengths > 0) & np.isfinite(lengths)))[0])
        geometry.impact_problem(samples[bad].scene, points[bad], normals[bad])  # its error
    normal = normals / lengths[:, None]  # builders._unit
    tangent = np.stack([normal[:, 1], -normal[:, 0]], axis=1)
    dofs = np.where(free_bodies, 2 * 3, 3)
    mass = np.ones((count, WIDTH))
    u, wn, wt = (np.zeros((count, WIDTH)) for _ in range(3))
    for first, body in ((0, bodies[:, :7]), (3, bodies[:, 7:])):
        # PlanarBody.partial_velocities: (d_x, d_y, r_x d_y − r_y d_x), A's negated (v^B − v^A)
        rows = slice(None) if first == 0 else free_bodies
        sign = np.where(free_bodies, -1.0, 1.0)[:, None] if first == 0 else 1.0
        r_x, r_y = points[:, 0] - body[:, 2], points[:, 1] - body[:, 3]
        for out, direction in ((wn, normal), (wt, tangent)):
            d_x, d_y = direction[:, 0], direction[:, 1]
            partial = np.stack([d_x, d_y, r_x * d_y - r_y * d_x], axis=1)
            out[rows, first:first + 3] = (sign * partial)[rows]
        mass[rows, first:first + 3] = body[rows][:, [0, 0, 1]]
        u[rows, first:first + 3] = body[rows][:, 4:7]
    problems = tuple(
        builders.ImpactProblem(mass_matrix=np.diag(mass[row, :size]), wn=wn[row, :size].copy(),
                               wt=wt[row, :size].copy(), u=u[row, :size].copy())
        for row, size in enumerate(dofs.tolist()))
    # (A20) with diagonal M: M⁻¹ w is w divided by the diagonal.
    mnn = np.sum(wn * wn / mass, axis=1)
    mnt = np.sum(wn * wt / mass, axis=1)
    mtt = np.sum(wt * wt / mass, axis=1)
    vn, vt = np.sum(wn * u, axis=1), np.sum(wt * u, axis=1)
    return ContactTerms(dofs.astype(np.int64), mass, u, wn, wt, mnn, mnt, mtt, vn, vt, mu, e,
                        free_bodies, problems)


@dataclass(frozen=True)
class LawResults:
    """One law's answer for every sample: the batch result and the speeds after (A16)."""

    law: str
    batch: planar_impact.BatchResult
    u_after: np.ndarray  # (n, 6); NaN where batch.status != 0


def solve_laws(terms: ContactTerms, laws=planar_impact.LAWS) -> dict[str, LawResults]:
    """``{law: LawResults}``: one :func:`planar_impact.solve_batch` call per law."""
    results = {}
    for law in laws:
        batch = planar_impact.solve_batch(terms.mnn, terms.mnt, terms.mtt, terms.vn, terms.vt,
                                          terms.mu, terms.e, law=law)
        impulse = (terms.wn * batch.normal_impulse[:, None]
                   + terms.wt * batch.tangential_impulse[:, None])
        results[law] = LawResults(law, batch, terms.u + impulse / terms.mass)  # (A16)
    return results


def routh_coordinates(terms: ContactTerms) -> dict[str, np.ndarray]:
    """Where each sample lies on Routh's map: ``alpha`` (A34), ``g``, ``h`` (A35), ``r_m``
    (A36) and ``alpha_over_rm``, in the theory's tangent (``v_t^A ≥ 0``).

    ``alpha_over_rm`` is NaN outside Table 1's cases 1–3 (``g > 0`` and ``h > 0``), where the
    type does not depend on ``α / r_m``.
    """
    # The theory's t makes v_t^A >= 0 (and m_nt >= 0 when v_t^A = 0): t -> -t flips m_nt.
    sign = np.where((terms.vt < 0) | ((terms.vt == 0) & (terms.mnt < 0)), -1.0, 1.0)
    mnt = sign * terms.mnt
    alpha = np.abs(terms.vt) / np.abs(terms.vn)  # (A34)
    g = terms.mu * terms.mtt - mnt  # (A35)
    h = terms.mnn - terms.mu * mnt
    with np.errstate(divide="ignore", invalid="ignore"):
        r_m = g / h  # (A36)
        ratio = np.where((g > 0) & (h > 0), alpha / r_m, np.nan)
    return {"alpha": alpha, "g": g, "h": h, "r_m": r_m, "alpha_over_rm": ratio}
