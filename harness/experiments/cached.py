"""What ``impact-harness experiments`` and ``calibrate`` computed, kept in the result cache
(:class:`harness.store.cache.ResultCache`, where engine runs are kept), and the progress
they print while computing it.

An entry is keyed by everything its numbers depend on: the command and its settings, the
SHA-256 of the data files read (none without a copy), the installed versions, the engines
registered at run time (their source), the code of ``harness/experiments``
(:func:`experiments_code`) and, through the
cache's own code version, ``planar_impact``, the engines, the scene, the verdicts and the
store. It holds plain JSON only (the text the command printed, and its ``--json``
document): never a per-drop number beyond what the command prints, as the Fazeli data carry
no licence. A rerun with nothing changed reads it back in well under a second; any change
computes it again. An unreadable or edited entry is a miss (the cache checks its SHA-256).
"""

from __future__ import annotations

import contextlib
import hashlib
import inspect
import io
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from harness.engines import ENGINE_NAMES, engine_class, engine_names
from harness.run.provenance import package_versions
from harness.store.cache import ResultCache
from harness.store.identity import code_version_of

#: Bump when what an entry holds changes.
ENTRY_LAYOUT = 1
#: A stage that may take longer than this (s) says so on stderr when it starts; a loop of
#: many short steps (a calibration's cells) says where it is at most this often.
PROGRESS_EVERY_S = 2.0


def experiments_code() -> str:
    """SHA-256 of ``harness/experiments``' source (the cache's code version covers the rest
    of what the numbers depend on)."""
    return code_version_of((Path(__file__).resolve().parent,))


def payload(command: str, settings: dict, data_sha256: dict | None) -> dict:
    """The key's payload: ``settings`` of ``command`` with the data, code and versions.
    An engine registered at run time (not a shipped module, so not in the cache's code
    version) is named by the SHA-256 of its class's source file."""
    return {"layout": ENTRY_LAYOUT, "command": command, "settings": settings,
            "data_sha256": data_sha256, "versions": package_versions(),
            "engines_registered": {name: _registered_source(name) for name in engine_names()
                                   if name not in ENGINE_NAMES},
            "experiments_code": experiments_code()}


def _registered_source(name: str) -> str:
    """SHA-256 of the source file of run-time engine ``name``'s class (its module and
    name when the file cannot be read)."""
    registered = engine_class(name)
    try:
        return hashlib.sha256(Path(inspect.getfile(registered)).read_bytes()).hexdigest()
    except (OSError, TypeError):
        return f"{registered.__module__}.{registered.__qualname__}"


class _Tee(io.TextIOBase):
    """Text written to the real stdout and kept."""

    def __init__(self, stream) -> None:
        self.stream, self.kept = stream, io.StringIO()

    def writable(self) -> bool:
        return True

    def write(self, text: str) -> int:
        self.kept.write(text)
        return self.stream.write(text)

    def flush(self) -> None:
        self.stream.flush()


def printed_once(cache: ResultCache | None, key_payload: dict,
                 compute: Callable[[], dict], progress: Callable[[str], None],
                 echo: bool = True) -> dict:
    """``{"text": what compute printed, **compute()}``: from the cache when ``key_payload``
    was computed before (its text printed again), else computed (its printing shown as it
    goes and kept) and stored. ``cache`` None: always computed, nothing stored. ``echo``
    False: the text is kept, never printed."""
    key = None if cache is None else cache.key(key_payload)
    if key is not None:
        found = cache.get(key, _check, count=False)
        if found is not None:
            progress(f"read from the cache (computed in {found['seconds']:.0f} s; "
                     "--no-cache computes it again)")
            if echo:
                sys.stdout.write(found["text"])
            return found
    tee = _Tee(sys.stdout if echo else io.StringIO())
    started = time.perf_counter()
    with contextlib.redirect_stdout(tee):
        result = compute()
    found = {**result, "text": tee.kept.getvalue(), "seconds": time.perf_counter() - started}
    if key is not None:
        try:
            cache.put(key, found)
        except OSError as error:  # the results are printed already: only the reuse is lost
            progress(f"not kept in the cache ({error.strerror or error})")
    return found


#: The entry both the report's aggregates (:func:`harness.experiments.aggregates.compute`)
#: and ``impact-harness experiments`` make of the engines on the drops: every engine and
#: preset on every drop at the headline fit, beside that law (the command's table "The
#: engines on the drops"), and every engine and law at its fitted or calibrated settings
#: (:func:`harness.experiments.calibrated_errors.compute` without its curves). The two
#: compute it from the same inputs, which its key names; whichever runs first keeps it, the
#: other reads it (``findings --check`` after a suite, whose report made it). Aggregates
#: only, as the command prints them and its ``--json`` holds them: no per-drop number.
ENGINES_ON_DROPS = "engines-on-drops"


def engines_on_drops_payload(data_sha256: dict, frame: str, fit: dict, law_fits: dict,
                             engines: list, seed: int, calibration_drops: int,
                             replicates: int) -> dict:
    """The key's payload of the :data:`ENGINES_ON_DROPS` entry: the drops (their files'
    SHA-256, the frame of their post-impact speeds), the headline fit the engines run at
    (``{"law", "objective", "mu", "e"}``), each law's fit ``{law: [mu, e]}`` (the laws'
    rows), the engines and presets in order ``[[engine, preset], ...]``, the seed of the
    split and the bootstrap, the calibration's drops and the bootstrap's replicates; the
    code and versions through :func:`payload`."""
    settings = {"frame": frame, "fit": fit, "law_fits": law_fits, "engines": engines,
                "seed": seed, "calibration_drops": calibration_drops,
                "replicates": replicates}
    return payload(ENGINES_ON_DROPS, json_plain(settings), data_sha256)


def engines_on_drops_get(cache: ResultCache | None, key_payload: dict) -> dict | None:
    """The kept entry ``{"rows", "calibrated", "seconds"}`` of ``key_payload``, or None
    (no cache, never computed, or not believed: the cache's seal and checksum)."""
    if cache is None:
        return None
    return cache.get(cache.key(key_payload), _check_engines_on_drops, count=False)


def engines_on_drops_put(cache: ResultCache | None, key_payload: dict, rows: list,
                         calibrated: dict, seconds: float,
                         progress: Callable[[str], None] = lambda text: None) -> dict:
    """``{"rows", "calibrated", "seconds"}`` as plain JSON, kept under ``key_payload``
    (when there is a cache; a failed write, said through ``progress``, loses only the
    reuse) and returned."""
    entry = json_plain({"rows": rows, "calibrated": calibrated, "seconds": seconds})
    if cache is not None:
        try:
            cache.put(cache.key(key_payload), entry)
        except OSError as error:
            progress(f"the engines on the drops not kept in the cache "
                     f"({error.strerror or error})")
    return entry


def _check_engines_on_drops(record: dict) -> str | None:
    if not (isinstance(record.get("rows"), list) and isinstance(record.get("calibrated"), dict)
            and isinstance(record.get("seconds"), int | float)):
        return "not an engines-on-drops entry"
    return None


def json_plain(value):
    """``value`` as plain JSON (dicts, lists, floats, ...): dataclasses as dicts (their
    arrays of 64 or more values left out), numpy arrays as lists, numpy scalars as
    Python's."""
    return json.loads(json.dumps(value, default=_plain))


def _plain(value):
    if hasattr(value, "__dataclass_fields__"):
        return {k: getattr(value, k) for k in value.__dataclass_fields__
                if not isinstance(getattr(value, k), np.ndarray) or getattr(value, k).size < 64}
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON: {type(value).__name__}")


def _check(record: dict) -> str | None:
    if not isinstance(record.get("text"), str) or not isinstance(record.get("seconds"),
                                                                 int | float):
        return "not an experiments entry"
    return None


def cache_problem(cache: ResultCache | None) -> str | None:
    """Why the cache's directory cannot be used (checked before any work), or None."""
    return None if cache is None else cache.prepare()


class Progress:
    """Progress lines on stderr, ``<command>: <text>``: :meth:`stage` at once (a stage that
    may take seconds), :meth:`step` at most every :data:`PROGRESS_EVERY_S` seconds."""

    def __init__(self, command: str, stream=None) -> None:
        self.command, self.stream = command, stream
        self._last = time.perf_counter()

    def stage(self, text: str) -> None:
        print(f"{self.command}: {text}", file=self.stream or sys.stderr, flush=True)
        self._last = time.perf_counter()

    __call__ = stage

    def step(self, text: str) -> None:
        if time.perf_counter() - self._last >= PROGRESS_EVERY_S:
            self.stage(text)


__all__ = ["ENGINES_ON_DROPS", "ENTRY_LAYOUT", "PROGRESS_EVERY_S", "Progress", "cache_problem",
           "engines_on_drops_get", "engines_on_drops_payload", "engines_on_drops_put",
           "experiments_code", "json_plain", "payload", "printed_once"]
