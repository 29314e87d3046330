"""Content-addressed cache of results: rerunning an unchanged suite does no engine work.

A record is stored under the key ``sha256(canonical JSON of the payload + code version)``,
where the payload names everything the result depends on (scenario, sweep point, engine and
its version, settings ...) and :func:`code_version` hashes the source of ``planar_impact``
and ``harness`` (engines included), so any code change invalidates every entry::

    cache = ResultCache()                     # .cache/results, or enabled=False for --no-cache
    key = cache.key({"scenario": name, "point": 3, "engine": "pymunk", "version": v, "settings": s})
    record = cache.get(key)
    if record is None:
        record = simulate(...)
        cache.put(key, record)

Files: one JSON file per key at ``root/<key[:2]>/<key>.json``, written atomically (a
temporary file in the same directory, then ``os.replace``), so concurrent writers and an
interrupted run never leave a half-written entry. An unreadable or corrupted file is a miss.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import tempfile
from functools import lru_cache
from pathlib import Path
from typing import Any

_HARNESS_DIR = Path(__file__).resolve().parent.parent  # harness/, from harness/run/
_SOURCE_DIRS: tuple[Path, ...] = (_HARNESS_DIR.parent / "src" / "planar_impact", _HARNESS_DIR)

CACHE_FORMAT = 1  # bump when the record layout changes


def _source_dirs() -> tuple[Path, ...]:
    dirs = list(_SOURCE_DIRS)
    if not dirs[0].is_dir():  # installed (non-editable): use the imported package's location
        import planar_impact

        dirs[0] = Path(planar_impact.__file__).resolve().parent
    return tuple(dirs)


@lru_cache(maxsize=None)
def _code_version_of(dirs: tuple[Path, ...]) -> str:
    digest = hashlib.sha256()
    for directory in dirs:
        for path in sorted(directory.rglob("*.py")):
            if "__pycache__" in path.parts:
                continue
            digest.update(path.relative_to(directory.parent).as_posix().encode())
            digest.update(b"\0")
            digest.update(path.read_bytes())
            digest.update(b"\0")
    return digest.hexdigest()


def code_version() -> str:
    """sha256 of the source of ``planar_impact`` and ``harness`` (engines included).

    Computed once per process (the source does not change under a running process).
    """
    return _code_version_of(_source_dirs())


def _canonical(value: Any) -> Any:
    """JSON-able form of ``value`` with a single spelling per value (floats by ``repr``)."""
    if isinstance(value, dict):
        return {str(key): _canonical(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_canonical(item) for item in value]
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        # repr round-trips exactly; non-finite values are not JSON
        return {"float": repr(value)} if not math.isfinite(value) else value
    if hasattr(value, "tolist"):  # numpy scalars and arrays
        return _canonical(value.tolist())
    if isinstance(value, Path):
        return value.as_posix()
    raise TypeError(f"cache payload holds a value that is not JSON-able: {type(value).__name__} {value!r}")


def canonical_json(payload: Any) -> str:
    """Canonical JSON text: sorted keys, no spaces, floats exact."""
    return json.dumps(_canonical(payload), sort_keys=True, separators=(",", ":"), allow_nan=False)


class ResultCache:
    """Results on disk, keyed by a content hash of what they depend on.

    Parameters
    ----------
    root
        Directory of the cache (created on the first ``put``).
    enabled
        ``False`` (the runner's ``--no-cache``): ``get`` always misses, ``put`` writes nothing.
    version
        Code version mixed into every key (default: :func:`code_version`); tests pass their own.
    """

    def __init__(self, root: Path | str = Path(".cache/results"), enabled: bool = True,
                 version: str | None = None):
        self.root = Path(root)
        self.enabled = bool(enabled)
        self.version = code_version() if version is None else version
        self.hits = 0
        self.misses = 0

    def key(self, payload: dict) -> str:
        """sha256 hex of the canonical JSON of ``payload`` plus the code version."""
        text = canonical_json({"payload": payload, "code_version": self.version, "format": CACHE_FORMAT})
        return hashlib.sha256(text.encode()).hexdigest()

    def path(self, key: str) -> Path:
        return self.root / key[:2] / f"{key}.json"

    def get(self, key: str) -> dict | None:
        """The stored record, or ``None`` (a miss) when absent, disabled or unreadable."""
        if not self.enabled:
            self.misses += 1
            return None
        try:
            with open(self.path(key), encoding="utf-8") as handle:
                stored = json.load(handle)
            if not isinstance(stored, dict) or stored.get("key") != key or not isinstance(stored.get("record"), dict):
                raise ValueError("not a cache entry")
        except (OSError, ValueError):
            self.misses += 1
            return None
        self.hits += 1
        return stored["record"]

    def put(self, key: str, record: dict) -> None:
        """Store ``record`` (JSON-able dict) under ``key``; atomic; no-op when disabled."""
        if not self.enabled:
            return
        path = self.path(key)
        path.parent.mkdir(parents=True, exist_ok=True)
        text = json.dumps({"key": key, "record": record}, default=_json_default)
        descriptor, temporary = tempfile.mkstemp(prefix=f".{key[:8]}-", suffix=".tmp", dir=path.parent)
        try:
            with os.fdopen(descriptor, "w", encoding="utf-8") as handle:
                handle.write(text)
            os.replace(temporary, path)
        except BaseException:
            try:
                os.unlink(temporary)
            except OSError:
                pass
            raise

    @property
    def stats(self) -> dict:
        total = self.hits + self.misses
        return {"enabled": self.enabled, "hits": self.hits, "misses": self.misses,
                "hit_rate": self.hits / total if total else 0.0}


def _json_default(value: Any) -> Any:
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, Path):
        return value.as_posix()
    raise TypeError(f"cache record holds a value that is not JSON-able: {type(value).__name__}")


__all__ = ["ResultCache", "canonical_json", "code_version"]
