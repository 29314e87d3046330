"""Every sample through an engine and preset, and the engines' bare stepping of the same impacts.

:func:`run_engine` is the survey's only call into the engines: it hands the scenes to
``Engine.run_many`` (harness/engines/contract.py), which runs many impacts per engine world
where the adapter can (pymunk, pybullet, Box2D) and one by one elsewhere, with the same
result bit for bit.
Every run is then judged by the verdict checks (:func:`harness.run.verdicts.judge`): a run
is one impact only if it fails none, and its ``status`` is the first failing reason.
A scene the engine cannot build is recorded :data:`SKIPPED`; a scene whose run raises is
recorded :data:`ERROR` with the exception's type and first line (``errors``), as
``impact-harness run`` records an engine's exception, and the other runs go on: the call
that raised is run again scene by scene, so every other scene's run is a lone run's, bit for
bit (``run_many`` equals ``run`` scene by scene). What the
checks need of a scene alone (:func:`harness.run.verdicts.prepare`) is worked out once for
every engine and preset.

:func:`bare_stepping` times, for the same scenes, the engine's own stepping with the
benchmark's bare steppers (harness/bench/engines.py): the same step call as the adapter in a
tight loop, from the adapter's start state, the reset outside (``bare_s``) and inside
(``bare_reset_s``) the timed region.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from harness.collector import collector_paused
from harness.engines import STATUSES, UnsupportedScene, load_engine
from harness.run import verdicts
from harness.survey.laws import WIDTH

#: Scenes handed to ``run_many`` at once: the runs (with their contact records) of one slice
#: are judged and dropped before the next, so memory does not grow with the survey.
SLICE = 2048
#: ``status`` and ``engine_status`` of a run the engine cannot build (``UnsupportedScene``:
#: Box2D's polygons of more than ``b2_maxPolygonVertices`` sides), as ``run`` records such a
#: task ``skipped``; the statistics leave these runs out and count them (``n_skipped``).
SKIPPED = "skipped"
#: ``status`` and ``engine_status`` of a run whose engine raised (anything raised inside
#: ``Engine.run_many``: the adapter's code and the engine's library alike, as ``run``
#: records it ``error: …``; a bug of the survey's own code, outside that call, stops the
#: survey instead: exit status 3). NaN speeds; left out of the statistics and counted
#: (``n_error``), listed with its reason in the summary; the survey exits 4.
ERROR = "error"


@dataclass(frozen=True)
class EngineResults:
    """One engine and preset over every sample (``n`` rows)."""

    engine: str
    engine_version: str
    preset: str
    velocities: np.ndarray  # (n, 6) post-impact speeds, padded like ContactTerms.u
    engine_status: np.ndarray  # (n,) str, the engine's own status (harness.engines.STATUSES)
    status: np.ndarray  # (n,) str, "ok" or the first failing verdict reason (verdicts.REASONS)
    reasons: np.ndarray  # (n,) str, every failing verdict reason, comma-separated ("" if none)
    steps: np.ndarray  # (n,) steps simulated
    wall_s: float  # s, engine runs only (run_many)
    judge_s: float  # s, the verdict checks
    skipped_why: str = ""  # the engine's message for the first skipped run ("" if none)
    errors: np.ndarray | None = None  # (n,) str, "Type: first line" of an ERROR run, else ""

    def __post_init__(self) -> None:
        if self.errors is None:
            object.__setattr__(self, "errors", np.full(len(self.status), "", dtype=str))


def run_engine(engine_name: str, preset: str, scenes, problems=None,
               law_energy_change=None, terms=None, arrays=None,
               overrides: dict | None = None) -> EngineResults:
    """Run every scene through ``engine_name`` at ``preset`` and judge every run.

    ``problems``: each scene's ``ImpactProblem`` (the verdicts' input; None: not judged, the
    status is the engine's); ``law_energy_change``: newton-lcp's energy change per scene (J),
    to attribute an energy gain to the law (docs/verdicts.md); ``terms``: the scenes'
    :func:`harness.run.verdicts.prepare` and ``arrays`` their
    :func:`harness.run.verdicts.term_arrays` (worked out here when None); ``overrides``:
    settings changed from the preset (``--set``). The runs are judged slice by slice with
    :func:`harness.run.verdicts.judge_many`, :func:`judge`'s verdicts.
    """
    engine = load_engine(engine_name)
    # one dict for every run: the adapters cache on it
    settings = engine.settings(preset, overrides)
    count = len(scenes)
    velocities = np.zeros((count, WIDTH))
    engine_status = np.empty(count, dtype=object)
    status = np.empty(count, dtype=object)
    reasons = np.full(count, "", dtype=object)
    errors = np.full(count, "", dtype=object)
    steps = np.zeros(count, dtype=np.int64)
    wall = judging = 0.0
    skipped_why = ""
    clock = time.perf_counter
    if problems is not None and (terms is None or arrays is None):
        tick = clock()
        terms = verdicts.prepare_many(scenes, problems) if terms is None else terms
        arrays = verdicts.term_arrays(problems, terms) if arrays is None else arrays
        judging += clock() - tick
    # The collector stays off while the slices' runs live, and they are dropped inside: it
    # would walk every tuple of their contact records (tens per MuJoCo run), freeing none.
    with collector_paused():
        for begin in range(0, count, SLICE):
            tick = clock()
            end = min(count, begin + SLICE)
            built, runs, why, raised = _run_supported(engine, scenes, begin, end, settings)
            skipped_why = skipped_why or why
            wall += clock() - tick
            tick = clock()
            if len(built) < end - begin:  # judge the runs that were built, alone
                for row in sorted(set(range(begin, end)) - set(built)):
                    velocities[row] = np.nan
                    engine_status[row] = status[row] = ERROR if row in raised else SKIPPED
                    errors[row] = raised.get(row, "")
                _judge(built, runs, scenes, problems, law_energy_change, terms, arrays,
                       velocities, engine_status, status, reasons, steps)
                judging += clock() - tick
                del runs
                continue
            for row, run in enumerate(runs, start=begin):
                speeds = run.velocities
                velocities[row, :3 * len(speeds)] = [value for body in speeds for value in body]
                engine_status[row] = run.status.value
                steps[row] = run.steps
            if problems is None:
                status[begin:end] = engine_status[begin:end]
            else:
                judged = verdicts.judge_many(
                    scenes[begin:end], problems[begin:end], runs, velocities[begin:end],
                    terms[begin:end], arrays.rows(begin, end),
                    law_energy_change=(None if law_energy_change is None
                                       else law_energy_change[begin:end]))
                for row, (verdict_status, names) in enumerate(judged, start=begin):
                    status[row], reasons[row] = verdict_status, names
            judging += clock() - tick
            del runs
    assert set(engine_status) <= {*STATUSES, SKIPPED, ERROR}, set(engine_status) - set(STATUSES)
    return EngineResults(engine_name, engine.version, preset, velocities,
                         engine_status.astype(str), status.astype(str), reasons.astype(str),
                         steps, wall, judging, skipped_why, errors.astype(str))


#: A message's first line longer than this is cut after its first sentence.
ERROR_TEXT_CHARACTERS = 160


def error_text(error: BaseException) -> str:
    """An engine's exception as a run's reason: its type and the first line of its message,
    only its first sentence where that line is long (Drake's 'failed to converge' goes on
    for 600 characters of advice in its first line, and for lines after it)."""
    lines = str(error).strip().splitlines()
    if not lines:
        return type(error).__name__
    first = lines[0]
    if len(first) > ERROR_TEXT_CHARACTERS:
        sentence, stop, _ = first.partition(". ")
        # a line opening with ". " keeps its text: its "first sentence" would say nothing
        first = sentence + "." if stop and sentence.strip() else first
    return f"{type(error).__name__}: {first}"


def _run_supported(engine, scenes, begin: int, end: int, settings):
    """``(rows, runs, why, errors)``: ``run_many`` of scenes ``begin`` to ``end``; when it
    raises (for the whole call: a scene the engine refuses, :class:`UnsupportedScene`, or an
    exception of the engine), every scene is run alone and those refused or raising are left
    out of ``rows`` (``why``: the first refusal; ``errors``: ``{row: error_text}`` of those
    that raised). ``MemoryError`` is not a scene's fault and stops the survey."""
    try:
        return list(range(begin, end)), engine.run_many(scenes[begin:end], settings), "", {}
    except MemoryError:
        raise
    except Exception:  # noqa: BLE001 - UnsupportedScene or the engine's: each scene alone
        pass
    rows, runs, why, errors = [], [], "", {}
    for row in range(begin, end):
        try:
            runs += engine.run_many([scenes[row]], settings)
        except UnsupportedScene as error:
            why = why or f"engine cannot build the scene: {error}"
            continue
        except MemoryError:
            raise
        except Exception as error:  # noqa: BLE001 - the engine's: recorded, never dropped
            errors[row] = error_text(error)
            continue
        rows.append(row)
    return rows, runs, why, errors


def _judge(rows, runs, scenes, problems, law_energy_change, terms, arrays, velocities,
           engine_status, status, reasons, steps) -> None:
    """Fill the rows ``rows`` (not consecutive: skipped ones between) from their ``runs``."""
    for row, run in zip(rows, runs):
        speeds = run.velocities
        velocities[row, :3 * len(speeds)] = [value for body in speeds for value in body]
        engine_status[row] = run.status.value
        steps[row] = run.steps
    if not rows:
        return
    if problems is None:
        status[rows] = engine_status[rows]
        return
    index = np.asarray(rows)
    judged = verdicts.judge_many(
        [scenes[row] for row in rows], [problems[row] for row in rows], runs, velocities[index],
        [terms[row] for row in rows],
        type(arrays)(*(getattr(arrays, name)[index] for name in arrays.__dataclass_fields__)),
        law_energy_change=None if law_energy_change is None else law_energy_change[index])
    for row, (verdict_status, names) in zip(rows, judged):
        status[row], reasons[row] = verdict_status, names


def bare_stepping(engine_name: str, preset: str, scenes, steps,
                  overrides: dict | None = None) -> dict[str, float]:
    """Seconds of bare stepping of ``scenes`` (``steps[i]`` steps each, as the adapter took).

    Returns ``{"bare_s": …, "bare_reset_s": …, "impacts": n}``: the sums over the scenes of
    one timed pass each (the survey's impacts are all different, so there is no best-of).
    Each scene's stepper (``Engine.bare_stepper``, the benchmark's: a world of its own) is
    closed after its pass: a pybullet world holds tens of MB.
    """
    engine = load_engine(engine_name)
    settings = engine.settings(preset, overrides)
    clock = time.perf_counter
    bare = bare_reset = 0.0
    for scene, count in zip(scenes, steps):
        stepper = engine.bare_stepper(scene, settings)
        try:
            stepper.reset()
            begin = clock()
            stepper.step(int(count))
            bare += clock() - begin
            begin = clock()
            stepper.reset()
            stepper.step(int(count))
            bare_reset += clock() - begin
        finally:
            stepper.close()
    return {"bare_s": bare, "bare_reset_s": bare_reset, "impacts": len(scenes)}
