"""``python -m planar_impact.simultaneous [problems] [seed]``: how many coherent solutions
each law has on random two-contact problems, per family and reading
(:func:`~planar_impact.simultaneous.random_systems.coherent_count_distribution`)."""

from __future__ import annotations

import sys

from .random_systems import coherent_count_distribution
from .type_map import COUPLINGS

if __name__ == "__main__":  # python -m planar_impact.simultaneous [problems] [seed]
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    for family in ("generic", "body"):
        for coupling in COUPLINGS:
            table = coherent_count_distribution(count, seed, family, coupling)
            print(f"{family} coupling={coupling}: {table}")
