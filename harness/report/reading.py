"""Reading a results file for the report: its records built only when something asks.

A warm report of 1,000 scenarios finds nearly every piece it shows in its caches (the
figures' digests, :mod:`harness.report.fragments`): what it needs of the records is then
their digests per scenario, their order and the engines and presets present, all of which
the record lines of the file give without building a record. Parsing and building the
28,000 records (:func:`harness.run.records.read_results`) was a third of such a report.

:func:`read_for_report` reads the file's bytes and returns a :class:`LazyResults`, which
builds the records (by :func:`~harness.run.records.read_results`, which checks them) the
first time anything asks for them, so that what it gives never depends on what was cached.
It does so only when the file is laid out as :func:`~harness.run.records.write_results`
writes it (one record per line, each starting with its scenario, point, source, law and
preset) and of this harness's format; any other file is read in full at once.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from harness import inputs
from harness.run.records import (
    ANALYTIC,
    FORMAT,
    FORMAT_VERSION,
    RECORDS_END,
    RECORDS_START,
    Results,
    read_results,
    results_head,
)

#: How a record's line starts when its scenario, point, source and preset hold no escape (and
#: the point's label no brace): the scenario, the source and the preset (or None), then the
#: speeds before and after (lists of numbers, or null: a record without them is no record of
#: this format). Scenario names cannot hold an escape (the scenario schema's name pattern);
#: any other file is read in full (and :func:`~harness.run.records.read_results` says what
#: is wrong with it).
_LINE_HEAD = (rb'\{"scenario":"([^"\\]*)","point":\{[^{}]*\},"source":"([^"\\]*)",'
              rb'"law":(?:null|"[^"\\]*"),"preset":(?:null|"([^"\\]*)"),'
              rb'"u_before":(?:null|\[[^\[\]{}"]*\]),"u_after":(?:null|\[[^\[\]{}"]*\]),')
_LINE_HEAD_AT = re.compile(_LINE_HEAD)


#: What a record decided, as its line says it (a field of the record or of its diagnostics):
#: which record it is (scenario, point, source, law, preset) and its status, verdict and
#: collision type. Integers are taken whole and no float is (the lookahead), strings without
#: escapes only (none of these fields has one).
DECIDED_TEXT = re.compile(
    r'"(?:scenario|index|label|source|law|preset|status|verdict|collision_type)":'
    r'(?:"[^"\\]*"|null|true|false|-?\d+(?![.\deE]))')
_DECIDED_BYTES = re.compile(DECIDED_TEXT.pattern.encode())
#: What every record of a run was made from, in its provenance: the code that the cached
#: values depend on, the installed versions and the engines' settings. Not the machine, the
#: time, the executor or the cache's statistics.
RUN_INPUTS = ("code_version", "versions", "engine_versions", "engine_settings",
              "settings_overrides", "history", "task_time_limit_s")
#: What the runner says of a scenario that is not what its records were made from: where its
#: file is (a clone elsewhere is the same scenario) and its references (results, worked out
#: from the file and the code like the records).
NOT_INPUTS = ("path", "references")


def scenario_digest(lines) -> str:
    """The digest of what one scenario's record lines (``str`` or ``bytes``, in run order)
    decided: the sha256 of their :data:`DECIDED_TEXT` -- which records there are, their
    statuses, verdicts and collision types -- and nothing else of them.

    Never of their floats: their last bits depend on the CPU (BLAS, libm and SIMD kernels),
    and a fresh clone on another machine must find the committed figures current. The floats
    follow from what the records were made from, the scenario's file, the code, the installed
    versions and the settings (:func:`inputs_digests`, which :func:`with_inputs` adds); the
    decided fields are there for a run that ends otherwise from the same inputs (a fault, a
    time limit)."""
    if lines and isinstance(lines[0], str):
        found = DECIDED_TEXT.findall("\n".join(lines))
        return hashlib.sha256("\n".join(found).encode()).hexdigest()
    return hashlib.sha256(b"\n".join(_DECIDED_BYTES.findall(b"\n".join(lines)))).hexdigest()


def inputs_digests(provenance: dict, scenarios: dict) -> dict[str, str]:
    """``{scenario: digest of what its records were made from}``: the run's
    :data:`RUN_INPUTS` and what the runner says of the scenario but :data:`NOT_INPUTS` --
    its definition's digest (:attr:`harness.scenarios.Scenario.definition_digest`: every
    field of its file), laws, sweep, gates and descriptions."""
    run = {key: provenance.get(key) for key in RUN_INPUTS}
    # The settings the engines ran with are the code's (code_version) and the overrides
    # given (kept exactly); the floats of those worked out (libm) are left out.
    settings = _FLOAT_TEXT.sub("", json.dumps(run.pop("engine_settings"), sort_keys=True))
    run_text = json.dumps([run, settings], sort_keys=True, default=str)
    digests = {}
    for name, info in scenarios.items():
        described = {key: value for key, value in info.items() if key not in NOT_INPUTS}
        text = json.dumps([run_text, name, described], sort_keys=True, default=str)
        digests[name] = hashlib.sha256(text.encode()).hexdigest()
    return digests


#: A float as JSON writes it (``repr``: a point or an exponent).
_FLOAT_TEXT = re.compile(r"-?\d+\.\d+(?:[eE][+-]?\d+)?|-?\d+[eE][+-]?\d+|-?Infinity|NaN")


def with_inputs(decided: dict[str, str], inputs: dict[str, str]) -> dict[str, str]:
    """Each scenario's digest: that of what its records decided (:func:`scenario_digest`)
    with that of what they were made from (:func:`inputs_digests`; empty for a scenario the
    results do not describe)."""
    return {name: hashlib.sha256(f"{inputs.get(name, '')}\0{digest}".encode()).hexdigest()
            for name, digest in decided.items()}


class LazyResults:
    """:class:`harness.run.records.Results` as the report reads it: ``provenance``,
    ``scenarios``, the scenario of every record in order, each scenario's digest and the
    ``(source, preset)`` pairs present come from the file's lines; anything else (``records``,
    ``for_scenario`` ...) from the records, read in full the first time it is asked for."""

    def __init__(self, path: Path, status: os.stat_result, document: dict, data: bytes,
                 lines: _Lines, scenarios_digest: str | None = None):
        self.path = path
        self.provenance = document.get("provenance", {})
        self.scenarios = document.get("scenarios", {})
        self.record_scenarios = lines.names
        self.scenarios_digest = scenarios_digest
        self._data = data  # the file, where the lines' spans are
        self._segments = lines.segments
        self._pairs = lines.pairs
        self._status = status
        self._results: Results | None = None

    def scenario_digests(self, known: Callable[[str, Callable[[], str]], str] | None = None
                         ) -> dict[str, str]:
        """``{scenario: digest of its records}``: :func:`scenario_digest`'s of its lines,
        :func:`with_inputs`.

        ``known(key, make)``, when given, returns the digest kept under ``key`` -- a digest
        of the scenario's lines exactly as they are, volatile fields included -- or else
        ``make()``: a report of the very file it read last hashes its text once, without
        taking the volatile fields out.
        """
        digests = {}
        view = memoryview(self._data)
        for name, segments in self._segments.items():
            def make(segments=segments) -> str:
                text = b"\n".join(view[start:end] for start, end in segments)
                return scenario_digest(text.replace(b",\n", b"\n").split(b"\n"))

            if known is None:
                digests[name] = make()
                continue
            exact = hashlib.sha256()
            for index, (start, end) in enumerate(segments):
                exact.update(view[start:end] if index == 0 else b"\n" + view[start:end])
            digests[name] = known(f"digest\0{exact.hexdigest()}", make)
        return with_inputs(digests, inputs_digests(self.provenance, self.scenarios))

    def full(self) -> Results:
        """The results with their records (read once)."""
        if self._results is None:
            results = read_results(self.path)
            status = self.path.stat()
            if (status.st_size, status.st_mtime_ns, status.st_ino) != (
                    self._status.st_size, self._status.st_mtime_ns, self._status.st_ino):
                raise ValueError(f"{self.path}: the results file changed while being read")
            self._results = results
        return self._results

    @property
    def loaded(self) -> bool:
        """Whether the records were read."""
        return self._results is not None

    @property
    def records(self) -> list:
        return self.full().records

    def scenario_names(self) -> list[str]:
        """Scenario names in run order."""
        return list(dict.fromkeys(self.record_scenarios))

    def source_presets(self) -> frozenset:
        """The ``(source, preset)`` pairs of the records (analytic ones included)."""
        return self._pairs

    def __getattr__(self, name: str):
        if name.startswith("__"):  # copy, pickle: not the records' Results
            raise AttributeError(name)
        return getattr(self.full(), name)


def read_for_report(path: Path | str) -> LazyResults | Results:
    """The results in ``path`` for :func:`harness.report.write_report`: a
    :class:`LazyResults` when the file is as ``write_results`` writes it, else
    :func:`~harness.run.records.read_results`'s (which raises its errors)."""
    path = Path(path)
    try:  # a regular file of bounded size only (read_results then says what else it is)
        data, status = inputs.read_bytes_and_status(path, cap_name="max_results_bytes")
    except (OSError, inputs.InputError):
        data = b""
    lazy = _lazy(path, status, data) if data else None
    return read_results(path) if lazy is None else lazy


def _lazy(path: Path, status: os.stat_result, data: bytes) -> LazyResults | None:
    """:class:`LazyResults` from the file's bytes, None when they are not laid out as
    expected (or not this harness's format: :func:`read_results` then says why)."""
    document = results_head(data)
    if (document is None or document.get("format") != FORMAT
            or document.get("format_version") != FORMAT_VERSION):
        return None
    start = data.find(RECORDS_START.encode())  # found: results_head found it
    begin, end = start + len(RECORDS_START), len(data) - len(RECORDS_END)  # the record lines
    count = data.count(b"\n", begin, end) + 1 if end > begin else 0
    lines = _lines(data, begin, end, count)
    if lines is None:
        return None
    # write_results puts the scenarios last in the head, after a newline only structure has:
    # their text is what a digest of them needs (else one of their JSON is made)
    at = data.rfind(b'\n "scenarios": {', 0, start)
    return LazyResults(path, status, document, data, lines,
                       None if at < 0 else hashlib.sha256(data[at:start]).hexdigest())


@dataclass
class _Lines:
    """The record lines of a results file: the scenario of each, where each scenario's lines
    are in the file's records (``[start, end)`` byte spans of consecutive lines, separated by
    ``",\\n"`` as in the file) and the ``(source, preset)`` pairs present."""

    names: list[str]
    segments: dict[str, list[tuple[int, int]]]
    pairs: frozenset


def _segments(names: list[str], starts: list[int], end: int
              ) -> dict[str, list[tuple[int, int]]]:
    """Each scenario's spans of consecutive lines, from the lines' scenarios and starts and
    where the last line ends."""
    segments: dict[str, list[tuple[int, int]]] = {}
    previous = None
    for index, name in enumerate(names):
        stop = starts[index + 1] - 2 if index + 1 < len(starts) else end
        if name == previous:
            spans = segments[name]
            spans[-1] = (spans[-1][0], stop)
        else:
            segments.setdefault(name, []).append((starts[index], stop))
            previous = name
    return segments


def _lines(data: bytes, begin: int, end: int, count: int) -> _Lines | None:
    """:class:`_Lines` of the ``count`` record lines in ``data[begin:end]``, found by their
    newlines (a raw newline only ends a line), when every line starts as :data:`_LINE_HEAD`
    reads (no escape in the scenario, source or preset, a point without braces in its
    label); else None."""
    starts = [begin]
    find = data.find
    at = find(b"\n", begin, end)
    while at >= 0 and len(starts) < count:
        starts.append(at + 1)
        at = find(b"\n", at + 1, end)
    if at >= 0 or len(starts) != count or any(data[start - 2] != 44 for start in starts[1:]):
        return None  # 44: the comma before each newline
    match = _LINE_HEAD_AT.match
    heads = [match(data, at, end) for at in starts]
    if None in heads:
        return None
    names = [str(head[1], "utf-8") for head in heads]
    pairs = frozenset((str(source, "utf-8"), None if preset is None else str(preset, "utf-8"))
                      for source, preset in {(head[2], head[3]) for head in heads})
    return _Lines(names, _segments(names, starts, end), pairs)


def scenarios_digest(results) -> str:
    """A digest of ``results.scenarios`` (what the runner says of each scenario): of their
    text in the file when the report read it (:class:`LazyResults`), else of their JSON."""
    if isinstance(results, LazyResults) and results.scenarios_digest is not None:
        return results.scenarios_digest
    text = json.dumps(results.scenarios, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def record_scenarios(results) -> list[str]:
    """The scenario of every record, in order (from the lines when ``results`` has them)."""
    known = getattr(results, "record_scenarios", None)
    if isinstance(known, list):
        return known
    return [record.scenario for record in results.records]


def source_presets(results) -> frozenset:
    """The ``(source, preset)`` pairs of the records, engine ones only."""
    known = getattr(results, "source_presets", None)
    pairs = known() if callable(known) else {(r.source, r.preset) for r in results.records}
    return frozenset(pair for pair in pairs if pair[0] != ANALYTIC)


__all__ = ["DECIDED_TEXT", "NOT_INPUTS", "RUN_INPUTS", "LazyResults", "inputs_digests",
           "read_for_report", "record_scenarios", "scenario_digest", "with_inputs",
           "scenarios_digest", "source_presets"]
