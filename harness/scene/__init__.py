"""The impact to simulate: what every source (analytic laws and engines) is given.

* :mod:`harness.scene.model` -- shapes, bodies and the :class:`Scene` (pose at first touch,
  velocities, the pair's ``e`` and ``μ``);
* :mod:`harness.scene.geometry` -- the contact of a scene and its contact terms, the bridge
  from a scene to a ``planar_impact.ImpactProblem``;
* :mod:`harness.scene.features` -- a shape's point features (corners, end caps);
* :mod:`harness.scene.random_problems` -- seeded random contact-space problems for the
  solver's tests, benchmarks and stress runs.
"""

from harness.scene.model import Body, Box, Contact, Disk, Polygon, Rod, Scene

__all__ = ["Body", "Box", "Contact", "Disk", "Polygon", "Rod", "Scene"]
