"""Errors and batch status codes of the solver."""

from __future__ import annotations


class ImpactInputError(ValueError):
    """An impact problem the solver cannot accept, or one with no admissible answer.

    The message names the field, the value and what is allowed.
    """


# Status codes of :func:`planar_impact.solve_batch`: 0 is solved; every other code marks a
# row whose outputs are NaN. The scalar :func:`planar_impact.solve` raises
# ImpactInputError with the message below instead.
SOLVED = 0
NON_FINITE = 1
NOT_POSITIVE_DEFINITE = 2
NEGATIVE_FRICTION = 3
RESTITUTION_OUT_OF_RANGE = 4
NO_APPROACH = 5
PAINLEVE_JAM = 6
REVERSE_SLIDING_Q_NONPOSITIVE = 7
NO_CONSISTENT_SOLUTION = 8
OUTPUT_OVERFLOW = 9

STATUS_MESSAGES: dict[int, str] = {
    SOLVED: "solved",
    NON_FINITE: "an input is NaN or infinite (all inputs must be finite)",
    NOT_POSITIVE_DEFINITE: (
        "the inverse-inertia terms are not positive definite "
        "(need m_nn > 0, m_tt > 0 and Δ = m_nn·m_tt − m_nt² > 0)"
    ),
    NEGATIVE_FRICTION: "friction coefficient μ < 0 (allowed: μ ≥ 0)",
    RESTITUTION_OUT_OF_RANGE: "restitution e outside [0, 1]",
    NO_APPROACH: "no approach: v_n^A ≥ 0 (allowed: v_n^A < 0, the bodies must be closing)",
    PAINLEVE_JAM: (
        "Painlevé-type jam: h = m_nn − μ·m_nt ≤ 0 and g = μ·m_tt − m_nt ≤ 0, "
        "no admissible continuation of the impulse process"
    ),
    REVERSE_SLIDING_Q_NONPOSITIVE: (
        "reverse sliding with q = m_nn + μ·m_nt ≤ 0: the normal velocity never recovers"
    ),
    NO_CONSISTENT_SOLUTION: (
        "the law has no consistent solution for this row (no real e_i for the paper's "
        "Stronge mapping, or no consistent stick/slide mode for newton-lcp)"
    ),
    OUTPUT_OVERFLOW: (
        "an output exceeds the float64 range (inputs too large in magnitude: the energy change, "
        "of order v²/m, passes 1.8e308); rescale the units"
    ),
}
