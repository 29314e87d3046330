"""A run's per-step contact records, as the verdicts read them.

:class:`StepContacts` is one step's contact as an engine recorded it; :class:`ContactTrack`
holds a run's records as arrays (read from an engine run's own raw record or a task's
output only when a check first asks for them), and :func:`records_many` reads many runs'
raw records into flat arrays at once, for the batched second-feature check.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from itertools import chain
from operator import itemgetter
from typing import Any

import numpy as np


@dataclass(frozen=True)
class StepContacts:
    """One step's contact as an engine recorded it, in the scene frame.

    ``points``: ``(x, y, depth)`` per point (m; depth > 0 overlap); ``bodies``: every body's
    ``(x, y, θ, v_x, v_y, ω)`` after the step. Matches the engines' ``ContactStep``.
    """

    step: int
    points: tuple[tuple[float, float, float], ...]
    bodies: tuple[tuple[float, ...], ...]


class ContactTrack:
    """A run's per-step contact records as arrays, in the scene frame, so that a check looks
    at every point of every step at once.

    ``steps``: ``(R,)`` the step of each record; ``poses``: ``(R, B, 3)`` every body's
    ``(x, y, θ)`` after that step; ``points``: ``(P, 3)`` every point's ``(x, y, depth)`` (m;
    depth > 0 overlap), record by record in order; ``record``: ``(P,)`` the record (row of
    ``steps``) each point belongs to; ``size``: ``P``. A track of an engine run's own record
    (:meth:`from_record`) or of a task's output (:meth:`from_output`) reads its arrays when a
    check first asks for them: most runs need none (a disk's, or one point in all).
    """

    __slots__ = ("_arrays", "_raw", "size")

    def __init__(self, steps: np.ndarray, poses: np.ndarray, points: np.ndarray,
                 record: np.ndarray):
        self._arrays = (steps, poses, points, record)
        self._raw = None
        self.size = len(points)

    @property
    def steps(self) -> np.ndarray:
        return self._read()[0]

    @property
    def poses(self) -> np.ndarray:
        return self._read()[1]

    @property
    def points(self) -> np.ndarray:
        return self._read()[2]

    @property
    def record(self) -> np.ndarray:
        return self._read()[3]

    def _read(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        if self._arrays is None:
            read, raw = self._raw
            self._arrays = read(raw)
            self._raw = None
        return self._arrays

    @classmethod
    def from_steps(cls, records: Sequence[StepContacts]) -> ContactTrack:
        """The track of :class:`StepContacts` records (of each body only ``(x, y, θ)``)."""
        return cls._of([record.step for record in records],
                       [record.points for record in records],
                       [record.bodies for record in records])

    @classmethod
    def from_output(cls, contacts: Sequence[Mapping[str, Any]]) -> ContactTrack:
        """The track of the runner's engine-task output ``contacts`` (dicts with ``step``,
        ``points`` and ``bodies``), read only when asked (as :meth:`from_record`)."""
        track = cls.__new__(cls)
        track._arrays, track._raw = None, (_output_arrays, contacts)
        track.size = sum(len(record["points"]) for record in contacts)
        return track

    @classmethod
    def from_record(cls, contact_record) -> ContactTrack:
        """The track of an ``EngineRun.contact_record`` ``(shift, raw)`` (run frame: scene
        frame + shift), read without building a typed record per step, and only when asked:
        the numbers of ``EngineRun.contacts``, each coordinate less the shift."""
        track = cls.__new__(cls)
        track._arrays, track._raw = None, (_record_arrays, contact_record)
        track.size = sum(len(contacts[0]) for _, contacts, _ in contact_record[1])
        return track

    @classmethod
    def _of(cls, steps: Sequence[int], points, states) -> ContactTrack:
        """The track of per-record steps, point lists and body states."""
        counts = [len(record) for record in points]
        bodies = len(states[0]) if len(states) else 0
        flat_points = np.array([point[:3] for record in points for point in record],
                               dtype=float).reshape(-1, 3)
        poses = np.array([[state[:3] for state in record] for record in states],
                         dtype=float).reshape(len(states), bodies, 3)
        return cls(np.asarray(steps, dtype=np.int64), poses, flat_points,
                   np.repeat(np.arange(len(counts)), counts))


def _output_arrays(contacts: Sequence[Mapping[str, Any]]
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(steps, poses, points, record)`` of :class:`ContactTrack` from an engine-task
    output's ``contacts``."""
    return ContactTrack._of([int(record["step"]) for record in contacts],
                            [record["points"] for record in contacts],
                            [record["bodies"] for record in contacts])._arrays


def _record_arrays(contact_record) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(steps, poses, points, record)`` of :class:`ContactTrack` from an engine run's raw
    record ``(shift, raw)``."""
    (shift_x, shift_y), raw = contact_record
    steps = np.fromiter((step for step, _, _ in raw), np.int64, len(raw))
    counts = [len(contacts[0]) for _, contacts, _ in raw]
    bodies = len(raw[0][2]) if raw else 0
    # every point is (x, y, depth) and every pose (x, y, θ): each read as one flat run
    points = np.fromiter(chain.from_iterable(chain.from_iterable(
        contacts[0] for _, contacts, _ in raw)), float, 3 * sum(counts)).reshape(-1, 3)
    poses = np.fromiter(chain.from_iterable(chain.from_iterable(
        poses for _, _, poses in raw)), float, 3 * bodies * len(raw))
    poses = poses.reshape(len(raw), bodies, 3)
    shift = np.array([shift_x, shift_y])
    points[:, :2] -= shift
    poses[:, :, :2] -= shift
    return steps, poses, points, np.repeat(np.arange(len(raw)), counts)


def as_track(contacts: Sequence[StepContacts] | ContactTrack) -> ContactTrack:
    return contacts if isinstance(contacts, ContactTrack) else ContactTrack.from_steps(contacts)


_FIRST, _SECOND, _THIRD = itemgetter(0), itemgetter(1), itemgetter(2)


def records_many(contact_records: Sequence) -> tuple[np.ndarray, ...]:
    """Many runs' raw contact records ``(shift, raw)`` (``EngineRun.contact_record``) as flat
    arrays in the scene frame, read in a few passes over all of them (not run by run).

    Returns ``(poses, points, record_of_point, run_of_record, run_of_point, point_counts)``:
    ``poses`` ``(R, 2, 3)`` every record's bodies' ``(x, y, θ)`` (a one-body run's second
    body NaN), ``points`` ``(P, 3)`` every point's ``(x, y, depth)``, run by run and record by
    record in order, the record (row of ``poses``) and run of each point, the run of each
    record, and ``(runs,)`` each run's number of points. The numbers of :class:`ContactTrack`
    (the same subtraction of each run's shift).
    """
    raws = [raw for _, raw in contact_records]
    record_counts = np.fromiter(map(len, raws), np.int64, len(raws))
    every = list(chain.from_iterable(raws))
    # (step, contacts, poses) records: contacts[0] the points (C-level getters, not a loop)
    point_lists = list(map(_FIRST, map(_SECOND, every)))
    pose_lists = list(map(_THIRD, every))
    per_record = np.fromiter(map(len, point_lists), np.int64, len(every))
    total = int(per_record.sum())
    # every point is (x, y, depth) and every pose (x, y, θ): each read as one flat run
    points = np.fromiter(chain.from_iterable(chain.from_iterable(point_lists)), float,
                         3 * total).reshape(-1, 3)
    bodies = np.fromiter(map(len, pose_lists), np.int64, len(every))
    rows = np.fromiter(chain.from_iterable(chain.from_iterable(pose_lists)), float,
                       3 * int(bodies.sum())).reshape(-1, 3)
    run_of_record = np.repeat(np.arange(len(raws)), record_counts)
    record_of_point = np.repeat(np.arange(len(every)), per_record)
    run_of_point = run_of_record[record_of_point]
    shifts = np.array([shift for shift, _ in contact_records], dtype=float).reshape(-1, 2)
    points[:, :2] -= shifts[run_of_point]
    record_of_row = np.repeat(np.arange(len(every)), bodies)
    rows[:, :2] -= shifts[run_of_record[record_of_row]]
    first_rows = np.cumsum(bodies) - bodies
    poses = np.full((len(every), 2, 3), np.nan)
    poses[record_of_row, np.arange(len(rows)) - first_rows[record_of_row]] = rows
    point_counts = np.bincount(run_of_point, minlength=len(raws))
    return poses, points, record_of_point, run_of_record, run_of_point, point_counts


__all__ = ["ContactTrack", "StepContacts", "as_track", "records_many"]
