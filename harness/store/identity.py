"""What names a stored result: the canonical JSON text of what it depends on, and the
version of the code that computed it.

A result cache's key (:class:`harness.store.cache.ResultCache`) is the SHA-256 of
:func:`canonical_json` of a payload (sorted keys, exact floats, dataclasses as their fields)
with :func:`code_version` (the SHA-256 of the source the stored values depend on,
:data:`CACHED_CODE`): the same inputs and code spell the same text on every machine, and a
change to that code names every result anew. A value many keys hold (a point's scene, in the
key of each of its engine runs) is spelled once (:class:`Spelled`).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import secrets
from collections.abc import Mapping
from dataclasses import fields, is_dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import planar_impact

_HARNESS_DIR = Path(__file__).resolve().parent.parent  # harness/, from harness/store/
#: The harness source (directories and files, relative to ``harness/``) that the cached
#: values depend on: the store (the keys' spelling, the entries' layout), the engine runs (the
#: adapters, the scene they build, ``engine_task`` in ``run/tasks.py``), the several-contact
#: references (the references, the event-driven solver, the departures they hold) and each
#: scenario's finished records (the scenario model, the runner, metrics, contact histories,
#: verdicts, the record layout). Add a module here when
#: a cached value starts to depend on it; a listed path that is missing is an error, never
#: silently skipped.
CACHED_CODE: tuple[str, ...] = (
    "__init__.py", "store", "engines", "scene", "reference", "scenarios", "run/__init__.py",
    "run/tasks.py", "run/plan.py", "run/point_records.py", "run/gates.py",
    "run/scenario_records.py", "run/runner.py", "run/references.py", "run/metrics.py",
    "run/verdicts", "run/history.py", "run/records.py",
)


def cached_code_sources(harness_dir: Path = _HARNESS_DIR,
                        planar_impact_dir: Path | None = None) -> tuple[Path, ...]:
    """The source paths :func:`code_version` hashes: ``planar_impact`` (beside ``harness/``
    under ``src/``, else the imported package) and :data:`CACHED_CODE` under ``harness_dir``."""
    if planar_impact_dir is None:
        planar_impact_dir = harness_dir.parent / "src" / "planar_impact"
        if not planar_impact_dir.is_dir():  # installed (non-editable): the imported package
            planar_impact_dir = Path(planar_impact.__file__).resolve().parent
    return (planar_impact_dir, *(harness_dir / name for name in CACHED_CODE))


@lru_cache(maxsize=None)
def code_version_of(sources: tuple[Path, ...]) -> str:
    """sha256 over the ``*.py`` files of ``sources`` (directories, recursively, or files),
    each named by its path from the source's parent."""
    digest = hashlib.sha256()
    for source in sources:
        if source.is_file():
            files = [source]
        elif source.is_dir():
            files = sorted(path for path in source.rglob("*.py")
                           if "__pycache__" not in path.parts)
        else:
            raise FileNotFoundError(f"{source}: listed in the cached code, but missing")
        for path in files:
            name = (f"{source.parent.name}/{source.name}" if path is source
                    else path.relative_to(source.parent).as_posix())
            digest.update(name.encode())
            digest.update(b"\0")
            digest.update(path.read_bytes())
            digest.update(b"\0")
    return digest.hexdigest()


def code_version() -> str:
    """sha256 of the source the cached values depend on (:func:`cached_code_sources`).

    Computed once per process (the source does not change under a running process).
    """
    return code_version_of(cached_code_sources())


class Spelled:
    """A value spelled once as canonical JSON (:attr:`text`), for the payloads of many keys
    that hold it (a point's scene, in the key of each of its engine runs): a key's text holds
    it exactly as if the value itself were in the payload."""

    __slots__ = ("text",)

    def __init__(self, value: Any) -> None:
        self.text = canonical_json(value)


#: The stand-in of a :class:`Spelled` value while its payload is spelled around it: a string
#: no payload holds (random), which json writes as it is (letters and digits only).
_SPELLED_MARK = f"spelled{secrets.token_hex(16)}"


def _canonical_default(value: Any) -> Any:
    """The JSON-able form of a value json does not know: numpy values as lists or numbers,
    paths as POSIX text, dataclasses as their fields, read-only mappings as dicts; a
    :class:`Spelled` value as :data:`_SPELLED_MARK` (:func:`canonical_json` splices its text
    in)."""
    if isinstance(value, Spelled):
        return _SPELLED_MARK
    if hasattr(value, "tolist"):  # numpy scalars and arrays
        return value.tolist()
    if isinstance(value, Path):
        return value.as_posix()
    if is_dataclass(value) and not isinstance(value, type):
        return {f.name: getattr(value, f.name) for f in fields(value)}
    if isinstance(value, Mapping):
        return dict(value)
    raise TypeError(
        f"cache payload holds a value that is not JSON-able: {type(value).__name__} {value!r}"
    )


def canonical_json(payload: Any) -> str:
    """Canonical JSON text: sorted keys, no spaces, floats exact (``repr``; a non-finite one
    spelled ``NaN`` or ``Infinity``: a key's text, never read back), dataclasses as their
    fields; written by json's C encoder (a task's scene and settings are hashed for every
    engine run). A :class:`Spelled` value is its text, spliced in where json wrote its
    stand-in (in the order json met them)."""
    spelled: list[str] = []

    def default(value: Any) -> Any:
        if isinstance(value, Spelled):
            spelled.append(value.text)
        return _canonical_default(value)

    text = json.dumps(payload, sort_keys=True, separators=(",", ":"), default=default)
    if not spelled:
        return text
    pieces = text.split(f'"{_SPELLED_MARK}"')
    if len(pieces) != len(spelled) + 1:  # cannot be: the stand-in is random
        raise ValueError("a payload holds the stand-in of a spelled value")
    return "".join(itertools.chain.from_iterable(zip(pieces, [*spelled, ""])))


__all__ = ["CACHED_CODE", "Spelled", "cached_code_sources", "canonical_json", "code_version",
           "code_version_of"]
