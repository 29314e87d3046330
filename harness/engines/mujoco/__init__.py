"""MuJoCo adapter.

MuJoCo has no restitution coefficient: a contact is a soft constraint whose reference
acceleration is ``a_ref = -b·v - k·r`` (``r`` the penetration, ``v`` its rate); with an
impedance ``d`` near 1 the constraint space follows it, so over an impact the normal
direction behaves as a spring-damper that cannot pull. Its restitution follows from the
damping ratio ``ζ = b / (2·sqrt(k))`` alone (:func:`restitution_of_damping_ratio`): the
contact ends when ``k·r + b·v`` reaches 0, before the bodies separate, which is why
``e = 0.5`` needs ``ζ = 0.2553`` and not the linear formula's 0.2155. Friction is soft too,
and under ``accurate`` the same damping sets how much of the slip it removes (below).

Presets: ``defaults`` and ``matched-bounce``, the name this engine shows for the harness's
``accurate`` role (harness/engines/__init__.py): it matches the bounce ``e·|v_n|``, but with
friction leaving ``e²`` of the slip it creates kinetic energy in a part of the impacts with
``m_nt ≠ 0`` (docs/engines.md, 'MuJoCo'); no setting that keeps the bounce prevents it.

``matched-bounce`` sets, from the scene's ``e``, ``solref = (-k, -b)`` (MuJoCo's direct form) with
``ζ`` from the unilateral map and ``k`` such that the contact lasts ``contact_steps`` steps,
and a flat ``solimp`` (``d = 0.9999`` at every depth). ``defaults`` is MuJoCo's
``solref = (0.02, 1)``, ``solimp = (0.9, 0.95, 0.001, 0.5, 2)`` -- ``e`` is then not used
(measured restitution ≈ 0.13).

Planar motion: slide x, slide z and hinge y joints with an explicit ``<inertial>`` (mass and
the scene's inertia). The scene's (x, y) is MuJoCo's (x, z); the hinge's angle and rate are
``-θ`` and ``-ω``. Shapes: disk -> sphere; rod -> capsule along the body's x; box -> box;
polygon -> mesh (the polygon extruded along y); ellipse -> ellipsoid with semi-axes
``(semi_x, c, semi_y)`` (:func:`_geom_size`). Ground: an infinite plane, normal +z.
``μ = 0`` uses ``condim = 1`` (frictionless contact); otherwise ``condim = 3``.

Friction under ``matched-bounce``: the slip falls to ``e²`` of its start, and not at all at e = 1
    MuJoCo's friction rows have no spring term, only the contact's damping ``b``. Pyramidal
    cone: the two edge rows ``J_n ± μ·J_t`` both get ``a_ref = -b·(v_n ± μ·v_t) - k·r``;
    while both push, their difference gives the tangential reference ``a_t = -b·v_t`` (the
    ``k·r`` terms cancel). Elliptic cone: ``K = 0`` on the friction rows, so again
    ``a_t = -b·v_t``. With ``d`` near 1 the contact point's slip falls as ``exp(-b·t)`` while
    inside the cone, and over the contact time ``T = φ(ζ)/ω₀`` (:func:`contact_time_factor`)
    by ``exp(-b·T) = exp(-2ζ·φ(ζ)) = e²``: the ``b = 2ζω₀`` that sets the bounce also sets
    the friction. Measured (disk, slip 0.1 m/s, μ 0.3): slip ratio 0.8103 / 0.4905 / 0.2506
    / 0.0908 / 0.0100 at e = 0.9 / 0.7 / 0.5 / 0.3 / 0.1, e² within 8e-4 (the cone saturates
    only as the normal force vanishes at the end). A larger slip saturates the cone early and
    keeps more (reference disk, slip 1 m/s, e = 0.5: 0.265; docs/engines.md, 'MuJoCo').
    At ``e = 1`` (ζ = 0, b = 0) both edges get the same ``a_ref = -k·r``, carry equal forces,
    and the tangential impulse is exactly 0: the bounce is frictionless whatever μ and the
    spin. ``disk-backspin-elastic`` comes out with v_x 1 and ω -20 as it went in; its 28.9%
    departure from Poisson is the distance of the frictionless bounce from the law
    (1/sqrt(12)). The elliptic cone, impratio 100, noslip 50 and CG also give exactly 0
    (PGS 1.6e-6 N s, its iteration error): ``impratio`` scales only the regularisation ``R``,
    tiny at ``d = 0.9999``, and noslip works towards the same ``a_ref``.
    This is MuJoCo's contact model fed the adapter's e -> ζ map, not a set-up error: the
    geom friction reaches the contact (``mu`` 0.3 by the max rule) and ``condim`` 3 makes
    four pyramid rows. MuJoCo's one way to decouple, ``solreffriction``, exists only on
    explicit ``<pair>`` contacts and acts only with the elliptic cone. Tried, not used: a
    friction damping strong enough to give Poisson's tangential result at e = 1
    (``solreffriction = (0, -1e5)``: v_x 1.3334, ω -13.334) spoils the bounce through the
    cone (v_y 0.215 instead of 1; 0.824 at ``-1e4``).

Pair values: MuJoCo takes the larger friction of the two geoms, so the partner (plane, or
``bodies[1]``) has friction 0 and ``bodies[0]`` has ``μ``; both geoms get the same
``solref``/``solimp`` (MuJoCo averages them).

Reuse: one compiled ``MjModel`` and ``MjData`` per topology (ground or not, shape kinds),
for ``run`` and ``run_many`` alike (``run_many`` is ``run`` per scene: the engine steps one
impact per model, see docs/engines.md, 'MuJoCo'). For disks, rods and boxes a scene's
sizes, bounding spheres and boxes, masses and inertias are written into the model,
``mj_setConst`` derives subtree masses, ``invweight0``, ``dof_M0`` and ``dof_length``, and
:func:`_write_statistics` the statistics (MuJoCo 4's ``mj_setConst`` leaves them; the
solver reads ``meaninertia``): every array equals a fresh compile's, bit for bit
(tests/engines/test_mujoco_geometry.py). A polygon's mesh goes through the compiler
(hull, centroid, inertial frame): a copy of the topology's parsed spec takes the scene's
values and is compiled, about half the cost of parsing XML; the models of a topology share
one ``MjData`` per layout. Each run makes the model hold every option and contact parameter
of its settings, ``e`` and ``μ`` (rewritten whenever they differ by value from what the
model holds) and calls ``mj_resetData``, so reruns are bit-identical. A step reads its
contacts through one numpy view of the data's arena, made once per data
(``_contact_rows``), and its constraint forces through views of the same arena made once
per row count (``_force_view``) and kept while the data, model and options stay. The
contact impulse is MuJoCo's total constraint impulse on body B, ``M·Δq̇`` (exact here: no
gravity, no passive forces, constant mass matrix).

Settings (``defaults`` | ``accurate``, shown as ``matched-bounce``) are listed in
:data:`SETTING_DOCS`.

The package keeps the adapter apart from the model it builds and the reads it makes fast:

- :mod:`.adapter` -- :class:`MujocoEngine`, the contract's hooks (holding a scene's
  geometry, writing a run's options and contact parameters, the per-step readout);
- :mod:`.presets` -- the settings, their docs, the two presets and MuJoCo's enums they name;
- :mod:`.restitution` -- the map between the damping ratio and restitution (``e <-> ζ``);
- :mod:`.model` -- a scene as MuJoCo's XML and spec, and the values a compile gives a
  scene's geometry (written into a model without compiling it);
- :mod:`.world` -- a world: the compiled model, its data and the numpy views of the data's
  arena made once.

The names with a leading underscore are the package's own, shared among its modules; the
rest of the harness reaches the engine through the registry (:mod:`harness.engines`).
"""

from __future__ import annotations

from harness.engines.mujoco.adapter import BENCH_CONTACT_DURATION_S, ENGINE_CLASS, MujocoEngine
from harness.engines.mujoco.presets import PRESETS, SETTING_DOCS
from harness.engines.mujoco.restitution import (
    MIN_RESTITUTION,
    contact_time_factor,
    damping_ratio_for_restitution,
    restitution_of_damping_ratio,
    restitution_solref,
)

__all__ = [
    "BENCH_CONTACT_DURATION_S",
    "ENGINE_CLASS",
    "MIN_RESTITUTION",
    "PRESETS",
    "SETTING_DOCS",
    "MujocoEngine",
    "contact_time_factor",
    "damping_ratio_for_restitution",
    "restitution_of_damping_ratio",
    "restitution_solref",
]
