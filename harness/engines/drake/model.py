"""A scene as a Drake diagram: a MultibodyPlant with a planar joint per body, the shapes'
collision geometry, the ground half-space, and the per-run contact properties.

The scene's (x, y) is Drake's (x, y); each body has a :class:`PlanarJoint` to the world
(``q = (x, y, θ)``, ``v = (v_x, v_y, ω)``, rotation about +z: the scene's own signs), so the
motion is planar by construction. Shapes: disk -> sphere, rod -> capsule turned onto x,
box -> box, polygon -> the convex hull of the polygon extruded along z, ellipse ->
ellipsoid ``(semi_x, semi_y, min)``; the ground is a half-space whose normal is +y.
"""

from __future__ import annotations

import logging
import math
from functools import partial

import numpy as np
from pydrake.geometry import (
    AddContactMaterial,
    Box,
    Capsule,
    Convex,
    Ellipsoid,
    HalfSpace,
    ProximityProperties,
    RoleAssign,
    Sphere,
)
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import AddMultibodyPlant, CoulombFriction, MultibodyPlantConfig
from pydrake.multibody.tree import PlanarJoint, SpatialInertia, UnitInertia
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from harness.engines.contract import body_extent
from harness.scene import Scene

# Drake warns, once per world, that a rigid half-space takes no part in deformable contact
# (there is none here), and once per process that TAMSI is deprecated (the pinned 1.51.1
# keeps it; docs/engines.md, 'Drake'); its other messages stay.
_SILENCED = ("deformable contact", "The TAMSI solver is deprecated")
logging.getLogger("drake").addFilter(
    lambda record: not any(text in record.getMessage() for text in _SILENCED))

# The capsule's axis is Drake's z: turned about y onto x, the rod's length axis.
_ROD_FRAME = RigidTransform(RotationMatrix.MakeYRotation(math.pi / 2), [0.0, 0.0, 0.0])
# The half-space's outward normal is its frame's +z: turned about x onto +y.
_GROUND_FRAME = RigidTransform(RotationMatrix.MakeXRotation(-math.pi / 2), [0.0, 0.0, 0.0])


def plant_config(settings) -> MultibodyPlantConfig:
    """The settings that are MultibodyPlantConfig's own; always point contact (the geometry
    carries no hydroelastic properties, so Drake's default hydroelastic_with_fallback would
    be point contact too)."""
    return MultibodyPlantConfig(
        time_step=float(settings["time_step"]),
        penetration_allowance=float(settings["penetration_allowance"]),
        stiction_tolerance=float(settings["stiction_tolerance"]),
        contact_model="point",
        discrete_contact_approximation=settings["discrete_contact_approximation"])


def world_key(scene: Scene, settings, geometry: tuple) -> tuple:
    """A world depends on the geometry (with masses: Drake's default stiffness is estimated
    from them at Finalize) and the plant's configuration."""
    return (geometry, float(settings["time_step"]), float(settings["penetration_allowance"]),
            float(settings["stiction_tolerance"]), settings["discrete_contact_approximation"])


def _shape(body) -> tuple[object, RigidTransform]:
    shape = body.shape
    kind = shape.kind
    depth = 2.0 * body_extent(shape)  # the prism's extent out of the plane (any > 0)
    if kind == "disk":
        return Sphere(shape.radius), RigidTransform()
    if kind == "rod":
        return Capsule(shape.radius, shape.length), _ROD_FRAME
    if kind == "box":
        return Box(shape.width, shape.height, depth), RigidTransform()
    if kind == "ellipse":
        c = min(shape.semi_x, shape.semi_y)
        return Ellipsoid(shape.semi_x, shape.semi_y, c), RigidTransform()
    points = np.asarray(shape.vertices(), dtype=float)  # polygon: its hull, extruded
    prism = np.vstack([np.column_stack([points, np.full(len(points), side * depth / 2)])
                       for side in (-1.0, 1.0)])
    return Convex(prism.T, "polygon"), RigidTransform()


class World:
    """One scene's diagram, its contexts and simulator, and what a run reads every step."""

    def __init__(self, scene: Scene, settings) -> None:
        builder = DiagramBuilder()
        plant, scene_graph = AddMultibodyPlant(plant_config(settings), builder)
        plant.mutable_gravity_field().set_gravity_vector([0.0, 0.0, 0.0])  # impact only
        self.bodies, self.joints, self.geometries = [], [], []
        for index, body in enumerate(scene.bodies):
            mass, inertia = float(body.mass), float(body.moment_of_inertia)
            # Only I_zz acts in the plane; I_xx = I_yy = I_zz is a valid 3-D inertia.
            unit = inertia / mass
            rigid = plant.AddRigidBody(f"b{index}", SpatialInertia(
                mass, [0.0, 0.0, 0.0], UnitInertia(unit, unit, unit)))
            shape, frame = _shape(body)
            self.geometries.append(plant.RegisterCollisionGeometry(
                rigid, frame, shape, f"g{index}", ProximityProperties()))
            self.joints.append(plant.AddJoint(
                PlanarJoint(f"j{index}", plant.world_frame(), rigid.body_frame())))
            self.bodies.append(rigid)
        if scene.ground:
            self.geometries.insert(0, plant.RegisterCollisionGeometry(
                plant.world_body(), _GROUND_FRAME, HalfSpace(), "ground", ProximityProperties()))
        plant.Finalize()
        self.diagram = builder.Build()
        self.context = self.diagram.CreateDefaultContext()
        self.plant, self.scene_graph = plant, scene_graph
        self.plant_context = plant.GetMyMutableContextFromRoot(self.context)
        self.geometry_context = scene_graph.GetMyMutableContextFromRoot(self.context)
        self.simulator = Simulator(self.diagram, self.context)
        # What a run calls every step, bound once: every lookup through the bindings costs
        # (the step's read-out is a third of its instructions; docs/engines.md, 'Drake').
        self.advance_to = self.simulator.AdvanceTo
        port = plant.get_contact_results_output_port()
        self.contact_results = partial(port.Eval, self.plant_context)
        # The port's value, held from a run's first step on (a user's loop never reads it):
        # a step's results are computed into this same object, so after a step EvalAbstract
        # brings it up to date (7 k instructions against Eval's 12 k: no wrapping of the
        # value; tests/engines/test_drake.py checks that it is Eval's, every step).
        self.update_contact_results = partial(port.EvalAbstract, self.plant_context)
        self.results = None
        self.positions = partial(plant.GetPositions, self.plant_context)
        self.velocities = partial(plant.GetVelocities, self.plant_context)
        # The plant's discrete state [q; v] as a numpy view of the context's own vector (no
        # copy, no call): a step writes its values in place (tests/engines/test_drake.py).
        self.state = self.plant_context.get_discrete_state_vector().get_value()
        self.positions_count = plant.num_positions()
        self.source = plant.get_source_id()
        self.time_step = float(settings["time_step"])
        self.extents = [body_extent(body.shape) for body in scene.bodies]
        # The geometry of the scene's body B (the last; one geometry a body): a point pair
        # whose Drake B it is reports the force on the scene's B.
        self.geometry_b = self.geometries[-1]
        # +1 when a point pair's Drake B is the scene's body B, -1 the other way round: read
        # at a run's first contact step and kept (Drake orders a pair's ids, id_A < id_B, so
        # the one pair of two geometries keeps its order).
        self.sign = None
        self.steps = 0
        self.held = None  # the contact properties the geometry holds (by value)

    def hold_properties(self, properties: tuple) -> None:
        """Every geometry gets ``(stiffness, dissipation, μ)`` (None: Drake's estimate), in
        the context: Drake combines two geometries' stiffnesses in series, their
        dissipations weighted by the other's stiffness and their frictions by the harmonic
        mean, so equal values on both give the pair's ``k/2``, ``d`` and ``μ``."""
        if properties == self.held:
            return
        stiffness, dissipation, mu = properties
        for geometry in self.geometries:
            values = ProximityProperties()
            AddContactMaterial(dissipation=dissipation, point_stiffness=stiffness,
                               friction=CoulombFriction(mu, mu), properties=values)
            self.scene_graph.AssignRole(self.geometry_context, self.source, geometry, values,
                                        RoleAssign.kReplace)
        self.held = properties
