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

The file is the results' only form: plain JSON, read by ``json`` (no pickle beside it).
:func:`read_results` refuses a file of another format or version, or a record without a
field every record has (:data:`REQUIRED_FIELDS`), with a ``ValueError`` naming the file.

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
import sys
from dataclasses import asdict, dataclass, field, fields, is_dataclass
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

from harness import inputs
from harness.collector import collector_paused
from harness.engines import engine_names, source_label
from harness.scenarios import PRESETS
from harness.scenarios.schema import NAME_ALLOWED, NAME_PATTERN
from harness.store.cache import LINE_SEPARATOR  # between two record lines (no raw newline)
from harness.store.files import output_file_problem, write_parts_atomically

FORMAT = "impact-harness-results"
FORMAT_VERSION = 1
DEFAULT_RESULTS = Path("reports") / "results.json"
ANALYTIC = "analytic"


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
        """``engine.preset`` labels present, engines in registry order (one not registered
        here, from a run where it was, after them by name), ``defaults`` first."""
        return [source_label(e, p) for e, p in self.engine_roles()]

    def engine_roles(self) -> list[tuple[str, str]]:
        """``(engine, preset role)`` pairs present, in :meth:`engine_labels`' order."""
        present = self._engine_runs()
        registered = engine_names()
        others = sorted({e for e, _ in present if e not in registered})
        return [(e, p) for p in PRESETS for e in (*registered, *others) if (e, p) in present]

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
    """Plain JSON values of the built-in types only (what the JSON reads back); non-finite
    floats become None, numpy values and subclasses of str, int and float plain Python,
    nested dataclasses dicts."""
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
    (:func:`record_line`) joined by :data:`LINE_SEPARATOR` as UTF-8 ``text``. A run writes a
    scenario's block read from the result cache as it is: no record is parsed or encoded
    again."""

    text: bytes | memoryview
    count: int

    @classmethod
    def of_lines(cls, lines: Sequence[str]) -> "RecordBlock":
        """The block of records whose ``lines`` are known."""
        return cls(text=LINE_SEPARATOR.join(lines).encode("utf-8"), count=len(lines))

    def lines(self) -> list[str]:
        """The records' lines, decoded and split."""
        return str(self.text, "utf-8").split(LINE_SEPARATOR) if self.count else []


def write_results(path: Path | str, records: Iterable[Record | None], provenance: Mapping,
                  scenarios: Mapping | None = None, *,
                  lines: Sequence[str | None] | None = None) -> Path:
    """Write the results file (atomically) and return its path.

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
    if any(record is None and line is None for record, line in zip(records, lines)):
        raise ValueError("a record that is None has no line")
    lines = [record_line(record.as_dict()) if line is None else line
             for record, line in zip(records, lines)]
    return write_result_blocks(path, [RecordBlock.of_lines(lines)], provenance, scenarios)


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
    return path


def _separated(parts: Sequence, separator) -> Iterable:
    """``parts`` with ``separator`` between each two (what ``separator.join(parts)`` writes,
    without the one large copy)."""
    for number, part in enumerate(parts):
        if number:
            yield separator
        yield part


#: What comes between the header and the first record line of a results file, and after the
#: last: :func:`read_results` finds the record lines by them.
RECORDS_START = ',\n "records": [\n'
RECORDS_END = "\n ]\n}\n"


def check_writable(path: Path | str, *, make_parent: bool = False) -> str | None:
    """``None`` when a results file can be written at ``path``, else the reason it cannot
    (:func:`harness.store.files.output_file_problem`: nothing there or a regular file, in an
    existing writable directory).

    Checked before a run starts, so a bad ``--json`` costs nothing. ``make_parent``: the
    directory is made (itself only) when missing -- for the default results file only, whose
    ``reports/`` is the harness's own; a directory the user names must exist.
    """
    path = Path(path)
    try:  # a name too long raises
        if make_parent and not os.path.lexists(path.parent) and path.parent.parent.is_dir():
            try:
                path.parent.mkdir()
            except OSError as error:
                return f"cannot make {path.parent}: {error.strerror or error}"
        return output_file_problem(path)
    except OSError as error:
        return f"cannot write there: {error.strerror or error}"


def read_results(path: Path | str) -> Results:
    """Read a results file; a wrong format raises ``ValueError`` naming the file."""
    path = Path(path)
    with collector_paused():
        return _read_results(path)


def _read_results(path: Path) -> Results:
    try:
        # a regular file of bounded size only: /dev/zero or a FIFO is refused, never read
        data, _ = inputs.read_bytes_and_status(path, cap_name="max_results_bytes")
        text = str(data, "utf-8")
        document, lines = _split_records(text)
        if document is None:  # not as write_results lays it out: read whole
            document = json.loads(text)
    except FileNotFoundError:
        raise FileNotFoundError(
            f"{path}: no results file; run `impact-harness run` (or `suite`) first") from None
    except IsADirectoryError:
        raise ValueError(f"{path}: is a directory, not a results file") from None
    except (ValueError, OSError) as error:  # JSONDecodeError, UnicodeDecodeError, InputError
        raise ValueError(f"{path}: not a readable results file: {error}") from None
    except RecursionError:
        raise ValueError(f"{path}: not a readable results file: nested too deep") from None
    if not isinstance(document, dict) or document.get("format") != FORMAT:
        raise ValueError(f"{path}: not an impact-harness results file (format {FORMAT!r})")
    if document.get("format_version") != FORMAT_VERSION:
        raise ValueError(f"{path}: results format version {document.get('format_version')!r}; "
                         f"this harness reads {FORMAT_VERSION}")
    items = document.get("records", [])
    problem = records_problem(items)
    if problem:
        raise ValueError(f"{path}: {problem}")
    provenance, scenarios = document.get("provenance", {}), document.get("scenarios", {})
    if not isinstance(provenance, dict) or not isinstance(scenarios, dict):
        raise ValueError(f"{path}: 'provenance' and 'scenarios' must be JSON objects")
    problem = provenance_problem(provenance, scenarios)
    if problem:
        raise ValueError(f"{path}: {problem}")
    records = []
    for number, item in enumerate(items):
        try:
            records.append(Record.from_dict(item))
        except (TypeError, KeyError, ValueError, AttributeError, RecursionError) as error:
            raise ValueError(f"{path}: record {number} is malformed: {type(error).__name__}: "
                             f"{str(error)[:200]}") from None
    results = Results(records=records, provenance=provenance, scenarios=scenarios)
    if lines is not None and len(lines) == len(records):
        results._lines = (records, len(records), lines)
    return results


#: The fields every record of a results file holds (a record without one is refused: a
#: report or comparison of it would be wrong, not merely short).
REQUIRED_FIELDS = ("scenario", "point", "source", "law", "preset", "u_before", "u_after",
                   "status", "departure")
#: The type of each required field (None allowed where a record may lack the value).
_REQUIRED_TYPES = {"scenario": (str,), "point": (dict,), "source": (str,),
                   "law": (str, type(None)), "preset": (str, type(None)),
                   "u_before": (list, type(None)), "u_after": (list, type(None)),
                   "status": (str,), "departure": (dict,)}


_NUMBER = (int, float, type(None))
#: The type of each other field, when a record holds it.
_OPTIONAL_TYPES = {"vn_approach": _NUMBER, "vt_approach": _NUMBER, "vn_separation": _NUMBER,
                   "vt_separation": _NUMBER, "energy_change": _NUMBER,
                   "collision_type": (int, type(None)), "normal_impulse": _NUMBER,
                   "tangential_impulse": _NUMBER, "wall_time_s": _NUMBER, "cached": (bool,),
                   "diagnostics": (dict, type(None)), "verdict": (str, type(None)),
                   "reasons": (list,)}
#: The provenance's values the report and compare read, by key, with their types.
_PROVENANCE_TYPES = {"gates": (list,), "engine_settings": (dict,), "versions": (dict,),
                     "git": (dict, type(None)), "machine": (dict,), "cache": (dict,),
                     "selection": (dict,), "engines": (list,), "presets": (list,),
                     "executor": (dict,), "settings_overrides": (dict,), "command": (list,),
                     "engine_versions": (dict,), "engines_missing": (dict,),
                     "created_utc": (str,), "code_version": (str,), "history": (str,),
                     "wall_time_s": _NUMBER, "task_time_limit_s": _NUMBER}


def _is_float_value(value) -> bool:
    """Whether ``value`` is null or a number a float holds (an integer of 400 digits is
    not: it would end in an OverflowError far from the file)."""
    if value is None or isinstance(value, float):
        return True
    return (isinstance(value, int) and not isinstance(value, bool)
            and abs(value) <= sys.float_info.max)


def _kinds(kinds: tuple) -> str:
    return " or ".join("null" if kind is type(None) else kind.__name__ for kind in kinds)


def _value_problem(item: dict) -> str | None:
    """Why a record's values (past the required fields' own types) are not those a run
    writes: an optional field of another type, a departure or a speed that is not a
    number (a report or a comparison of it would fail late, or be wrong)."""
    if not NAME_PATTERN.match(item["scenario"]):  # it names files and HTML anchors
        return f"scenario = {item['scenario']!r:.120}: not a scenario's name ({NAME_ALLOWED})"
    for name, kinds in _OPTIONAL_TYPES.items():
        value = item.get(name)
        if name in item and (not isinstance(value, kinds)
                             or isinstance(value, bool) and bool not in kinds):
            return f"{name} = {value!r}: not a {_kinds(kinds)}"
    for name in ("u_before", "u_after"):
        if item[name] is not None and not all(map(_is_float_value, item[name])):
            return f"{name} = {item[name]!r:.120}: not a list of numbers"
    if not all(isinstance(law, str) and _is_float_value(v)
               for law, v in item["departure"].items()):
        return f"departure = {item['departure']!r:.120}: not numbers by law"
    if not all(isinstance(reason, dict) and isinstance(reason.get("name"), str)
               for reason in item.get("reasons", ())):
        return f"reasons = {item['reasons']!r:.120}: not a list of named reasons"
    return None


def provenance_problem(provenance: dict, scenarios: dict) -> str | None:
    """Why a results file's provenance or scenarios are not as a run writes them."""
    for name, kinds in _PROVENANCE_TYPES.items():  # null: a value the run did not record
        if name in provenance and not isinstance(provenance[name], (*kinds, type(None))):
            return f"provenance.{name} = {provenance[name]!r:.80}: not a {_kinds(kinds)}"
    for number, gate in enumerate(provenance.get("gates") or []):
        if not (isinstance(gate, dict) and all(isinstance(value, str | int | float | None)
                                               for value in gate.values())
                and isinstance(gate.get("status"), str)):
            return f"provenance.gates[{number}] = {gate!r:.80}: not a gate's record"
    for engine, presets in (provenance.get("engine_settings") or {}).items():
        if not (isinstance(presets, dict) and all(isinstance(settings, dict)
                                                  for settings in presets.values())):
            return (f"provenance.engine_settings.{engine} = {presets!r:.80}: not settings by "
                    "preset")
    for name in ("versions", "engine_versions", "engines_missing"):
        for key, value in (provenance.get(name) or {}).items():
            if not isinstance(value, (str, type(None))):
                return f"provenance.{name}.{key} = {value!r:.80}: not a string"
    if not all(isinstance(word, str) for word in provenance.get("command") or ()):
        return f"provenance.command = {provenance['command']!r:.80}: not a list of strings"
    for name, value in scenarios.items():
        if not isinstance(value, dict):
            return f"scenarios.{name} = {value!r:.80}: not a JSON object"
    return None


def records_problem(items: Any) -> str | None:
    """Why the records of a results file cannot be read (None: they can): each must be an
    object holding :data:`REQUIRED_FIELDS` with values of their types; the first bad one
    is named by its position."""
    if not isinstance(items, list):
        return "'records' must be a list"
    for number, item in enumerate(items):
        if not isinstance(item, dict):
            return f"record {number}: not a JSON object"
        missing = [name for name in REQUIRED_FIELDS if name not in item]
        if missing:
            return (f"record {number}: no {', '.join(missing)} (every record has "
                    f"{', '.join(REQUIRED_FIELDS)}): not a complete results file")
        for name in REQUIRED_FIELDS:
            if not isinstance(item[name], _REQUIRED_TYPES[name]):
                return (f"record {number}: {name} = {item[name]!r}: not a "
                        + " or ".join("null" if kind is type(None) else kind.__name__
                                      for kind in _REQUIRED_TYPES[name]))
        problem = _value_problem(item)
        if problem:
            return f"record {number}: {problem}"
    return None


def results_head(data: bytes) -> dict | None:
    """The document before the records of a results file's bytes laid out by
    :func:`write_results` (its records then come from the record lines), else None. Its
    format is not checked here."""
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
           "REQUIRED_FIELDS", "Record", "RecordBlock", "Results", "check_writable",
           "plain_value", "read_results", "record_line", "records_problem", "results_head",
           "write_result_blocks", "write_results"]
