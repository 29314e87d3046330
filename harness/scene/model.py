"""Planar scenes: the one description every source (analytic laws and engines) is given.

Conventions (shared by the engine contract and the scenario files):

* The plane is x (right), y (up); angles are counter-clockwise, in radians here
  (scenario files use degrees and convert).
* A body's pose is the position of its centre of mass and the angle of its x axis.
* Shapes are given in the body frame about the centre of mass:
  ``Disk(radius)``; ``Rod(length, radius)``, a capsule whose end-cap centres lie at
  ``(±length/2, 0)``; ``Box(width, height)``, ``width`` along the body's x axis;
  ``Polygon(vertices)``, convex, counter-clockwise, about the centre of mass;
  ``Ellipse(semi_x, semi_y)``, ``semi_x`` along the body's x axis, about its centre (its
  centre of mass), with the polygon that stands in for it in engines without an ellipse.
* The ground, when present, is the fixed half-space ``y <= 0`` with normal ``+y``.
* Velocities: centre-of-mass velocity ``(v_x, v_y)`` in m/s and angular velocity ``ω`` in
  rad/s (counter-clockwise positive).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Union

import numpy as np


@dataclass(frozen=True)
class Disk:
    radius: float  # m

    kind = "disk"

    def area(self) -> float:
        return math.pi * self.radius**2

    def inertia_per_mass(self) -> float:
        """Polar moment of a uniform disk about its centre, divided by its mass."""
        return 0.5 * self.radius**2


@dataclass(frozen=True)
class Rod:
    """A capsule: a rectangle ``length × 2·radius`` capped by two half-disks."""

    length: float  # m, between the centres of the end caps
    radius: float  # m, of the caps (half the thickness)

    kind = "rod"

    def area(self) -> float:
        return 2.0 * self.radius * self.length + math.pi * self.radius**2

    def inertia_per_mass(self) -> float:
        """Uniform-density capsule about its centre, divided by its mass."""
        length, radius = self.length, self.radius
        rect_area = 2.0 * radius * length
        caps_area = math.pi * radius**2
        # Rectangle about its centre.
        rect = rect_area * (length**2 + (2.0 * radius) ** 2) / 12.0
        # Two half-disks: a full disk's polar moment about its own centre, moved by the
        # parallel-axis theorem. The half-disk centroid sits 4r/(3π) beyond the cap centre.
        half_area = caps_area / 2.0
        centroid_offset = 4.0 * radius / (3.0 * math.pi)
        half_about_own_centroid = half_area * (0.5 * radius**2) - half_area * centroid_offset**2
        distance = length / 2.0 + centroid_offset
        caps = 2.0 * (half_about_own_centroid + half_area * distance**2)
        return (rect + caps) / (rect_area + caps_area)


@dataclass(frozen=True)
class Box:
    width: float  # m, along the body's x axis
    height: float  # m, along the body's y axis

    kind = "box"

    def area(self) -> float:
        return self.width * self.height

    def inertia_per_mass(self) -> float:
        return (self.width**2 + self.height**2) / 12.0

    def vertices(self) -> np.ndarray:
        half_w, half_h = self.width / 2.0, self.height / 2.0
        return np.array([[-half_w, -half_h], [half_w, -half_h], [half_w, half_h],
                         [-half_w, half_h]])


@dataclass(frozen=True)
class Polygon:
    """Convex polygon, vertices counter-clockwise in the body frame about the centre of mass."""

    points: tuple[tuple[float, float], ...]

    kind = "polygon"

    def vertices(self) -> np.ndarray:
        return np.asarray(self.points, dtype=float)

    def area(self) -> float:
        x, y = self.vertices().T
        return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))

    def centroid(self) -> np.ndarray:
        x, y = self.vertices().T
        cross = x * np.roll(y, -1) - np.roll(x, -1) * y
        area = 0.5 * cross.sum()
        cx = np.sum((x + np.roll(x, -1)) * cross) / (6.0 * area)
        cy = np.sum((y + np.roll(y, -1)) * cross) / (6.0 * area)
        return np.array([cx, cy])

    def inertia_per_mass(self) -> float:
        """Uniform-density polygon about the body origin (its centre of mass), per unit mass.

        Worked out once per polygon and kept on the instance, outside the dataclass
        fields: each vertex's terms in plain floats (numpy's elementwise arithmetic, the
        same roundings, costs µs a call on a few points), the two sums numpy's (its
        pairwise order), so the value is what numpy alone gives, bit for bit.
        """
        known = self.__dict__.get("_inertia_per_mass")
        if known is not None:
            return known
        points = self.points
        count = len(points)
        crosses, terms = [], []
        for index in range(count):  # vertex k and k + 1 (np.roll(·, -1))
            x, y = float(points[index][0]), float(points[index][1])
            x1, y1 = map(float, points[index + 1 - count])
            cross = x * y1 - x1 * y
            crosses.append(cross)
            terms.append(cross * (x * x + x * x1 + x1 * x1 + y * y + y * y1 + y1 * y1))
        value = float(np.add.reduce(terms) / (6.0 * np.add.reduce(crosses)))
        object.__setattr__(self, "_inertia_per_mass", value)  # frozen: not a field
        return value


#: Vertices of the polygon standing in for an ellipse in the engines that take no ellipse
#: (pymunk, pybullet, Box2D): few, so that the vertices next to the contact stay well above
#: the ground (docs/engines.md, 'The ellipse').
STAND_IN_VERTICES = 8


@dataclass(frozen=True)
class Ellipse:
    """A uniform ellipse, semi-axes ``semi_x`` along the body's x axis and ``semi_y`` along
    its y axis, centred on the body origin (its centre of mass).

    Only MuJoCo takes an ellipse (its ellipsoid geom); the other engines get
    :meth:`stand_in`, an inscribed polygon with a vertex at the ellipse's point of parameter
    ``vertex_at`` (rad): the point ``(semi_x cos φ, semi_y sin φ)``. Placed there the
    first contact point, the polygon's contact point, normal and Jacobian are the
    ellipse's (every vertex lies on the ellipse, which lies on one side of its tangent);
    :func:`harness.scene.geometry.place_stand_in` places it on a body's lowest point. The
    default is the lowest point of an unturned ellipse.
    """

    semi_x: float  # m, along the body's x axis
    semi_y: float  # m, along the body's y axis
    vertex_at: float = -math.pi / 2  # rad, the parameter of the stand-in's first vertex

    kind = "ellipse"

    def area(self) -> float:
        return math.pi * self.semi_x * self.semi_y

    def inertia_per_mass(self) -> float:
        """Polar moment of a uniform ellipse about its centre, divided by its mass."""
        return (self.semi_x**2 + self.semi_y**2) / 4.0

    def stand_in(self) -> Polygon:
        """The inscribed :data:`STAND_IN_VERTICES`-gon with vertices at parameters
        ``vertex_at + 2πk/N``, counter-clockwise. N even: the polygon is symmetric about the
        centre, so its centroid is the ellipse's (its mass and inertia are the body's in
        every engine all the same). Made once per instance."""
        known = self.__dict__.get("_stand_in")
        if known is not None:
            return known
        count = STAND_IN_VERTICES
        points = []
        for k in range(count):
            phi = self.vertex_at + 2.0 * math.pi * k / count
            points.append((self.semi_x * math.cos(phi), self.semi_y * math.sin(phi)))
        polygon = Polygon(tuple(points))
        object.__setattr__(self, "_stand_in", polygon)  # frozen: not a field
        return polygon


Shape = Union[Disk, Rod, Box, Polygon, Ellipse]


@dataclass(frozen=True)
class Body:
    name: str
    shape: Shape
    mass: float  # kg
    position: tuple[float, float]  # m, centre of mass
    angle: float = 0.0  # rad, CCW, of the body's x axis
    velocity: tuple[float, float] = (0.0, 0.0)  # m/s, centre of mass
    angular_velocity: float = 0.0  # rad/s, CCW
    inertia: float | None = None  # kg m², about the centre of mass; None = uniform density

    @property
    def moment_of_inertia(self) -> float:
        if self.inertia is not None:
            return float(self.inertia)
        return self.mass * self.shape.inertia_per_mass()

    def state(self) -> np.ndarray:
        """Generalised speeds ``(v_x, v_y, ω)`` of this body."""
        return np.array([self.velocity[0], self.velocity[1], self.angular_velocity], dtype=float)

    def moved(self, **changes) -> "Body":
        return replace(self, **changes)


@dataclass(frozen=True)
class Scene:
    """One impact: one body against the fixed ground, or two free bodies."""

    bodies: tuple[Body, ...]
    restitution: float  # e of the pair
    friction: float  # μ of the pair
    ground: bool = False
    name: str = ""
    # An engine run of this scene goes on, through separations, until this time (s) after
    # its first contact: the end of the sequence of impacts the scene's reference is (the
    # event-driven reference's last impact). None: it ends at the first separation.
    run_until: float | None = None

    def __post_init__(self) -> None:
        if self.run_until is not None and not (math.isfinite(self.run_until)
                                               and self.run_until >= 0.0):
            raise ValueError(f"scene {self.name!r}: run_until must be a finite time >= 0 s, "
                             f"got {self.run_until!r}")
        count = len(self.bodies)
        if self.ground and count != 1:
            raise ValueError(f"scene {self.name!r}: a ground scene has exactly 1 body, got {count}")
        if not self.ground and count != 2:
            raise ValueError(
                f"scene {self.name!r}: a scene without ground has 2 bodies, got {count}")

    def state(self) -> np.ndarray:
        """All generalised speeds, ``(v_x, v_y, ω)`` per body in order."""
        return np.concatenate([body.state() for body in self.bodies])

    def mass_matrix(self) -> np.ndarray:
        diagonal = []
        for body in self.bodies:
            diagonal += [body.mass, body.mass, body.moment_of_inertia]
        return np.diag(diagonal)


@dataclass(frozen=True)
class Contact:
    """A single contact: point (world, m), unit normal from body A into body B, and gap (m)."""

    point: np.ndarray
    normal: np.ndarray
    gap: float
    # Number of distinct points at the minimum distance (a face resting on a face gives 2).
    point_count: int = 1
