"""A scene in a pybullet client: each body a planar multibody chain (prismatic x, prismatic
z, revolute y) with the shape on its last link, and the ground as Bullet's static plane.

pybullet is called with positional arguments where it is called for every body (its keyword
parsing costs ~0.2 µs a call); package docstring, "Planar motion" and "Cost".
"""

from __future__ import annotations

import math

from harness.engines.pybullet.presets import _ENGINE_PARAMETERS
from harness.engines.quiet import import_quietly
from harness.scene import Scene

p = import_quietly("pybullet")  # not `import pybullet as p`: it prints its build time

# Bullet's capsule runs along its frame's z; turned +90° about y, z goes to x.
_CAPSULE_ALONG_X = p.getQuaternionFromEuler([0.0, math.pi / 2.0, 0.0])


def _collision_shape(client: int, shape, extent: float) -> int:
    """The shape's collision shape; ``extent`` is its :func:`body_extent`."""
    depth = 2.0 * extent  # out-of-plane thickness; any value works with the chain
    if shape.kind == "ellipse":  # Bullet's planar ellipse would be a mesh: its placed polygon
        shape = shape.stand_in()
    if shape.kind == "disk":
        return p.createCollisionShape(p.GEOM_SPHERE, radius=shape.radius, physicsClientId=client)
    if shape.kind == "rod":
        return p.createCollisionShape(
            p.GEOM_CAPSULE,
            radius=shape.radius,
            height=shape.length,
            collisionFrameOrientation=_CAPSULE_ALONG_X,
            physicsClientId=client,
        )
    if shape.kind == "box":
        return p.createCollisionShape(
            p.GEOM_BOX,
            halfExtents=[shape.width / 2.0, depth / 2.0, shape.height / 2.0],
            physicsClientId=client,
        )
    vertices = [
        [x, side * depth / 2.0, y]
        for x, y in shape.vertices().tolist()
        for side in (-1.0, 1.0)
    ]
    return p.createCollisionShape(p.GEOM_MESH, vertices=vertices, physicsClientId=client)


# createMultiBody's link arguments that every chain shares (pybullet copies them in).
_LINK_ORIGINS = [[0.0, 0.0, 0.0]] * 3
_LINK_ROTATIONS = [[0.0, 0.0, 0.0, 1.0]] * 3
_NO_VISUALS = [-1, -1, -1]
_LINK_PARENTS = [0, 1, 2]
_NO_FORCES = [0.0, 0.0, 0.0]
_JOINT_TYPES = [p.JOINT_PRISMATIC, p.JOINT_PRISMATIC, p.JOINT_REVOLUTE]
_JOINT_AXES = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]]
_ORIGIN = [0.0, 0.0, 0.0]
_NO_ROTATION = [0.0, 0.0, 0.0, 1.0]
_create_multibody = p.createMultiBody


def _planar_multibody(client: int, body, collision: int, offset: float = 0.0,
                      pair_values: tuple[float, float] | None = None) -> int:
    """The body's planar chain, its last link of shape ``collision``, its base at ``offset``
    along the engine's y (out of the plane); ``pair_values``: its (e, μ), if given."""
    mass, inertia = float(body.mass), float(body.moment_of_inertia)
    # Positional (pybullet's order; each keyword costs a lookup): baseMass,
    # baseCollisionShapeIndex, baseVisualShapeIndex, basePosition, baseOrientation,
    # baseInertialFramePosition, baseInertialFrameOrientation (their defaults), then the
    # links' masses, collision and visual shapes, positions, orientations, inertial frame
    # positions and orientations, parents, joint types and axes, useMaximalCoordinates.
    uid = _create_multibody(0.0, -1, -1, [0.0, offset, 0.0], _NO_ROTATION, _ORIGIN,
                            _NO_ROTATION, [0.0, 0.0, mass], [-1, -1, collision], _NO_VISUALS,
                            _LINK_ORIGINS, _LINK_ROTATIONS, _LINK_ORIGINS, _LINK_ROTATIONS,
                            _LINK_PARENTS, _JOINT_TYPES, _JOINT_AXES, 0, physicsClientId=client)
    # Mass and the inertia in one call (a call without mass= can zero it); e and μ in the
    # same call keep the runs' bits (tests/engines/test_pybullet_survey_identity.py).
    if pair_values is None:
        p.changeDynamics(uid, 2, mass=mass, localInertiaDiagonal=[inertia, inertia, inertia],
                         physicsClientId=client)
    else:
        p.changeDynamics(uid, 2, mass=mass, localInertiaDiagonal=[inertia, inertia, inertia],
                         restitution=pair_values[0], lateralFriction=pair_values[1],
                         physicsClientId=client)
    # The joints' default velocity motors off: no force (one call for the three joints).
    p.setJointMotorControlArray(uid, _LINK_PARENTS, p.VELOCITY_CONTROL, forces=_NO_FORCES,
                                physicsClientId=client)
    return uid


def _configure(client: int, settings) -> None:
    """No gravity and the engine settings that are set (the others stay Bullet's)."""
    p.setGravity(0.0, 0.0, 0.0, physicsClientId=client)
    parameters = {
        keyword: settings[key]
        for key, keyword in _ENGINE_PARAMETERS.items()
        if settings[key] is not None
    }
    p.setPhysicsEngineParameter(physicsClientId=client, **parameters)


def _add_plane(client: int) -> int:
    """The ground: Bullet's static plane ``z = 0``, with the partner's neutral e and μ."""
    plane_shape = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=client)
    plane = p.createMultiBody(0.0, plane_shape, physicsClientId=client)
    p.changeDynamics(plane, -1, restitution=1.0, lateralFriction=1.0, physicsClientId=client)
    return plane


def _add_bodies(client: int, scene: Scene, settings, extents, offset: float = 0.0,
                pair_values: tuple[float, float] | None = None) -> list[int]:
    """The scene's bodies (``extents``: their :func:`body_extent`) as planar chains (bases at
    ``offset`` along y), damped as set, never sleeping; ``bodies[0]`` gets ``pair_values``
    (e, μ) if given (else :meth:`PybulletEngine._reset` sets them), the partner body the
    neutral e and μ."""
    bodies = []
    linear_damping = float(settings["linear_damping"])
    angular_damping = float(settings["angular_damping"])
    for body, extent in zip(scene.bodies, extents):
        collision = _collision_shape(client, body.shape, extent)
        uid = _planar_multibody(client, body, collision, offset, pair_values)
        pair_values = None  # bodies[0]'s only
        # On the shape's link only: the damping and sleeping are the multibody's, and the
        # massless links' joint damping is 0 already (the runs keep their bits: the tests).
        # A separate call from the mass's: one call with both changed the bits (measured).
        p.changeDynamics(uid, 2, linearDamping=linear_damping, angularDamping=angular_damping,
                         jointDamping=0.0, activationState=p.ACTIVATION_STATE_DISABLE_SLEEPING,
                         physicsClientId=client)
        bodies.append(uid)
    if len(bodies) == 2:
        p.changeDynamics(bodies[1], 2, restitution=1.0, lateralFriction=1.0,
                         physicsClientId=client)
    return bodies
