"""A result-cache entry file (``<key>.json``: a header line, then the record's JSON) read and
written by hand, for tests that damage or inspect entries."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path


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
    Path(path).write_bytes(json.dumps(header).encode("utf-8") + b"\n" + body)
