"""Hand-built reference scenes with known contacts, shared by the engine tests and benchmarks,
and their newton-lcp answer (the law sequential-impulse engines solve)."""

from __future__ import annotations

import math

from harness.scene.geometry import ground_contact, impact_problem, place_stand_in
from harness.scene.model import Body, Box, Disk, Ellipse, Rod, Scene


def reference_scenes() -> dict[str, tuple[Scene, tuple[float, float], tuple[float, float]]]:
    """Hand-built scenes: ``name -> (scene, contact point, normal from A into B)``.

    * ``disk``: disk r 0.1 m, 1 kg, v (1, -1) m/s, no spin (sticks under newton-lcp).
    * ``disk-spin``: the same with ω = 5 rad/s (slides).
    * ``rod-45``: the rod of the engine notes (docs/engines.md), 1 m capsule (cap radius
      5 mm), 1 kg, inertia 1/12 kg m², 45°, v (0.5, -1) m/s, e 0.5, μ 0.3 -> newton-lcp
      (0.7202, -0.2660, -2.1666).
    * ``box-corner``: box 0.4 × 0.2 m, 1 kg, 30°, lowest corner on the ground, v (0.3, -1),
      ω 0.5 rad/s.
    * ``two-disks``: disks r 0.1 m (1 kg) and 0.15 m (2 kg) touching along 30°, with
      oblique velocities and spin.
    * ``ellipse``: the Fazeli et al. (2017) ellipse (36.4 g, semi-axes 35 and 25 mm) at 30°,
      lowest point on the ground, v (0.3, -2.5) m/s, ω 5 rad/s (MuJoCo's ellipsoid, a
      placed 8-gon elsewhere).
    All with e = 0.5, μ = 0.3.
    """
    e, mu = 0.5, 0.3
    scenes = {}
    radius = 0.1
    for name, spin in (("disk", 0.0), ("disk-spin", 5.0)):
        body = Body("disk", Disk(radius), 1.0, (0.0, radius), 0.0, (1.0, -1.0), spin)
        scenes[name] = (Scene((body,), e, mu, ground=True, name=name), (0.0, 0.0), (0.0, 1.0))

    angle, length, cap = math.radians(45.0), 1.0, 0.005
    cap_x, cap_y = -length / 2.0 * math.cos(angle), -length / 2.0 * math.sin(angle)
    rod = Body("rod", Rod(length, cap), 1.0, (0.0, -cap_y + cap), angle, (0.5, -1.0), 0.0,
               inertia=1.0 / 12.0)
    scenes["rod-45"] = (Scene((rod,), e, mu, ground=True, name="rod-45"), (cap_x, 0.0), (0.0, 1.0))

    angle = math.radians(30.0)
    box = Box(0.4, 0.2)
    c, s = math.cos(angle), math.sin(angle)
    corners = [(c * x - s * y, s * x + c * y) for x, y in box.vertices().tolist()]
    low = min(corners, key=lambda point: point[1])
    body = Body("box", box, 1.0, (0.0, -low[1]), angle, (0.3, -1.0), 0.5)
    scenes["box-corner"] = (Scene((body,), e, mu, ground=True, name="box-corner"), (low[0], 0.0),
                            (0.0, 1.0))

    r_a, r_b, phi = 0.1, 0.15, math.radians(30.0)
    normal = (math.cos(phi), math.sin(phi))
    a = Body("a", Disk(r_a), 1.0, (0.0, 0.0), 0.0, (1.0, 0.2), 0.0)
    b = Body("b", Disk(r_b), 2.0, ((r_a + r_b) * normal[0], (r_a + r_b) * normal[1]), 0.3,
             (-0.5, 0.0), 1.0)
    contact = (r_a * normal[0], r_a * normal[1])
    scenes["two-disks"] = (Scene((a, b), e, mu, ground=False, name="two-disks"), contact, normal)

    ellipse = Body("ellipse", Ellipse(0.035, 0.025), 0.0364, (0.0, 0.0), math.radians(30.0),
                   (0.3, -2.5), 5.0)
    lowest = ground_contact(ellipse).gap
    ellipse = place_stand_in(ellipse.moved(position=(0.0, -lowest)))
    point = ground_contact(ellipse).point
    scenes["ellipse"] = (Scene((ellipse,), e, mu, ground=True, name="ellipse"),
                         (float(point[0]), 0.0), (0.0, 1.0))
    return scenes


def newton_lcp_velocities(scene: Scene, contact, normal):
    """``planar_impact``'s ``newton-lcp`` post-impact velocities for a reference scene."""
    problem = impact_problem(scene, contact, normal)
    return problem.solve(mu=scene.friction, e=scene.restitution, law="newton-lcp")

