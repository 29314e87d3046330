"""Result records of a validation run and the versioned JSON file that holds them.

One :class:`Record` per (scenario, sweep point, source), where the source is ``"analytic"``
(one record per law) or an engine (one record per preset). The results file is::

    {
      "format": "impact-harness-results",
      "format_version": 1,
      "provenance": {...},     # versions, settings per engine and preset, commit, machine, time
      "scenarios": {...},      # per scenario: description, tags, sweep, speed labels, gates
      "records": [{...}, ...]  # Record.as_dict(), in run order
    }

Floats are written by ``repr`` (exact round trip); non-finite values (an engine that blew up)
are written as ``null`` and the record's ``status`` says why. Each scenario's info and each
record is one line of compact JSON.

Beside the file, :func:`write_results` keeps its *companion*, ``<name>.pickle``
(:func:`companion_path`): the same records pickled as plain values, which
:func:`read_results` loads several times faster than it parses the JSON, and uses only while
the JSON file is the very one it was written with. The JSON stays the results (``compare``,
any other reader); the companion can be deleted at no cost but speed.

Record fields (units SI):

``scenario``, ``point`` (``{"index", "parameter", "value", "label"}``), ``source``,
``law`` (analytic records) or ``preset`` (engine records), ``u_before`` and ``u_after``
(``(v_x, v_y, ω)`` of each body in file order, or a generalized system's own speeds),
``vn_approach``, ``vt_approach``, ``vn_separation``, ``vt_separation`` (contact velocities,
m/s, in the scene's ``t = (n_y, −n_x)``), ``energy_change`` (J), ``collision_type``
(Poisson/Stronge numbering 1–5 for those laws; 1 stick, 2 reverse sliding, 3 forward sliding
for the Newton laws and for engines, classified from the end state), ``normal_impulse``,
``tangential_impulse`` (N s on body B), ``status`` (``"ok"``, an engine status of
:data:`harness.engines.STATUSES`, ``"skipped: <reason>"`` or ``"error: <reason>"``),
``wall_time_s``, ``departure`` (``{law: ‖u − u_law‖_M / s}``, ``s`` the frame-free scale of
:func:`harness.run.metrics.frame_free_scale`; an engine record at a flat face or a tilt holds
only the references that apply there, by name, :func:`harness.run.references.applicable`,
never the single-contact laws), ``cached`` (engine records: the result came
from the cache), ``diagnostics`` (engine records: steps, contact points, penetration, drift,
the engine's own impulses, settings overrides), ``verdict`` (engine records with output:
``"single-impact"`` or ``"flagged"``) and ``reasons`` (each check the run fails, or a
law-attributed energy gain: ``{name, value, tolerance, detail, attribution, fails}``; see
:mod:`harness.run.verdicts`). A flagged run's ``status`` is never ``"ok"``: it is the
engine's status, or the first failing reason's name.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import pickle
import tempfile
from dataclasses import asdict, dataclass, field, fields, is_dataclass
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

from harness.collector import collector_paused
from harness.run.files import write_parts_atomically

FORMAT = "impact-harness-results"
FORMAT_VERSION = 1
DEFAULT_RESULTS = Path("reports") / "results.json"
ANALYTIC = "analytic"
#: Between two record lines of a results file (a line never holds a raw newline).
LINE_SEPARATOR = ",\n"


@dataclass
class Record:
    """One (scenario, sweep point, source) result; see the module docstring for the fields."""

    scenario: str
    point: dict
    source: str  # "analytic" or the engine name
    law: str | None = None  # analytic records
    preset: str | None = None  # engine records
    u_before: list | None = None
    u_after: list | None = None
    vn_approach: float | None = None  # m/s
    vt_approach: float | None = None  # m/s
    vn_separation: float | None = None  # m/s
    vt_separation: float | None = None  # m/s
    energy_change: float | None = None  # J
    collision_type: int | None = None
    normal_impulse: float | None = None  # N s, on body B
    tangential_impulse: float | None = None  # N s, along t
    status: str = "ok"
    wall_time_s: float = 0.0  # s
    departure: dict = field(default_factory=dict)  # law -> relative KE-norm error
    cached: bool = False
    diagnostics: dict | None = None
    verdict: str | None = None  # engine records: "single-impact" | "flagged"
    reasons: list = field(default_factory=list)  # engine records: verdicts.Reason dicts

    @property
    def label(self) -> str:
        """``"poisson"`` for a law, ``"pymunk.accurate"`` for an engine run: the engine and
        the name it shows for the run's preset role (``"mujoco.matched-bounce"``)."""
        from harness.engines import source_label

        return self.law if self.source == ANALYTIC else source_label(self.source, self.preset)

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    @property
    def skipped(self) -> bool:
        return self.status.startswith("skipped")

    @property
    def failing_reasons(self) -> list[str]:
        """Names of the verdict's failing reasons (empty for a single impact)."""
        return [r["name"] for r in self.reasons if r.get("fails", True)]

    def as_dict(self) -> dict:
        # A shallow dict of the fields: plain_value copies the nested values anyway, so
        # dataclasses.asdict's deep copy (most of the time of writing a results file) is waste.
        return plain_value({name: getattr(self, name) for name in _RECORD_FIELDS})

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Record":
        if cls is Record and data.keys() == _FIELD_SET:
            # A record as written (every field, nothing else): its values as they are, without
            # the keyword call and the filter, which were most of reading a results file.
            record = object.__new__(Record)
            record.__dict__.update(data)
            return record
        names = _FIELD_SET if cls is Record else {f.name for f in fields(cls)}
        return cls(**{key: value for key, value in data.items() if key in names})


_RECORD_FIELDS = tuple(f.name for f in fields(Record))
_FIELD_SET = frozenset(_RECORD_FIELDS)  # from_dict's filter: fields() per record was slow


@dataclass
class Results:
    """A results file in memory."""

    records: list[Record]
    provenance: dict = field(default_factory=dict)
    scenarios: dict = field(default_factory=dict)  # name -> description, tags, speed labels …
    # scenario -> its records, built on first use; rebuilt when ``records`` is replaced or
    # changes length (a report asks once per scenario and figure: a scan each was quadratic).
    _by_scenario: tuple = field(default=(None, 0, {}), init=False, repr=False, compare=False)
    _present: tuple = field(default=(None, 0, frozenset()), init=False, repr=False,
                            compare=False)
    # (records, length, lines) as read_results found them: each record's line in the file.
    _lines: tuple = field(default=(None, 0, None), init=False, repr=False, compare=False)

    def record_lines(self) -> list[str] | None:
        """Each record's line in the results file it was read from (:func:`record_line`'s
        text), parallel to :attr:`records`; None for results built in memory, or once
        ``records`` was replaced or changed length since."""
        records, length, lines = self._lines
        if records is self.records and length == len(self.records):
            return lines
        return None

    def scenario_names(self) -> list[str]:
        """Scenario names in run order."""
        return list(self._scenario_index())

    def for_scenario(self, name: str) -> list[Record]:
        """The records of scenario ``name``, in run order."""
        return list(self._scenario_index().get(name, ()))

    def _scenario_index(self) -> dict[str, list[Record]]:
        records, length, index = self._by_scenario
        if records is not self.records or length != len(self.records):
            index = {}
            for record in self.records:
                index.setdefault(record.scenario, []).append(record)
            self._by_scenario = (self.records, len(self.records), index)
        return index

    def engine_labels(self) -> list[str]:
        """``engine.preset`` labels present, engines in registry order, ``defaults`` first."""
        from harness.engines import source_label

        return [source_label(e, p) for e, p in self.engine_roles()]

    def engine_roles(self) -> list[tuple[str, str]]:
        """``(engine, preset role)`` pairs present, in :meth:`engine_labels`' order."""
        from harness.scenarios import ENGINES, PRESETS

        present = self._engine_runs()
        return [(e, p) for p in PRESETS for e in ENGINES if (e, p) in present]

    def _engine_runs(self) -> frozenset:
        """The ``(engine, preset)`` pairs of the records, found once per records list (a
        report asks a dozen times, a scan of every record each)."""
        records, length, present = self._present
        if records is not self.records or length != len(self.records):
            present = frozenset((r.source, r.preset) for r in self.records
                                if r.source != ANALYTIC)
            self._present = (self.records, len(self.records), present)
        return present


_PLAIN = (str, int, bool, type(None))


def plain_value(value: Any) -> Any:
    """Plain JSON values of the built-in types only (what the JSON reads back, and all a
    results file's companion may hold); non-finite floats become None, numpy values and
    subclasses of str, int and float plain Python, nested dataclasses dicts."""
    kind = type(value)
    if kind is float:  # the common cases first, by exact type: a results file has millions
        return value if math.isfinite(value) else None
    if kind in _PLAIN:
        return value
    if isinstance(value, dict):
        if set(map(type, value)) <= _STR:  # the keys as they are: str(key) is key
            flat = _flat(value.values())
            if flat is not None:
                return dict(zip(value, flat))
        return {str(key): plain_value(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        flat = _flat(value)
        return flat if flat is not None else [plain_value(item) for item in value]
    if isinstance(value, str):  # a str subclass (an engine's Status): its plain text
        return value[:]
    if hasattr(value, "tolist") and not isinstance(value, bytes):
        return plain_value(value.tolist())
    if isinstance(value, float):  # subclasses as plain floats, as in the JSON
        return float(value) if math.isfinite(value) else None
    if isinstance(value, int) and not isinstance(value, bool):
        return int(value)
    if isinstance(value, Path):
        return value.as_posix()
    if is_dataclass(value) and not isinstance(value, type):
        return plain_value(asdict(value))
    return value


_STR = frozenset((str,))
_PLAIN_TYPES = frozenset(_PLAIN)


def _flat(items) -> list | None:
    """``[plain_value(item) for item in items]`` when every item is a float or of
    :data:`_PLAIN` (by exact type: what the columns of a record mostly are), worked out
    without a call per item; None when some item is of another type."""
    items = list(items)
    kinds = set(map(type, items))
    if kinds <= _PLAIN_TYPES:
        return items
    if float not in kinds or not kinds - {float} <= _PLAIN_TYPES:
        return None
    if kinds == {float} and all(map(math.isfinite, items)):
        return items
    return [item if type(item) is not float or math.isfinite(item) else None
            for item in items]


def _plain_line(value: Any) -> str:
    """:func:`record_line` of ``plain_value(value)``, without walking ``value`` in Python when
    json takes it as it is (a run's scenario infos, already plain: 2.7 MB at 1,000
    scenarios)."""
    try:
        return record_line(value)
    except (TypeError, ValueError):  # a value json does not know, or a non-finite float
        return record_line(plain_value(value))


def record_line(data: Mapping) -> str:
    """A record's line in a results file: ``data`` (:meth:`Record.as_dict`) as compact JSON
    on one line (never a raw newline: JSON escapes them in strings)."""
    return _LINE_ENCODER.encode(data)


#: json.dumps(ensure_ascii=False, allow_nan=False, separators=(",", ":")), made once, and
#: without its cycle check (~8% of the encoding): a record's values are a tree
#: (``plain_value`` copies them), and a cyclic value fails either way (RecursionError).
_LINE_ENCODER = json.JSONEncoder(ensure_ascii=False, allow_nan=False, separators=(",", ":"),
                                 check_circular=False)


@dataclass
class RecordBlock:
    """Consecutive records of a results file as they are written: their ``count`` lines
    (:func:`record_line`) joined by :data:`LINE_SEPARATOR` as UTF-8 ``text``, and, for the
    companion (:func:`companion_path`), the list of their dicts (:meth:`Record.as_dict`) and
    the list of their lines, each pickled. A run writes a scenario's block read from the
    result cache as it is: no record is parsed, encoded or pickled again."""

    text: bytes | memoryview
    count: int
    pickled_datas: bytes | memoryview
    pickled_lines: bytes | memoryview

    @classmethod
    def of_lines(cls, lines: Sequence[str], datas: Sequence[dict] | None = None,
                 pickled_datas: bytes | None = None) -> "RecordBlock":
        """The block of records whose ``lines`` are known and whose dicts are ``datas``
        (or, already pickled, ``pickled_datas``; one of the two)."""
        if pickled_datas is None:
            pickled_datas = pickle.dumps(list(datas), protocol=pickle.HIGHEST_PROTOCOL)
        return cls(text=LINE_SEPARATOR.join(lines).encode("utf-8"), count=len(lines),
                   pickled_datas=pickled_datas,
                   pickled_lines=pickle.dumps(list(lines), protocol=pickle.HIGHEST_PROTOCOL))

    def lines(self) -> list[str]:
        """The records' lines, decoded and split."""
        return str(self.text, "utf-8").split(LINE_SEPARATOR) if self.count else []


def write_results(path: Path | str, records: Iterable[Record | None], provenance: Mapping,
                  scenarios: Mapping | None = None, *,
                  lines: Sequence[str | None] | None = None) -> Path:
    """Write the results file (atomically) and its companion (:func:`companion_path`), and
    return the file's path.

    ``scenarios`` maps each scenario name to what the reports need besides the records
    (description, tags, system, sweep parameter, labels of the speeds, gates). ``lines``
    (parallel to ``records``): a record's :func:`record_line` when already known (read from
    the result cache with the record, which is unchanged since; the record may then be
    None), else None. :func:`write_result_blocks` writes records already laid out.
    """
    records = list(records)
    lines = [None] * len(records) if lines is None else list(lines)
    if len(lines) != len(records):
        raise ValueError(f"{len(lines)} lines for {len(records)} records")
    datas = [None if record is None else record.as_dict() for record in records]
    lines = [record_line(data) if line is None else line for data, line in zip(datas, lines)]
    if any(data is None for data in datas):  # a record known by its line only
        with collector_paused():
            datas = [json.loads(line) if data is None else data
                     for data, line in zip(datas, lines)]
    return write_result_blocks(path, [RecordBlock.of_lines(lines, datas)], provenance,
                               scenarios)


def write_result_blocks(path: Path | str, blocks: Sequence[RecordBlock], provenance: Mapping,
                        scenarios: Mapping | None = None) -> Path:
    """:func:`write_results` of the records of ``blocks``, in order."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    blocks = [block for block in blocks if block.count]
    document = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "provenance": plain_value(dict(provenance)),
    }
    # One scenario per line, one record per line: a diff of two results files reads record by
    # record, and the compact lines are written by json's C encoder (indented text is not).
    scenario_lines = ",".join(f"\n  {record_line(str(name))}: {_plain_line(info)}"
                              for name, info in (scenarios or {}).items())
    head = json.dumps(document, indent=1, ensure_ascii=False, allow_nan=False)
    head = (head[:-2] + ',\n "scenarios": {' + scenario_lines + ("\n }" if scenario_lines else "}")
            + RECORDS_START)
    # A unique temporary in the same directory, then an atomic rename: two runs writing the
    # same file at once each replace it whole; a reader never sees half a file. Written block
    # by block: the 56 MB of a large run are never copied into one text first.
    separator = LINE_SEPARATOR.encode()
    write_parts_atomically(path, itertools.chain(
        (head,), _separated([block.text for block in blocks], separator), (RECORDS_END,)))
    _write_companion(path, blocks)
    return path


def _separated(parts: Sequence, separator) -> Iterable:
    """``parts`` with ``separator`` between each two (what ``separator.join(parts)`` writes,
    without the one large copy)."""
    for number, part in enumerate(parts):
        if number:
            yield separator
        yield part


#: The ``format`` of a results file's companion (:func:`companion_path`).
COMPANION_FORMAT = "impact-harness-results-companion"


def companion_path(path: Path | str) -> Path:
    """The companion of the results file ``path``: ``<name>.pickle`` beside it.

    It holds the same records as the file, pickled (plain dicts, lists, strings and numbers:
    nothing else is unpickled), which :func:`read_results` loads several times faster than
    it parses the JSON. It is used only while the results file is the one it was written
    with (the file's size, modification time and inode, recorded in it, still match: each
    write replaces the file by a new one); anything else reads the JSON, which stays the
    results. Deleting it costs only speed.
    """
    path = Path(path)
    return path.with_name(path.name + ".pickle")


def _write_companion(path: Path, blocks: Sequence[RecordBlock]) -> None:
    """Write ``path``'s companion: a header, then the records' dicts in the ``blocks``'
    pickled parts, then their lines of the file (what ``Results.record_lines`` gives) in
    pickled parts; a companion that cannot be written is no error (the results file is
    whole, and a companion of another file is never used)."""
    companion = companion_path(path)
    try:
        status = path.stat()
        header = {"format": COMPANION_FORMAT, "results_size": status.st_size,
                  "results_mtime_ns": status.st_mtime_ns, "results_inode": status.st_ino,
                  "records": sum(block.count for block in blocks), "parts": len(blocks),
                  "line_parts": len(blocks)}
        write_parts_atomically(companion, (pickle.dumps(header),
                                           *(block.pickled_datas for block in blocks),
                                           *(block.pickled_lines for block in blocks)))
    except OSError:
        pass


class _PlainUnpickler(pickle.Unpickler):
    """An unpickler of plain values only: no class or function is ever looked up (a
    companion holds dicts, lists, strings, numbers, booleans and None)."""

    def find_class(self, module, name):
        raise pickle.UnpicklingError(f"{module}.{name}: a companion holds plain values only")


def read_companion_header(handle, status: os.stat_result) -> dict | None:
    """The header of the companion open in ``handle`` when it was written with the results
    file whose ``os.stat`` is ``status`` (the same size, modification time and inode), else
    None. Raises what unpickling raises on a damaged companion."""
    header = _PlainUnpickler(handle).load()
    if not (isinstance(header, dict) and header.get("format") == COMPANION_FORMAT
            and header.get("results_size") == status.st_size
            and header.get("results_mtime_ns") == status.st_mtime_ns
            and header.get("results_inode") == status.st_ino
            and isinstance(header.get("records"), int)
            and isinstance(header.get("parts"), int)
            and isinstance(header.get("line_parts"), int)):
        return None
    return header


def _read_companion(path: Path, status: os.stat_result
                    ) -> tuple[list[dict], list[str]] | None:
    """The record dicts and lines of ``path``'s companion when it matches the file
    (``status``), else None (absent, written for another file, damaged: the JSON is read)."""
    try:
        with open(companion_path(path), "rb") as handle:
            header = read_companion_header(handle, status)
            if header is None:
                return None
            datas: list = []
            for _ in range(header["parts"]):  # one pickle each: an unpickler (memo) each
                part = _PlainUnpickler(handle).load()
                if not isinstance(part, list):
                    return None
                datas += part
            lines: list = []
            for _ in range(header["line_parts"]):
                part = _PlainUnpickler(handle).load()
                if not isinstance(part, list):
                    return None
                lines += part
    except Exception:  # noqa: BLE001 - an unreadable companion is only slower reading
        return None
    if (len(datas) != header.get("records") or not all(isinstance(d, dict) for d in datas)
            or not isinstance(lines, list) or len(lines) != len(datas)
            or not all(isinstance(line, str) for line in lines)):
        return None
    return datas, lines


#: What comes between the header and the first record line of a results file, and after the
#: last: :func:`read_results` finds the record lines by them.
RECORDS_START = ',\n "records": [\n'
RECORDS_END = "\n ]\n}\n"


def check_writable(path: Path | str) -> str | None:
    """``None`` when a results file can be written at ``path``, else the reason it cannot.

    Checked before a run starts (creates the parent directory, and a temporary in it that it
    removes), so a bad ``--json`` costs nothing.
    """
    path = Path(path)
    if path.is_dir():
        return "is a directory"
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        descriptor, temporary = tempfile.mkstemp(prefix=f".{path.name}-", suffix=".tmp",
                                                 dir=path.parent)
        os.close(descriptor)
        os.unlink(temporary)
    except OSError as error:
        return f"cannot write there: {error.strerror or error}"
    return None


def read_results(path: Path | str) -> Results:
    """Read a results file; a wrong format raises ``ValueError`` naming the file."""
    path = Path(path)
    with collector_paused():
        return _read_results(path)


def _read_results(path: Path) -> Results:
    try:
        with open(path, "rb") as handle:
            status = os.fstat(handle.fileno())
            data = handle.read()
        companion = _read_companion(path, status)
        document = None if companion is None else results_head(data)
        if document is not None:  # the records and their lines from the companion
            datas, lines = companion
        else:
            text = str(data, "utf-8")
            datas, (document, lines) = None, _split_records(text)
            if document is None:  # not as write_results lays it out: read whole
                document = json.loads(text)
    except FileNotFoundError:
        raise FileNotFoundError(
            f"{path}: no results file; run `impact-harness run` (or `suite`) first") from None
    except IsADirectoryError:
        raise ValueError(f"{path}: is a directory, not a results file") from None
    except (ValueError, OSError) as error:  # JSONDecodeError, UnicodeDecodeError
        raise ValueError(f"{path}: not a readable results file: {error}") from None
    if not isinstance(document, dict) or document.get("format") != FORMAT:
        raise ValueError(f"{path}: not an impact-harness results file (format {FORMAT!r})")
    if document.get("format_version") != FORMAT_VERSION:
        raise ValueError(f"{path}: results format version {document.get('format_version')!r}; "
                         f"this harness reads {FORMAT_VERSION}")
    items = datas if datas is not None else document.get("records", [])
    records = [Record.from_dict(item) for item in items]
    results = Results(records=records, provenance=document.get("provenance", {}),
                      scenarios=document.get("scenarios", {}))
    if lines is not None and len(lines) == len(records):
        results._lines = (records, len(records), lines)
    return results


def results_head(data: bytes) -> dict | None:
    """The document before the records of a results file's bytes laid out by
    :func:`write_results` (its records then come from the companion, or from the record
    lines), else None. Its format is not checked here."""
    start = data.find(RECORDS_START.encode())
    if start < 0 or not data.endswith(RECORDS_END.encode()):
        return None
    try:
        document = json.loads(str(data[:start], "utf-8") + "\n}")
    except ValueError:
        return None
    return document if isinstance(document, dict) and "records" not in document else None


_DECODER = json.JSONDecoder()


def _split_records(text: str) -> tuple[dict | None, list[str] | None]:
    """A results file laid out by :func:`write_results`, read as ``(document, record lines)``
    (the lines are what the report's figure digests hash); ``(None, None)`` for any other
    layout. A line never holds a raw newline (JSON escapes it), so ``",\\n"`` only
    separates record lines, and the header's top-level ``"records"`` key is the only place
    the text between the header and the records can be."""
    start = text.find(RECORDS_START)
    if start < 0 or not text.endswith(RECORDS_END):
        return None, None
    try:
        document = json.loads(text[:start] + "\n}")
        # the records' list parsed where it stands (no copy of the text)
        records, end = _DECODER.raw_decode(text, start + len(RECORDS_START) - 2)
    except ValueError:
        return None, None
    if end != len(text) - len(RECORDS_END) + 3:  # after "\n ]": where the file ends it
        return None, None
    body = text[start + len(RECORDS_START):len(text) - len(RECORDS_END)]
    if not isinstance(document, dict) or "records" in document:
        return None, None
    document["records"] = records
    lines = body.split(",\n") if body else []
    if len(lines) != len(records) or not all(line[:1] == "{" and line[-1:] == "}"
                                             for line in lines):
        lines = None  # records laid out otherwise (indented): read, but no lines
    return document, lines


__all__ = ["ANALYTIC", "DEFAULT_RESULTS", "FORMAT", "FORMAT_VERSION", "LINE_SEPARATOR",
           "Record", "RecordBlock", "Results", "check_writable", "companion_path",
           "plain_value", "read_companion_header", "read_results", "record_line", "results_head",
           "write_result_blocks", "write_results"]
