"""The impact to simulate: what every source (analytic laws and engines) is given.

* :mod:`harness.scene.model` -- shapes, bodies and the :class:`Scene` (pose at first touch,
  velocities, the pair's ``e`` and ``μ``);
* :mod:`harness.scene.geometry` -- the contact of a scene and its contact terms, the bridge
  from a scene to a ``planar_impact.ImpactProblem``;
* :mod:`harness.scene.ellipse` -- the ellipse's lowest point and contact Jacobian in closed
  form, and the error of a polygon in its place;
* :mod:`harness.scene.features` -- a shape's point features (corners, end caps), which one
  a point is at, and its extent;
* :mod:`harness.scene.random_problems` -- seeded random contact-space problems for the
  solver's tests, benchmarks and stress runs.
"""

from harness.scene.model import Body, Box, Contact, Disk, Ellipse, Polygon, Rod, Scene

__all__ = ["Body", "Box", "Contact", "Disk", "Ellipse", "Polygon", "Rod", "Scene"]
