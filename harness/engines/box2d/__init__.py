"""Box2D (pybox2d 2.3.10) adapter.

The law Box2D solves: sequential impulses on a velocity-level Newton-Coulomb problem per
contact point, in single precision (``float32``). In a step Box2D first updates contacts at
the current positions (collision first), then integrates velocities, iterates impulses until
each point's normal velocity reaches ``-e·v_rel`` (``v_rel`` the point's normal velocity before
the step) with Coulomb friction at the end state -- ``planar_impact``'s ``"newton-lcp"`` for
one point -- and finally moves the bodies. Collision-first means ``approach_steps = 0``
starts the bodies at the scene's pose and the first step finds the contact there
(``StepTiming(lead_steps=0)``).

The restitution threshold: Box2D gives a point its bounce only when ``v_rel <
-b2_velocityThreshold`` (1 m/s, compiled in); a slower impact gets ``e = 0``. The laws are
homogeneous in lengths and velocities, so the adapter can run a scaled copy of the scene:
lengths times ``L`` (``length_scale``), velocities times ``V`` (``velocity_scale``), time times
``L/V`` (the time step passed to Box2D is ``time_step·L/V``), angular velocities times
``V/L``, inertias times ``L²``, masses unchanged, impulses times ``V``. Everything read back
is scaled back. Powers of two keep every scaling exact in binary floating point. ``"auto"``
picks the smallest power of two ``V >= 1`` that lifts the impact speed at the first contact,
computed from the scene in double precision (:func:`.scaling.first_touch_speed`), to
``2 · b2_velocityThreshold``; where rounding could tip that choice between machines, the
larger scale is taken and ``derived["velocity_scale_at_boundary"]`` says so. Every run
measures the speed Box2D itself saw (``derived["box2d_impact_speed"]``, in the scaled
world): after the first step's collision pass called alone
(:func:`.manifold._speed_after_collide`), or, for a scene not touching at its start, by a
PreSolve listener until the first contact.

Other compiled-in limits: ``b2_maxTranslation`` (2 m per step) and ``b2_maxRotation`` (π/2
per step) clip a body's velocity for good when a step would move it further. In scene units
the caps are ``|v| <= 2 m / (L·time_step)`` and ``|ω| <= (π/2) / time_step`` (``V`` cancels):
every run reports them in ``derived`` (``speed_cap``, ``angular_speed_cap``), and a run in
which a velocity sat at a cap carries a note. Polygons carry a skin
(``b2PolygonShape::m_radius``, ``b2_polygonRadius`` = 0.01 m by default): they collide as
rounded shapes, a contact is active within the summed skins, and its point lies midway
between the skinned surfaces.

The start a hair deep: an exactly touching pose can round, in float32, to a hair apart, and
the contact is then found a step late. The adapter moves the base class's start state
``detection_overlap`` body extents further along the free flight (a time of
``overlap·extent / impact speed``), a depth in lengths, which a fraction of a step
(``StepTiming.overlap``) would not give for slow impacts.

Bodies: one ``b2World`` per geometry, length scale and skin; the ground is a static box
whose top face is ``y = 0``. A disk is a circle fixture; a box or polygon a polygon fixture;
a rod (capsule) is two circles at ``(±length/2, 0)`` with a box between them on one body (the
box's half-thickness is the cap radius less its skin, so the fixtures' union is the capsule).
Masses and inertias are set with ``b2Body::SetMassData`` (fixtures have zero density).

Pair values: Box2D mixes ``friction = sqrt(μ_A·μ_B)`` and ``restitution = max(e_A, e_B)``;
every fixture gets the pair's ``e`` and ``μ`` (``sqrt(μ·μ) == μ`` exactly in float32).

Reuse: before each run every contact is destroyed (with its warm-start impulses), the bodies
are put to sleep (zeroing their sleep timers), moved far away and back to the start state
(Box2D fits their proxies' boxes anew) and the contact manager looks for new pairs. The
proxies themselves are kept: their ids set the order in which the contacts are created and
solved, so keeping them makes reruns bit-identical whatever ran before (see
:meth:`_World.place`, :func:`_place`).

Many impacts (``run_many``): up to :data:`MANY_CHUNK` impacts share a b2World, kept apart by
collision groups, with the runs of ``run`` bit for bit (see
:meth:`Box2DEngine._build_many`).

pybox2d's ``contact.worldManifold`` returned an uninitialised normal here: the adapter
computes the world manifold itself, from the poses at the step's start (the manifold's).
Each step reads every body once (its pose then is the next step's start) and only the
touching contacts, from Box2D's structs at their addresses where their layout is the one
checked at import (:mod:`.readout`): pybox2d's getters make a Python
object for every struct they return, which cost many times Box2D's own step.

Settings (``defaults`` | ``accurate``) are listed in :data:`SETTING_DOCS`.

The package keeps the adapter apart from what pybox2d needs worked around (each module's
docstring names the pybox2d problem it answers):

- :mod:`.adapter` -- :class:`Box2DEngine`, the contract's hooks;
- :mod:`.presets` -- the settings, their docs and the two presets, and Box2D's compiled-in
  limits;
- :mod:`.readout` -- Box2D's structs read at their addresses (pybox2d's getters make a
  Python object per struct);
- :mod:`.manifold` -- a contact's world manifold computed anew (pybox2d's
  ``worldManifold`` returned an uninitialised normal);
- :mod:`.building` -- bodies and fixtures made through reused definitions and shapes
  (pybox2d's keyword constructors cost more than the rest of the build);
- :mod:`.world` -- one impact's b2World kept across runs, and what the readout keeps of it;
- :mod:`.scaling` -- the velocity scaling that serves ``e`` below Box2D's compiled-in
  restitution threshold, and the impact speed it is chosen from;
- :mod:`.batch` -- many impacts in one b2World (``run_many``).

The names with a leading underscore are the package's own, shared among its modules; the
rest of the harness reaches the engine through the registry (:mod:`harness.engines`).
"""

from __future__ import annotations

from harness.engines.box2d.adapter import CLIPPED_NOTE, ENGINE_CLASS, Box2DEngine
from harness.engines.box2d.batch import MANY_CHUNK
from harness.engines.box2d.presets import (
    DETECTION_OVERLAP,
    MAX_ROTATION,
    MAX_TRANSLATION,
    POLYGON_RADIUS,
    PRESETS,
    SETTING_DOCS,
    VELOCITY_THRESHOLD,
)
from harness.engines.box2d.scaling import THRESHOLD_NOTE

__all__ = [
    "CLIPPED_NOTE",
    "DETECTION_OVERLAP",
    "ENGINE_CLASS",
    "MANY_CHUNK",
    "MAX_ROTATION",
    "MAX_TRANSLATION",
    "POLYGON_RADIUS",
    "PRESETS",
    "SETTING_DOCS",
    "THRESHOLD_NOTE",
    "VELOCITY_THRESHOLD",
    "Box2DEngine",
]
