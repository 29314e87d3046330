"""What each law of ``planar_impact`` predicts for measured impacts (``solve_batch`` on
the impacts' contact-space problems)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import planar_impact as pi

from .records import ContactSpace, MeasuredImpacts


@dataclass(frozen=True)
class LawPrediction:
    """A law's answer for every (μ, e) given and every impact: arrays (..., N)."""

    law: str
    status: np.ndarray  # 0 where solved (planar_impact.STATUS_MESSAGES)
    normal_impulse: np.ndarray
    tangential_impulse: np.ndarray
    collision_type: np.ndarray
    speeds_after: np.ndarray  # (..., N, 3)

    def impulses(self) -> np.ndarray:
        """(..., N, 2): (P_t, P_n), the order of ``MeasuredImpacts.measured_impulses``."""
        return np.stack([self.tangential_impulse, self.normal_impulse], axis=-1)


def predict(impacts: MeasuredImpacts, law: str, mu, e,
            space: ContactSpace | None = None) -> LawPrediction:
    """``law`` with friction ``mu`` and restitution ``e`` (scalars or arrays broadcasting
    against (N,), e.g. shape (K, 1)) on every impact."""
    space = impacts.contact_space() if space is None else space
    result = pi.solve_batch(space.mnn, space.mnt, space.mtt, space.vn, space.vt, mu, e,
                            law=law, delta=space.delta)
    speeds = impacts.speeds_from_impulses(result.normal_impulse, result.tangential_impulse)
    return LawPrediction(law, result.status, result.normal_impulse, result.tangential_impulse,
                         result.collision_type, speeds)
