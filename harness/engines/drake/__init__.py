"""Drake adapter (pydrake 1.51.1, the newest Drake with Python 3.11 wheels).

Drake's point contact is compliant: a Hunt–Crossley force ``f = k·x·(1 + d·ẋ)`` (``x`` the
penetration, ``ẋ`` its rate) that cannot pull, with regularised Coulomb friction, stepped by
a discrete solver (SAP's ``lagged`` approximation by default, or TAMSI). It has no
restitution coefficient: the bounce follows from ``d`` and the approach speed.

Presets (docs/engines.md, 'Drake'): ``defaults`` is ``MultibodyPlantConfig()``'s (1 ms
steps, SAP lagged, stiffness and dissipation estimated from a 1 mm penetration allowance;
``e`` is not used: a 1 m/s drop leaves at about 0.02 m/s). ``accurate`` sets the stiffness
from the contact's normal effective mass so that an undamped contact lasts 500 steps of
1 µs, and ``d = a/v`` with ``a`` from ``e`` through the discrete contact's own map
(:func:`discrete_dissipation`), on TAMSI (measured: SAP's bounces at 2.8x the CPU, and SAP
drops small normal impulses beside a large tangential speed). A central drop then bounces
at ``e·v`` for ``e <= exp(-π²/1000) = 0.990`` and within 1% above.

Planar motion: one ``PlanarJoint`` per body to the world (``q = (x, y, θ)``, rotation about
+z: the scene's signs); disk -> sphere, rod -> capsule along x, box -> box, polygon ->
convex prism, ellipse -> ellipsoid; the ground a half-space with normal +y; point contact.

- :mod:`.adapter` -- :class:`DrakeEngine`, the contract's hooks (the per-run contact
  values, the step and its contact read-out);
- :mod:`.model` -- a scene as a Drake diagram (plant, scene graph, simulator), and the
  contact properties written into its context;
- :mod:`.restitution` -- the maps between Hunt–Crossley's ``d·v`` and restitution, continuous
  and discrete;
- :mod:`.presets` -- the settings, their docs and the two presets.

The rest of the harness reaches the engine through the registry (:mod:`harness.engines`).
"""

from __future__ import annotations

from harness.engines.drake.adapter import ENGINE_CLASS, DrakeEngine
from harness.engines.drake.presets import PRESETS, SETTING_DOCS
from harness.engines.drake.restitution import (
    MIN_RESTITUTION,
    discrete_dissipation,
    discrete_restitution,
    dissipation_for_restitution,
    restitution_of_dissipation,
)

__all__ = [
    "ENGINE_CLASS",
    "MIN_RESTITUTION",
    "PRESETS",
    "SETTING_DOCS",
    "DrakeEngine",
    "discrete_dissipation",
    "discrete_restitution",
    "dissipation_for_restitution",
    "restitution_of_dissipation",
]
