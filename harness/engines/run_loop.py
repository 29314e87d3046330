"""The run loop's state and the bookkeeping of its records, shared by ``Engine.run`` and
``Engine.run_many`` (harness/engines/contract.py, 'The loop').

:class:`Plan` holds what a run needs that depends only on the scene and the settings;
:class:`Progress` one run's loop state and the rule that ends the contact; :func:`tally`
reads the run's contact records once, after the loop.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence

from harness.engines.run_result import Pose, RawContacts, Velocity
from harness.scene.features import body_extent

# Relative size of a step's normal impulse (against the largest step's) below which the
# step counts as "no impulse": rounding noise of re-solving a resting contact is ~1e-16.
NO_IMPULSE_RELATIVE = 1e-12
# A contact point still closes when its relative normal velocity is below this fraction of
# the scene's largest speed (rounding of a resting contact is ~1e-16 of it).
APPROACH_RELATIVE = 1e-9
# In-plane points closer than this fraction of the largest body extent are one point.
SAME_POINT_RELATIVE = 1e-6
# Steps beyond a scene's ``run_until`` through which a separation does not end the run: an
# engine resolves a strike up to a step or two from its exact time (it detects contacts at
# the start or the end of a step, or through a skin), so the sequence's last strike may come
# a step or two after the reference's.
SEQUENCE_MARGIN_STEPS = 4


class Plan:
    """Everything a run needs that depends only on the scene and the settings objects
    (filled in by ``Engine._new_plan``)."""

    __slots__ = ("_same_point", "before", "body_b_mass", "body_b_velocity", "dt", "max_steps",
                 "notes", "prepared", "scene", "settings", "shift", "speed_scale", "until_steps",
                 "weights", "world", "world_key")

    def __init__(self, scene, settings, world, world_key) -> None:
        self.scene, self.settings = scene, settings
        self.world, self.world_key = world, world_key
        self._same_point = None

    @property
    def same_point(self) -> float:
        """In-plane points closer than this (m) are one point (:data:`SAME_POINT_RELATIVE`
        of the largest body extent); worked out on first use: only a step with several
        points needs it, and a polygon's extent costs µs."""
        tolerance = self._same_point
        if tolerance is None:
            tolerance = self._same_point = SAME_POINT_RELATIVE * max(
                max(body_extent(body.shape) for body in self.scene.bodies), 1e-12)
        return tolerance


class Progress:
    """One run's loop state, and the rule that ends it (shared by ``Engine.run`` and
    ``Engine.run_many``).

    The contact ends at a step, after contact began, with no contact, or whose normal
    impulse is at most ``no_impulse_relative`` of the largest while no contact point still
    closes (see the module docstring).
    """

    # What observe reads at every step is held here, not looked up on the engine and the
    # plan each time (the loop's hot path: every step of every run).
    __slots__ = ("_append", "_read_poses", "_read_velocities", "_relative", "_speed_scale",
                 "_until", "first_contact", "peak", "records", "separated", "velocities")

    def __init__(self, plan: Plan, read_poses: Callable, read_velocities: Callable,
                 no_impulse_relative: float) -> None:
        self.first_contact = None
        self.peak = 0.0
        self.separated = False
        self.records = records = []
        self.velocities = None  # set where read at the step that ended the contact
        self._append = records.append
        self._read_poses = read_poses
        self._read_velocities = read_velocities
        self._relative = no_impulse_relative
        self._speed_scale = plan.speed_scale
        self._until = plan.until_steps

    def observe(self, raw: RawContacts | None, steps: int, world) -> bool:
        """Take step ``steps``'s contact ``raw`` of ``world``; True when the run ends here."""
        if raw is None:
            first = self.first_contact
            if first is not None:
                self.separated = True
                return steps - first >= self._until
            return False
        first = self.first_contact
        if first is None:
            first = self.first_contact = steps
        self.separated = False  # a contact again, in a sequence of impacts (run_until)
        self.velocities = None
        poses = self._read_poses(world)
        self._append((steps, raw, poses))
        pressure = raw[3]
        if pressure is None:  # still pushing, by the adapter's knowledge
            return False
        peak = self.peak
        if pressure > peak:
            peak = self.peak = pressure
        if pressure <= self._relative * peak:
            velocities = self._read_velocities(world)
            if not approaching(poses, velocities, raw, self._speed_scale):
                self.separated = True
                if steps - first < self._until:
                    return False  # the sequence may not be over: read again at the end
                self.velocities = velocities
                return True
        return False


def approaching(poses: Sequence[Pose], velocities: Sequence[Velocity], raw: RawContacts,
                 speed_scale: float) -> bool:
    """Whether any contact point still closes (relative normal velocity below
    ``-APPROACH_RELATIVE·speed_scale``): a step without impulse is then not a separation
    (a contact found before touch carries none while the bodies still approach)."""
    n_x, n_y = raw[1]
    last = len(poses) - 1
    for point_x, point_y, _ in raw[0]:
        relative = 0.0
        for index, ((x, y, _), (vx, vy, omega)) in enumerate(zip(poses, velocities)):
            normal_velocity = ((vx - omega * (point_y - y)) * n_x
                               + (vy + omega * (point_x - x)) * n_y)
            relative += normal_velocity if index == last else -normal_velocity
        if relative < -APPROACH_RELATIVE * speed_scale:
            return True
    return False


def count_planar_points(points: Iterable[tuple[float, float]], tolerance: float) -> int:
    """Number of distinct in-plane points (closer than ``tolerance`` in x and y count as one).

    A 3-D engine may report a prism's edge touching the ground as two points at ±y; they
    are the same point of the planar problem.
    """
    if type(points) is list and len(points) == 2:  # a prism's edge, every 3-D contact step
        (x, y), (a, b) = points
        return 2 if abs(a - x) > tolerance or abs(b - y) > tolerance else 1
    distinct: list[tuple[float, float]] = []
    for x, y in points:
        if all(abs(x - a) > tolerance or abs(y - b) > tolerance for a, b in distinct):
            distinct.append((x, y))
    return len(distinct)


def tally(records: Sequence, plan: Plan) -> tuple[int, float, float, float, bool]:
    """``(max_points, max_penetration, impulse_x, impulse_y, engine_impulse)`` of a run's
    contact records ``(step, RawContacts, poses)``: the most distinct in-plane points of one
    step, the largest depth, the summed impulse on body B, and whether every step gave its
    impulse (else it is worked out from momentum)."""
    max_points = 0
    max_penetration = 0.0
    impulse_x = impulse_y = 0.0
    engine_impulse = True
    same = None  # plan.same_point, asked for once and only if a step has two points
    for _, (points, _, impulse, _), _ in records:
        for point in points:
            if point[2] > max_penetration:  # noqa: PLR1730 - hot path
                max_penetration = point[2]
        count = len(points)
        if count == 2:  # count_planar_points' two points (a prism's edge, in 3-D), inlined
            (x, y, _), (a, b, _) = points
            if same is None:
                same = plan.same_point
            count = 2 if abs(a - x) > same or abs(b - y) > same else 1
        elif count > 2:
            count = count_planar_points([(x, y) for x, y, _ in points], plan.same_point)
        if count > max_points:  # noqa: PLR1730 - hot path
            max_points = count
        if impulse is None:
            engine_impulse = False
        else:
            impulse_x += impulse[0]
            impulse_y += impulse[1]
    return max_points, max_penetration, impulse_x, impulse_y, engine_impulse
