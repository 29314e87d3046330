"""The bounds of every knob a user sets, in one table, whichever way it is set.

An engine setting may come from a scenario file's ``[engine_settings]``, from ``--set
ENGINE.KEY=VALUE`` or from the Python API (``Engine.settings``); a command's size from its
options (``--samples``, ``--workers``, ``--seed``, ``--chunk-size``); a polygon's ``sides``
from a population file. Each path reads :data:`BOUNDS` here, so a value refused one way is
refused every way, with one line naming where it came from, the key, the value and the
allowed range (:func:`problem`, :func:`check`).

Shared by the scenarios, the engines, the run and the survey, which must not depend on each
other for it (as :mod:`harness.processes`).
"""

from __future__ import annotations

import math
import numbers
import os
from dataclasses import dataclass

#: Bounds on the work one file may ask for; each can be raised with the environment variable
#: ``IMPACT_HARNESS_<NAME>`` (e.g. ``IMPACT_HARNESS_MAX_SWEEP_POINTS=5000``).
LIMITS: dict[str, float] = {
    # Every point is checked (geometry, solver) when read, then run on every engine and
    # preset: 1000 points take about a minute to run; the library's largest sweep has 11.
    "max_sweep_points": 1000,
    # Engine step cap (settings max_steps, and approach_steps): the library's largest is
    # 20000 (MuJoCo).
    "max_engine_steps": 1_000_000,
    # Smallest engine time step (s); the library's smallest is 1e-5 (MuJoCo accurate).
    "min_time_step": 1e-7,
    # Most iterations of an engine's solver per step: the library's largest is 100; a run
    # costs iterations x steps.
    "max_solver_iterations": 10_000,
    # Largest scenario or population file read (bytes): the library's largest is 3 kB.
    "max_input_bytes": 4 * 2**20,
    # Largest results file read (bytes): the library's is about 2 MB, a 1,000-file run's 40.
    "max_results_bytes": 2**31,
}


def limit(name: str) -> float:
    """``LIMITS[name]``, or the value of ``IMPACT_HARNESS_<NAME>`` when set and a number."""
    text = os.environ.get(f"IMPACT_HARNESS_{name.upper()}")
    if text:
        try:
            value = float(text)
        except ValueError:
            raise ValueError(f"IMPACT_HARNESS_{name.upper()}={text!r}: not a number") from None
        if value > 0:
            return value
    return LIMITS[name]


def _spelled(number: float) -> str:
    """A bound as the user would type it: whole numbers in full (4294967295), others short."""
    if float(number).is_integer() and abs(number) < 1e16:
        return str(int(number))
    return f"{number:g}"


@dataclass(frozen=True)
class Bound:
    """``low <= value <= high`` (``low < value`` when ``low_open``), an integer when
    ``integer``. ``low`` or ``high`` may name a :data:`LIMITS` entry (raised through the
    environment); ``why`` says where the numbers come from."""

    low: float | str
    high: float | str
    integer: bool = False
    low_open: bool = False
    why: str = ""

    def range(self) -> tuple[float, float]:
        return (limit(self.low) if isinstance(self.low, str) else self.low,
                limit(self.high) if isinstance(self.high, str) else self.high)

    def allowed(self) -> str:
        low, high = (_spelled(end) for end in self.range())
        kind = "an integer" if self.integer else "a number"
        relation = "<" if self.low_open else "<="
        raise_it = [f"IMPACT_HARNESS_{end.upper()}" for end in (self.low, self.high)
                    if isinstance(end, str)]
        return (f"{kind}, {low} {relation} value <= {high}"
                + (f" ({', '.join(raise_it)} changes it)" if raise_it else ""))


#: The bounds, by knob: an engine setting by its key (the same for every engine that has
#: it), a command-line option by its name without dashes, a population key by its name.
BOUNDS: dict[str, Bound] = {
    # engine settings (harness/engines/contract.py and each adapter's own checks)
    "time_step": Bound("min_time_step", 1.0, low_open=True,
                       why="a step below it makes a run of millions of steps"),
    "max_steps": Bound(1, "max_engine_steps", integer=True),
    "approach_steps": Bound(0, "max_engine_steps",
                            why="steps of free flight before the touch, each stepped"),
    "iterations": Bound(1, "max_solver_iterations", integer=True),
    "velocity_iterations": Bound(1, "max_solver_iterations", integer=True),
    "position_iterations": Bound(0, "max_solver_iterations", integer=True),
    "num_solver_iterations": Bound(1, "max_solver_iterations", integer=True),
    "ls_iterations": Bound(1, "max_solver_iterations", integer=True),
    "noslip_iterations": Bound(0, "max_solver_iterations", integer=True),
    "contact_steps": Bound(1, "max_engine_steps"),
    # command-line options
    "samples": Bound(1, 1_000_000, integer=True,
                     why="samples per population; 2,000 by default, 10^6 takes minutes"),
    "workers": Bound(1, 1024, integer=True),
    "seed": Bound(0, 2**32 - 1, integer=True, why="numpy's seeds"),
    "chunk-size": Bound(1, 100_000, integer=True),
    "task-time-limit": Bound(0, 86_400, low_open=True, why="seconds, a day at most"),
    # experiments and calibrate (harness/experiments): counts of drops and resamples
    "replicates": Bound(10, 10_000, integer=True,
                        why="bootstrap resamples; experiments refits every law on each (200 "
                            "by default, 10,000 take tens of minutes)"),
    "drops": Bound(2, 5_000, integer=True,
                   why="impacts calibrate runs per cell of its grid (12 by default; the "
                       "measured set has 1,718; MuJoCo's grid has 27 cells)"),
    "law-mu": Bound(0, 100,
                    why="the friction coefficient calibrate's target law runs at"),
    "law-e": Bound(0, 1, why="the restitution coefficient calibrate's target law runs at"),
    # population files
    "sides": Bound(3, 64, integer=True,
                   why="a regular polygon; beyond 64 sides it is a disk to the engines"),
}


def problem(knob: str, value) -> str | None:
    """Why ``value`` is out of the bounds of ``knob`` (``"out of range; allowed: ..."``), or
    None when it is within them or ``knob`` has none. A value of the wrong type is left to
    the knob's own check (which says what type it takes)."""
    bound = BOUNDS.get(knob)
    if bound is None or isinstance(value, bool) or not isinstance(value, numbers.Real):
        return None
    low, high = bound.range()
    if bound.integer and isinstance(value, float) and value.is_integer():
        value = int(value) if math.isfinite(value) else value
    inside = (math.isfinite(value) and (value > low if bound.low_open else value >= low)
              and value <= high)
    if inside and (not bound.integer or isinstance(value, numbers.Integral)):
        return None
    return f"out of range; allowed: {bound.allowed()}"


class OutOfBounds(ValueError):
    """A knob's value outside :data:`BOUNDS`: one line naming the source, the key, the
    value and the allowed range."""


def check(source: str, knob: str, value) -> None:
    """Raise :class:`OutOfBounds` when ``value`` is outside the bounds of ``knob``;
    ``source`` says where it was set (``"--samples"``, ``"--set pymunk.iterations=..."``)."""
    reason = problem(knob, value)
    if reason is not None:
        raise OutOfBounds(f"{source}: {knob} = {value!r}: {reason}")


__all__ = ["BOUNDS", "LIMITS", "Bound", "OutOfBounds", "check", "limit", "problem"]
