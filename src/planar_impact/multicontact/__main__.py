"""``python -m planar_impact.multicontact [problems] [seed] [plain]``: the two-phase law on
random problems, per family (:func:`~planar_impact.multicontact.measure.measure`);
``python -m planar_impact.multicontact admissible [draws] [seed]``: every m-contact
reference's solutions on broad flat landings checked for admissibility
(:func:`~planar_impact.multicontact.families.scan`)."""

from __future__ import annotations

import sys

from .families import scan
from .measure import measure

if __name__ == "__main__":  # python -m planar_impact.multicontact [problems] [seed] [plain]
    if sys.argv[1:2] == ["admissible"]:
        draws, seed = ([int(a) for a in sys.argv[2:4]] + [1000, 0][len(sys.argv[2:4]):])[:2]
        print(f"{draws} flat landings (boxes, rods, polygons), seed {seed}")
        for name, counts in scan(draws, seed).items():
            print(f"{name}: {counts}")
        sys.exit(0)
    arguments = [int(a) for a in sys.argv[1:3]]
    plain = sys.argv[3:4] == ["plain"]  # one velocity-level problem per phase
    for family, counts in measure(*arguments, follow_slip=not plain).items():
        print(f"{family}: {counts}")
