"""Measured impacts as the laws see them: generalized speeds before and after, the contact's
partial velocities (Jacobian rows) and the mass matrix.

One record holds N impacts of one body on the ground (arrays with N rows). The contact
space of row i is the (A20) problem of ``planar_impact.solve_batch``: ``m_nn = w_n M⁻¹ w_n``,
``m_nt = w_n M⁻¹ w_t``, ``m_tt = w_t M⁻¹ w_t``, ``v_n = w_n·u``, ``v_t = w_t·u``; a law's
impulses ``(P_n, P_t)`` give the speeds after as ``u + M⁻¹ (w_n P_n + w_t P_t)`` (A16).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ContactSpace:
    """The (A20) terms and approach velocities of every row (arrays of N)."""

    mnn: np.ndarray
    mnt: np.ndarray
    mtt: np.ndarray
    delta: np.ndarray  # Δ = m_nn m_tt − m_nt², formed without cancellation
    vn: np.ndarray
    vt: np.ndarray


@dataclass(frozen=True)
class MeasuredImpacts:
    """N measured single impacts of one rigid body (3 generalized speeds: v_x, v_y, ω)."""

    source: str
    mass_matrix: np.ndarray  # (3, 3)
    speeds_before: np.ndarray  # (N, 3)
    speeds_after: np.ndarray  # (N, 3)
    wn: np.ndarray  # (N, 3): partial velocity of the contact point along the normal
    wt: np.ndarray  # (N, 3): ... along the tangent
    drop_ids: np.ndarray  # (N,) the source's own numbering of the impacts

    def __post_init__(self):
        rows = self.speeds_before.shape[0]
        for name in ("speeds_before", "speeds_after", "wn", "wt"):
            if getattr(self, name).shape != (rows, 3):
                raise ValueError(f"{self.source}: {name} has shape "
                                 f"{getattr(self, name).shape}, expected ({rows}, 3)")
        if self.drop_ids.shape != (rows,):
            raise ValueError(f"{self.source}: drop_ids has shape {self.drop_ids.shape}")

    def __len__(self) -> int:
        return self.speeds_before.shape[0]

    def subset(self, rows) -> MeasuredImpacts:
        rows = np.asarray(rows)
        return MeasuredImpacts(self.source, self.mass_matrix, self.speeds_before[rows],
                               self.speeds_after[rows], self.wn[rows], self.wt[rows],
                               self.drop_ids[rows])

    def contact_space(self) -> ContactSpace:
        # M⁻¹ = K Kᵀ; with a = Kᵀ w_n, b = Kᵀ w_t the terms are dot products and, by
        # Lagrange's identity, Δ = |a × b|², a sum of squares (no cancellation).
        factor = np.linalg.cholesky(np.linalg.inv(self.mass_matrix))
        a, b = self.wn @ factor, self.wt @ factor
        return ContactSpace(
            mnn=np.einsum("ij,ij->i", a, a), mnt=np.einsum("ij,ij->i", a, b),
            mtt=np.einsum("ij,ij->i", b, b), delta=np.sum(np.cross(a, b) ** 2, axis=1),
            vn=np.einsum("ij,ij->i", self.wn, self.speeds_before),
            vt=np.einsum("ij,ij->i", self.wt, self.speeds_before),
        )

    def speeds_from_impulses(self, normal, tangential) -> np.ndarray:
        """Speeds after an impact with contact impulses ``normal``, ``tangential`` (arrays
        broadcasting against N rows, e.g. (..., N)): shape (..., N, 3)."""
        normal, tangential = np.asarray(normal)[..., None], np.asarray(tangential)[..., None]
        inverse = np.linalg.inv(self.mass_matrix)
        return self.speeds_before + (normal * self.wn + tangential * self.wt) @ inverse.T

    def measured_impulses(self) -> np.ndarray:
        """The contact impulse (P_t, P_n) that best explains each measured change of speed:
        ``(J M⁻¹ Jᵀ)⁻¹ J Δu`` with ``J = [w_t; w_n]`` (N, 2), as the paper's authors form it
        (the change need not lie in the span the contact can produce)."""
        jacobian = np.stack([self.wt, self.wn], axis=1)  # (N, 2, 3)
        inverse = np.linalg.inv(self.mass_matrix)
        contact_mass = np.linalg.inv(jacobian @ inverse @ np.swapaxes(jacobian, 1, 2))
        change = self.speeds_after - self.speeds_before
        return np.einsum("nij,nj->ni", contact_mass, np.einsum("nij,nj->ni", jacobian, change))
