"""planar_impact: exact planar one-point impact with Coulomb friction (numpy only).

Djerassi, *Collision with friction; Part B: Poisson's and Stronge's hypotheses* (2009),
with Part A's Newton law, Stronge's exact energetic law and the velocity-level
Newton–Coulomb law of sequential-impulse engines; several contacts in ``simultaneous`` and
``multicontact`` (a two-phase Poisson law for m contacts).

>>> import planar_impact as pi
>>> problem = pi.builders.two_sleds(gamma=0.2, delta=0.85)
>>> result = problem.solve(mu=0.3, e=0.8, law="poisson")
>>> result.collision_type, round(result.vn_separation, 2)
(3, 0.82)
"""

from . import builders, errors, laws, multicontact, process, simultaneous
from .batch import BatchResult, solve_batch
from .builders import ImpactProblem, PlanarBody
from .contact_space import LAWS
from .errors import STATUS_MESSAGES, ImpactInputError
from .process import impulse_process, process_collision_type, sequential_impulses
from .solver import ImpactResult, solve

__all__ = [
    "LAWS",
    "STATUS_MESSAGES",
    "BatchResult",
    "ImpactInputError",
    "ImpactProblem",
    "ImpactResult",
    "PlanarBody",
    "builders",
    "errors",
    "impulse_process",
    "laws",
    "multicontact",
    "process",
    "process_collision_type",
    "sequential_impulses",
    "simultaneous",
    "solve",
    "solve_batch",
]

