"""pybullet (Bullet) adapter.

The law Bullet solves: sequential impulses (projected Gauss-Seidel) on a velocity-level
Newton-Coulomb problem (``planar_impact``'s ``"newton-lcp"``), with two biases that its
defaults switch on: a contact is created up to ``contactBreakingThreshold`` (0.02 m) before
touch and the solver then aims at ``e·|v_n| - gap/dt``; restitution is zeroed below
``restitutionVelocityThreshold`` (0.2 m/s). ``accurate`` removes both and the position
(ERP) terms, and turns warm starting off (see :data:`PRESETS`). In a step Bullet detects
contacts at the current positions, solves velocities, then moves: ``approach_steps = 0``
starts the bodies at the scene's pose.

Planar motion: each body is a fixed-base multibody chain world -> prismatic x ->
prismatic z -> revolute y, the shape on the last link with the scene's mass and inertia,
the joints' default velocity motors off (``force=0``) and joint damping 0. The scene's
(x, y) is the engine's (x, z); the revolute joint's angle and rate are ``-θ`` and ``-ω``.
Shapes: disk -> sphere (its in-plane section is the disk; the chain keeps it planar); rod ->
capsule along the link's x; box -> box; polygon -> convex hull of the polygon extruded
along y -- pybullet 3.2.7 keeps a link's hull collision margin at 0.001 m (changeDynamics
acts on bases only), so a polygon's contacts sit 1 mm outside it: a measured, pinned
departure, noted on the run. The ground is Bullet's static plane (normal +z; the
convex-plane collider uses exact support points).

Pair values: Bullet multiplies the two restitutions and the two lateral frictions; the
partner (plane, or ``bodies[1]``) gets 1, ``bodies[0]`` gets ``e`` and ``μ``.

Reuse and determinism: one world per (engine settings, geometry) -- at most
:data:`_MAX_WORLDS` alive, least recently used released. A world is a DIRECT client of its
own; connecting one costs ~20-50 ms, so a released world's client is emptied
(``resetSimulation``, which deletes Bullet's dynamics world and makes a new one) and kept
idle for the next world of the same engine settings (at most :data:`_MAX_IDLE` per
settings), which is then built in it in ~1 ms. Per settings only: a client keeps some
values across a reset (the time step, the sub-step count), and every value a world of the
same settings sets is the same, so a reused client equals a new one bit for bit
(tests/engines/test_pybullet.py checks runs against a fresh adapter's). Bullet's
``contactBreakingThreshold`` is a process-wide global read when a contact manifold is
created, so it is set again before every run. Before a run the bodies are parked far from
each other and the plane and collision detection is run once, which empties the contact
manifolds (Bullet warm-starts from them); sleeping is disabled.

Cost: an impact is ~2 steps, so what depends only on the scene and the settings (world,
start joint states, energy weights) is computed once per (scene, settings) pair of objects,
and pybullet is called with positional arguments (its keyword parsing costs ~0.2 µs a call).
Clients run without pybullet's TinyRenderer plugin, which meshed every new link's collision
shape for rendering (most of ``createMultiBody``'s cost for a sphere).

Many impacts (``run_many``, the survey): a new geometry needs new bodies, and
``createMultiBody`` (~0.2-0.3 ms a body) is then the cost of an impact, so many impacts
share one client (:data:`MANY_IMPACTS`, ground and two-body scenes apart) with one
``stepSimulation`` and one ``getContactPoints`` a step, instead of a client reset each.
Each impact lies in its own slice of the engine's y, the axis out of the scene's plane:
the joints' rotations about y have exact zeros off the plane and Bullet's collision and
Jacobian arithmetic works with differences of positions, so the x-z numbers are those of a
lone run at y = 0, while slices :data:`_MANY_GAP` (plus twice the contact breaking
threshold) apart never meet. The slices are laid out in bit-reversed order of making
(:func:`_slice_offsets`): made in order along the line, they made Bullet's broad-phase tree
a chain that every new, first-moved or removed body walked.
They share only the static plane, which joins no simulation islands. Finished impacts are
removed. The runs equal :meth:`run`'s bit for bit (tests/engines/test_pybullet_many.py);
moving impacts apart within the plane instead changes roundings (measured).
A batch's client is kept for the next batch of its settings and kind, with its plane, and
emptied by removing the bodies left in it: a ``resetSimulation`` (~2 ms, Bullet remakes its
dynamics world and memory pools) cost more than a batch's stepping. Bullet keeps every
collision shape made in a client (it refuses to remove one a removed body used, ~8 kB an
impact), so the client is reset after :data:`_MANY_RESET_AFTER` impacts
(tests/engines/test_pybullet_clients.py: runs keep their bits across both).
Where a batch's time goes (700 survey scenes, process CPU, measured with every pybullet call
timed): about three quarters inside pybullet -- ``createMultiBody`` a third (pybullet
serialises each new body's description and parses it back in the client, ~0.1 ms a call
whatever it creates: a ``batchPositions`` call of one body costs as much, and only its
copies of one shape share it), stepping a fifth -- and about a tenth in this module's
Python; the client's reset then costs ~15 µs per body made since the last. pybullet 3.2.7
has no call reading several bodies' joint states, ``createMultiBody`` takes no inertia, the
``changeDynamics`` folds tried change the bits (docs/engines.md; so does e and μ in the
damping call), and batch sizes 4 to 64 cost the same within the noise.

Settings (``defaults`` | ``accurate``) are listed in :data:`SETTING_DOCS`; ``None`` means
"not set: Bullet's default".

The package keeps the adapter apart from the pybullet calls it is built of:

- :mod:`.adapter` -- :class:`PybulletEngine`, the contract's hooks (worlds kept and
  evicted, a run's reset and steps, many impacts per client);
- :mod:`.presets` -- the settings, their docs and the two presets;
- :mod:`.bodies` -- a scene's planar multibody chains and the ground in a client;
- :mod:`.world` -- one impact's world, and its per-step reads (joint states, contacts);
- :mod:`.clients` -- DIRECT clients connected, emptied and kept between uses, and the
  batch that holds many impacts in one client.

The names with a leading underscore are the package's own, shared among its modules; the
rest of the harness reaches the engine through the registry (:mod:`harness.engines`).
"""

from __future__ import annotations

from harness.engines.pybullet.adapter import ENGINE_CLASS, MANY_IMPACTS, PybulletEngine
from harness.engines.pybullet.presets import PRESETS, SETTING_DOCS

__all__ = ["ENGINE_CLASS", "MANY_IMPACTS", "PRESETS", "SETTING_DOCS", "PybulletEngine"]
