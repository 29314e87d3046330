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
    # Largest cache entry read (bytes): a larger one is a miss, computed again. The
    # library's largest (a scenario's records with their histories) is about 1 MB.
    "max_cache_entry_bytes": 2**30,
}


#: How far the environment may move each limit: ``(lowest, highest)`` (a byte count beyond
#: what a read can take overflowed; NaN or a word was an internal error).
LIMIT_RANGES: dict[str, tuple[float, float]] = {
    "max_sweep_points": (1, 10_000_000),
    "max_engine_steps": (1, 1e12),
    "min_time_step": (1e-12, 1.0),
    "max_solver_iterations": (1, 1e12),  # the tests raise it to run a runaway engine
    "max_input_bytes": (1, 2**40),
    "max_results_bytes": (1, 2**40),
    "max_cache_entry_bytes": (1, 2**40),
}


def environment_problem() -> str | None:
    """Why a limit set in the environment (``IMPACT_HARNESS_<NAME>``) cannot be used, or
    None: each must be a number within :data:`LIMIT_RANGES`. Checked before any work."""
    for name in LIMITS:
        variable = f"IMPACT_HARNESS_{name.upper()}"
        text = os.environ.get(variable)
        if not text:
            continue
        low, high = LIMIT_RANGES[name]
        try:
            value = float(text) if len(text) <= 40 else math.nan
        except ValueError:
            value = math.nan
        if not low <= value <= high:  # NaN fails it too
            return (f"{variable}={text[:40]!r}: not a number within the range allowed; "
                    f"allowed: {_spelled(low)} <= value <= {_spelled(high)}")
    return None


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
    nonzero: bool = False  # 0 itself is refused (MuJoCo's solref entries)
    #: For a list of numbers: each entry's own bound, in order (``low``/``high`` unused).
    elements: tuple[Bound, ...] | None = None
    unit: str = ""
    words: tuple[str, ...] = ()  # names the knob also takes instead of a number ("auto")

    def range(self) -> tuple[float, float]:
        return (limit(self.low) if isinstance(self.low, str) else self.low,
                limit(self.high) if isinstance(self.high, str) else self.high)

    def allowed(self) -> str:
        if self.elements is not None:
            return (f"a list of {len(self.elements)} numbers: "
                    + "; ".join(f"[{i}] {entry.allowed()}"
                                for i, entry in enumerate(self.elements))
                    + "".join(f'; or "{word}"' for word in self.words))
        low, high = (_spelled(end) for end in self.range())
        kind = "an integer" if self.integer else "a number"
        relation = "<" if self.low_open else "<="
        raise_it = [f"IMPACT_HARNESS_{end.upper()}" for end in (self.low, self.high)
                    if isinstance(end, str)]
        return (f"{kind}, {low} {relation} value <= {high}"
                + (f" {self.unit}" if self.unit else "") + (", not 0" if self.nonzero else "")
                + "".join(f', or "{word}"' for word in self.words)
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
    # lengths in metres: at most the largest length a scene holds (1e2 m, the scenario
    # files' magnitudes, scenarios/schema.py MAGNITUDES)
    "collision_slop": Bound(0, 100, unit="m", why="pymunk's allowed overlap"),
    "contact_breaking_threshold": Bound(0, 100, unit="m"),
    "contact_slop": Bound(0, 100, unit="m"),
    "margin": Bound(0, 100, unit="m", why="MuJoCo's contact margin (1e300 overflowed)"),
    "polygon_radius": Bound(0, 100, unit="m"),
    "detection_overlap": Bound(0, 1, why="Box2D: a fraction of the largest body's extent"),
    # fractions
    "collision_bias": Bound(0, 1, why="pymunk: the overlap left after 1 s"),
    "damping": Bound(0, 1, why="pymunk: the velocity kept after 1 s (1: none lost)"),
    "linear_damping": Bound(0, 1),
    "angular_damping": Bound(0, 1),
    "contact_erp": Bound(0, 1),
    "erp": Bound(0, 1),
    "friction_erp": Bound(0, 1),
    "warm_starting_factor": Bound(0, 1),
    "global_cfm": Bound(0, 1),
    "tolerance": Bound(0, 1),
    "noslip_tolerance": Bound(0, 1),
    "solver_residual_threshold": Bound(0, 1e3),
    "restitution_velocity_threshold": Bound(0, 1e3, unit="m/s"),
    "impratio": Bound(0, 1e4, low_open=True),
    # counts
    "collision_persistence": Bound(0, 1000, integer=True, why="steps a contact is kept"),
    "num_sub_steps": Bound(0, 1000, integer=True,
                           why="pybullet's substeps per step, each solved (1e9 never ended)"),
    # scales of Box2D's units (its tolerances are tuned for 0.1 ... 10 m)
    "length_scale": Bound(2**-20, 2**20, why="Box2D metres per scene metre (1e300 "
                          "overflowed); powers of 2 are exact"),
    "velocity_scale": Bound(2**-20, 2**20, words=("auto",)),
    # MuJoCo's soft contact: solref [timeconst, dampratio] (or [-stiffness, -damping]) and
    # solimp [dmin, dmax, width, midpoint, power] (mujoco.readthedocs.io, 'Solver parameters')
    "solref": Bound(0, 0, words=("restitution",), elements=(
        Bound(-1e9, 10, nonzero=True, why="timeconst (s), or -stiffness"),
        Bound(-1e9, 1e3, nonzero=True, why="dampratio, or -damping"))),
    "solimp": Bound(0, 0, elements=(
        Bound(1e-4, 0.9999), Bound(1e-4, 0.9999), Bound(0, 1, unit="m"),
        Bound(1e-4, 0.9999), Bound(1, 100))),
    # Drake's point contact (drake.mit.edu, MultibodyPlantConfig; harness/engines/drake)
    "penetration_allowance": Bound(0, 100, low_open=True, unit="m",
                                   why="Drake: the overlap its default stiffness allows"),
    "stiction_tolerance": Bound(0, 1e3, low_open=True, unit="m/s",
                                why="Drake: the slip speed below which friction sticks"),
    "hunt_crossley_dissipation": Bound(0, 1e6, unit="s/m", words=("restitution",),
                                       why="Drake: d of the Hunt–Crossley force; "
                                           "\"restitution\" derives it from e"),
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
    # other commands' counts
    "count": Bound(1, 10_000_000, integer=True,
                   why="findings' random problems; 100,000 by default take seconds"),
    "show": Bound(0, 1_000_000, integer=True, why="rows printed"),
    "older-than": Bound(0, 36_500, why="days, a century at most"),
    "repeats": Bound(1, 1000, integer=True, why="a benchmark's repetitions"),
    # population files
    "sides": Bound(3, 64, integer=True,
                   why="a regular polygon; beyond 64 sides it is a disk to the engines"),
    "max_attempts": Bound(1, 100_000, integer=True,
                          why="draws per sample before the population is refused"),
}


def problem(knob: str, value) -> str | None:
    """Why ``value`` is out of the bounds of ``knob`` (``"out of range; allowed: ..."``), or
    None when it is within them or ``knob`` has none. A value of the wrong type is left to
    the knob's own check (which says what type it takes)."""
    bound = BOUNDS.get(knob)
    if bound is None:
        return None
    if bound.elements is not None:
        if not isinstance(value, (list, tuple)):
            return None  # a string ("restitution") or another type: the knob's own check
        if len(value) != len(bound.elements) or any(
                not _within(entry, item) for entry, item in zip(bound.elements, value)):
            return f"out of range; allowed: {bound.allowed()}"
        return None
    if _within(bound, value):
        return None
    return f"out of range; allowed: {bound.allowed()}"


def _within(bound: Bound, value) -> bool:
    """Whether ``value`` is inside ``bound`` (a value that is not a number is: its knob's
    own check says what type it takes)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return True
    low, high = bound.range()
    if bound.integer and isinstance(value, float) and value.is_integer():
        value = int(value) if math.isfinite(value) else value
    inside = (math.isfinite(value) and (value > low if bound.low_open else value >= low)
              and value <= high and not (bound.nonzero and value == 0))
    return inside and (not bound.integer or isinstance(value, numbers.Integral))


class OutOfBounds(ValueError):
    """A knob's value outside :data:`BOUNDS`: one line naming the source, the key, the
    value and the allowed range."""


def check(source: str, knob: str, value) -> None:
    """Raise :class:`OutOfBounds` when ``value`` is outside the bounds of ``knob``;
    ``source`` says where it was set (``"--samples"``, ``"--set pymunk.iterations=..."``)."""
    reason = problem(knob, value)
    if reason is not None:
        raise OutOfBounds(f"{source}: {knob} = {value!r}: {reason}")


def option(knob: str):
    """An ``argparse`` ``type`` for the command-line option of ``knob``: the text read as
    a number (an integer for an integer knob; ``1e3`` is 1000), within :data:`BOUNDS`;
    otherwise ``argparse.ArgumentTypeError`` whose message is a sentence saying what was
    given and what is allowed (argparse prints it after the option's name and exits 2)."""
    import argparse  # only the command line needs it

    bound = BOUNDS[knob]

    def parse(text: str):
        value = _number(text, bound.integer)
        reason = None if value is None else problem(knob, value)
        if value is None or reason is not None:
            raise argparse.ArgumentTypeError(
                f"{_shown(text)} is {'not a number' if value is None else 'out of range'}; "
                f"allowed: {bound.allowed()}")
        return value

    parse.__name__ = knob  # what argparse names in its own messages
    return parse


def _number(text: str, integer: bool):
    """``text`` as an int (``integer``: also a float's text holding a whole number) or a
    float, or None when it is neither (or a whole number of more digits than any bound)."""
    text = text.strip()
    if len(text) > 40:  # no bound has so many digits; int() of thousands is slow
        return None
    try:
        return int(text)
    except ValueError:
        pass
    try:
        value = float(text)
    except ValueError:
        return None
    if integer and math.isfinite(value) and value.is_integer():
        return int(value)
    return value


def _shown(text: str) -> str:
    """The user's text, cut short when long."""
    return repr(text if len(text) <= 40 else text[:37] + "...")


__all__ = ["BOUNDS", "LIMITS", "LIMIT_RANGES", "Bound", "OutOfBounds", "check",
           "environment_problem", "limit", "option", "problem"]
