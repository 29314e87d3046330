"""Random contact-space impact problems shared by the solver tests and benchmarks.

Draws cover every Table 1 case and every collision type: ``m_nt`` over its whole admissible
range ``|m_nt| < √(m_nn m_tt)``, friction from 0 to 2 (with exact zeros), restitution in
[0, 1] (with exact 0 and 1), tangential approach of both signs (with exact zeros).
"""

from __future__ import annotations

import numpy as np


def random_problems(count: int, seed: int, min_conditioning: float = 1e-3) -> dict:
    """``count`` problems as arrays ``mnn, mnt, mtt, vn, vt, mu, e``.

    ``min_conditioning`` bounds ``Δ/(m_nn m_tt) = 1 − ρ²`` from below, ρ being the
    correlation ``m_nt/√(m_nn m_tt)``: it keeps the problems away from singular ``M``,
    where any method's rounding error grows like 1/Δ.
    """
    rng = np.random.default_rng(seed)
    mnn = 10.0 ** rng.uniform(-1, 1, count)
    mtt = 10.0 ** rng.uniform(-1, 1, count)
    rho_max = np.sqrt(1.0 - min_conditioning)
    mnt = rng.uniform(-rho_max, rho_max, count) * np.sqrt(mnn * mtt)
    mnt[rng.random(count) < 0.03] = 0.0
    vn = -(10.0 ** rng.uniform(-1, 1, count))
    vt = rng.normal(0.0, 1.0, count) * 10.0 ** rng.uniform(-1.5, 1, count)
    vt[rng.random(count) < 0.05] = 0.0
    mu = rng.uniform(0.0, 2.0, count)
    mu[rng.random(count) < 0.05] = 0.0
    e = rng.uniform(0.0, 1.0, count)
    special = rng.random(count)
    e[special < 0.05] = 0.0
    e[special > 0.95] = 1.0
    return dict(mnn=mnn, mnt=mnt, mtt=mtt, vn=vn, vt=vt, mu=mu, e=e)


def row(problems: dict, index: int) -> dict:
    return {name: float(values[index]) for name, values in problems.items()}
