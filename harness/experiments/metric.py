"""How far a prediction is from a measured impact.

``normalized_error`` is the metric of Fazeli et al. (ICRA 2017): the error of the predicted
velocity of the centre of mass after impact, relative to the measured one,
``‖v̂ − v‖ / ‖v‖`` over (v_x, v_y). On the published files it reproduces the paper's
median errors of the six models (0.43 to 0.57) against the post-impact speeds as published
(``docs/experiments.md``, 'The error metric').

``impulse_error`` is the cost the authors fit (μ, e) with: the distance between the contact
impulse (P_t, P_n) that best explains the measured change and the predicted one, in N·s.
"""

from __future__ import annotations

import numpy as np

OBJECTIVES = {
    "median-error": "median over drops of the normalized error of the centre-of-mass velocity "
                    "after impact (the paper's metric)",
    "impulse": "mean over drops of |P_measured - P_predicted| (N s), the contact impulse the "
               "paper's authors fit (mu, e) with",
}


def normalized_error(predicted, measured) -> np.ndarray:
    """``‖v̂ − v‖ / ‖v‖`` of the centre-of-mass velocity (first two speeds); arrays (..., 3)."""
    predicted, measured = np.asarray(predicted), np.asarray(measured)
    difference = predicted[..., :2] - measured[..., :2]
    return np.hypot(difference[..., 0], difference[..., 1]) / np.hypot(measured[..., 0],
                                                                         measured[..., 1])


def impulse_error(predicted_impulses, measured_impulses) -> np.ndarray:
    """``|P̂ − P|`` of contact impulses given as (..., 2) arrays (P_t, P_n)."""
    difference = np.asarray(predicted_impulses) - np.asarray(measured_impulses)
    return np.hypot(difference[..., 0], difference[..., 1])


def aggregate(objective: str, per_drop, axis=-1):
    """The objective's value from per-drop errors (NaN rows, unsolved, are left out)."""
    per_drop = np.asarray(per_drop)
    complete = not np.isnan(per_drop).any()  # numpy's nan-aware reductions are far slower
    if objective == "median-error":
        return np.median(per_drop, axis=axis) if complete else np.nanmedian(per_drop, axis=axis)
    if objective == "impulse":
        return np.mean(per_drop, axis=axis) if complete else np.nanmean(per_drop, axis=axis)
    raise ValueError(f"objective: unknown {objective!r}; allowed: {', '.join(OBJECTIVES)}")
