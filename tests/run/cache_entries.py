"""A result-cache entry file (``<key>.json``: a header line, then the record's JSON) read and
written by hand, for tests that damage or inspect entries.

What these write is sealed with the cache's own key (:mod:`harness.store.sealing`): it
stands for damage the seal cannot tell (a bug of the harness writing a bad record), so the
checksums and the record checks behind the seal are what the tests reach. A forgery without
the key is ``tests/store/test_sealing.py``'s."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from harness.store.sealing import Seal


def _sealed(path: Path, header: dict) -> dict:
    """``header`` sealed with the key of the cache holding ``path`` (in a shard or packs)."""
    return Seal(Path(path).parent.parent).sealed(header)


def read_entry(path: Path) -> tuple[dict, dict]:
    """``(header, record)`` of an entry file, unchecked."""
    head, _, body = Path(path).read_bytes().partition(b"\n")
    return json.loads(head), json.loads(body)


def write_entry(path: Path, header: dict, record, *, sign: bool = True) -> None:
    """Write an entry file; ``sign``: with the SHA-256 of the new record (an entry whose
    content is bad but whole), else with the header's checksum as it is (an edited entry)."""
    body = json.dumps(record).encode("utf-8")
    if sign:
        header = {**header, "sha256": hashlib.sha256(body).hexdigest()}
    header = _sealed(path, header)
    Path(path).write_bytes(json.dumps(header).encode("utf-8") + b"\n" + body)


def read_pack(path: Path) -> tuple[dict, list[bytes]]:
    """``(header, bodies)`` of a pack (``packs/<sha256>.pack``), unchecked: each record's
    JSON as stored."""
    head, _, rest = Path(path).read_bytes().partition(b"\n")
    header = json.loads(head)
    bodies, offset = [], 0
    for size in header["sizes"]:
        bodies.append(rest[offset:offset + size])
        offset += size
    return header, bodies


def write_pack(path: Path, header: dict, bodies: list[bytes], *, sign: bool = True) -> None:
    """Write a pack of ``bodies`` (its sizes always updated: the pack stays whole); ``sign``:
    with their SHA-256 (records whose content is bad but whole), else with the header's
    checksums as they are (edited records)."""
    header = {**header, "sizes": [len(body) for body in bodies]}
    if sign:
        header["sha256"] = [hashlib.sha256(body).hexdigest() for body in bodies]
    header = _sealed(path, header)
    Path(path).write_bytes(json.dumps(header).encode("utf-8") + b"\n" + b"".join(bodies))


def stored_records(root: Path) -> list[tuple[Path, int | None, dict]]:
    """Every record the cache at ``root`` holds outside its scenarios' ``.jsonl`` entries:
    ``(file, index in its pack or None for a single entry, record)``, unreadable ones left
    out."""
    found = []
    for path in sorted(Path(root).glob("??/*.json")):
        try:
            found.append((path, None, read_entry(path)[1]))
        except (OSError, ValueError):
            continue
    for path in sorted(Path(root).glob("packs/*.pack")):
        try:
            _, bodies = read_pack(path)
            found += [(path, index, json.loads(body)) for index, body in enumerate(bodies)]
        except (OSError, ValueError, KeyError):
            continue
    return found


def engine_run_records(root: Path) -> list[tuple[Path, int | None, dict]]:
    """The :func:`stored_records` that are engine runs (they hold velocities)."""
    return [entry for entry in stored_records(root)
            if isinstance(entry[2], dict) and "velocities" in entry[2]]


def replace_record(path: Path, index: int | None, body: bytes, *, sign: bool = True) -> None:
    """Replace one stored record's JSON by ``body`` (in its pack, or its single entry)."""
    if index is None:
        header = json.loads(Path(path).read_bytes().partition(b"\n")[0])
        if sign:
            header["sha256"] = hashlib.sha256(body).hexdigest()
        header = _sealed(path, header)
        Path(path).write_bytes(json.dumps(header).encode("utf-8") + b"\n" + body)
        return
    header, bodies = read_pack(path)
    bodies[index] = body
    write_pack(path, header, bodies, sign=sign)
