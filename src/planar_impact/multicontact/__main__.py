"""``python -m planar_impact.multicontact [problems] [seed] [plain]``: the two-phase law on
random problems, per family (:func:`~planar_impact.multicontact.measure.measure`)."""

from __future__ import annotations

import sys

from .measure import measure

if __name__ == "__main__":  # python -m planar_impact.multicontact [problems] [seed] [plain]
    arguments = [int(a) for a in sys.argv[1:3]]
    plain = sys.argv[3:4] == ["plain"]  # one velocity-level problem per phase
    for family, counts in measure(*arguments, follow_slip=not plain).items():
        print(f"{family}: {counts}")
