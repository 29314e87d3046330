"""What the report computes per scenario, kept between reports as the figures are.

A report of 1,000 scenarios formats ~28,000 records into ~2,400 velocity tables and ~16,000
headline cells: most of a warm report's time, when nothing has changed since the last one.
Each scenario's pieces -- its HTML section and its :func:`scenario_view` (headline cells,
departure split) -- are stored in ``<out>/`` :data:`CACHE_FILE` under a key made of the
scenario's records digest (:func:`harness.report.figure_cache.scenario_digests`) and whatever
else the piece reads; a later report reuses a piece whose key is unchanged and computes the
rest. The file as a whole holds only for the same code (:func:`cache_context`): an edit to
the report, or another set of engine labels, starts it afresh.

The cache changes when a piece is computed, never what it holds: a stored piece is the JSON
of what the code returned (the code returns only JSON values, so that a computed and a read
piece are the same).

Anyone who can write the report's directory could edit a stored section and get their HTML
into index.html (issue 37): the file's first line is sealed -- the HMAC of
:mod:`harness.store.sealing` under the result cache's key, which never lies in the report's
directory (:func:`harness.store.cache_directory.output_seal`) -- and holds the SHA-256 of
everything after it. A file whose seal or checksum does not verify is not believed: its
pieces are computed anew, said in one line on stderr.
"""

from __future__ import annotations

import hashlib
import json
import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from harness.engines import PRESET_ROLES, engine_names
from harness.inputs import read_bytes
from harness.report.figure_cache import code_digest, scenario_digests
from harness.report.reading import record_scenarios
from harness.report.views import (
    HEADLINE_LAWS,
    departure_cell,
    engine_labels,
    label_records,
    record_label,
    single_contact,
    worst_departure,
)
from harness.run.metrics import departure_split
from harness.run.records import ANALYTIC, Record, Results
from harness.store.cache_directory import output_seal
from harness.store.files import write_parts_atomically
from harness.store.sealing import Seal

#: The cache's file in the report's directory.
CACHE_FILE = ".report-fragments.json"
#: The file of the scenarios' digests by the digest of their exact lines
#: (:meth:`harness.report.reading.LazyResults.scenario_digests`): apart, so that a results
#: file written anew with the same records (only their times change) rewrites this small
#: file, not the pieces.
DIGESTS_FILE = ".report-digests.json"


def cache_context(labels: Sequence[str]) -> str:
    """What every stored piece depends on besides its own key: the report's code (with
    matplotlib's version, :func:`harness.report.figure_cache.code_digest`), the metrics module
    (the departure split), the engine labels and the engines' and presets' order."""
    from importlib.util import find_spec


    digest = hashlib.sha256(code_digest())
    digest.update(Path(find_spec("harness.run.metrics").origin).read_bytes())  # not imported
    digest.update(json.dumps([list(labels), list(engine_names()), list(PRESET_ROLES)]).encode())
    return digest.hexdigest()


class FragmentCache:
    """Pieces of a report by key, read from ``path`` when it was written for ``context``;
    :meth:`save` keeps only the pieces this report asked for."""

    def __init__(self, path: Path | None, context: str, seal: Seal | None = None):
        self.path = path
        self.context = context
        self.seal = output_seal() if seal is None and path is not None else seal
        self.stored: dict = {}
        self.kept: dict = {}
        self.computed = 0
        if path is None:
            return
        try:  # a regular file of bounded size only (never a device: /dev/zero filled memory)
            raw = read_bytes(path, cap_name="max_results_bytes")
        except FileNotFoundError:
            return
        except (OSError, ValueError) as error:  # a device, a pipe, too large (InputError)
            self._not_believed(f"cannot be read ({getattr(error, 'strerror', None) or error})")
            return
        try:
            head_end = raw.find(b"\n")
            header = json.loads(raw[:head_end]) if head_end > 0 else None
            if not isinstance(header, dict):
                raise ValueError("not a report's cached pieces")
            self.seal.check(header)  # KeyProblem is a ValueError
            if header.get("context") != context:
                return  # written by other code: computed anew, nothing to say
            rest = memoryview(raw)[head_end + 1:]
            if header.get("sha256") != hashlib.sha256(rest).hexdigest():
                raise ValueError("checksum differs: changed after it was written")
            head, _, texts = str(rest, "utf-8").partition("\n")
            data = json.loads(head)
            stored = dict(data["entries"])
            stored.update((key, texts[start:end]) for key, (start, end) in data["texts"].items())
            self.stored = stored
        except (ValueError, AttributeError, KeyError, TypeError) as error:
            self._not_believed(str(error))

    def _not_believed(self, why: str) -> None:
        """Say in one line that the file is not believed (its pieces are computed anew)."""
        print(f"impact-harness report: warning: {self.path}: not believed, its pieces are "
              f"computed anew: {why[:200]}", file=sys.stderr)

    def get(self, key: str, make: Callable[[], object]):
        """The piece stored under ``key``, else ``make()`` (as its JSON reads back)."""
        if key in self.kept:
            return self.kept[key]
        if key in self.stored:
            value = self.stored[key]
        else:
            self.computed += 1
            value = make()
        self.kept[key] = value
        return value

    def save(self) -> None:
        """Write the pieces asked for (written whole and then renamed: a report stopped
        half-way leaves the previous file).

        The file is a sealed line of JSON -- the context and the SHA-256 of what follows
        (see the module) --, a line of JSON -- the pieces that are not text, and where each
        text piece is -- followed by the text pieces one after another: the sections are
        most of it, and reading them as JSON strings took longer than the rest of a warm
        report. A file that cannot be sealed (the key cannot be had) is not written.
        """
        if self.path is None or (not self.computed and self.kept.keys() == self.stored.keys()):
            return
        entries, spans, texts, at = {}, {}, [], 0
        for key, value in self.kept.items():
            if isinstance(value, str):
                spans[key] = (at, at + len(value))
                texts.append(value.encode("utf-8"))
                at += len(value)
            else:
                entries[key] = value
        head = json.dumps({"entries": entries, "texts": spans}).encode("utf-8")
        digest = hashlib.sha256(head + b"\n")
        for text in texts:
            digest.update(text)
        try:
            sealed = self.seal.sealed({"context": self.context, "sha256": digest.hexdigest()})
        except (OSError, ValueError) as error:  # KeyProblem is a ValueError
            print(f"impact-harness report: warning: {self.path}: not kept (cannot be sealed: "
                  f"{error}); the next report computes its pieces anew", file=sys.stderr)
            return
        write_parts_atomically(self.path, (json.dumps(sealed), "\n", head, b"\n", *texts))


def scenario_view(records: Sequence[Record], labels: Sequence[str]) -> dict:
    """What the headline tables and the split table show of one scenario.

    ``engine``: whether it has engine runs the single-contact laws describe (a row of the
    heat map and of ``summary.md``); per headline law, per label ``[value, flagged, skipped,
    text]`` (:func:`harness.report.views.worst_departure` and ``departure_cell``; a label
    without runs is skipped); ``split``: its departure split (:func:`split_view`).
    """
    by_label = label_records(records)
    view: dict = {"engine": any(r.source != ANALYTIC and single_contact(r) for r in records)}
    for law in HEADLINE_LAWS:
        cells = []
        for label in labels:
            subset = by_label.get(label)
            if subset:
                value, flagged, skipped = worst_departure(subset, law)
            else:
                value, flagged, skipped = math.nan, False, True
            cells.append([float(value), bool(flagged), bool(skipped),
                          departure_cell(subset or [], law)])
        view[law] = cells
    view["split"] = split_view(records)
    return view


def split_view(records: Sequence[Record]) -> dict:
    """One scenario's rows of :func:`harness.report.views.split_rows` reduced to what the
    split table shows: the largest finite law part (None if none), per label (in the rows'
    order) the largest finite solve part (None if none); no rows: ``{}``."""
    lcp = {r.point["index"]: r for r in records
           if r.source == ANALYTIC and r.law == "newton-lcp" and r.ok}
    law_part = -math.inf
    solve: dict[str, float] = {}
    for record in records:
        if (record.source == ANALYTIC or record.skipped or record.u_after is None
                or not single_contact(record)):  # as split_rows
            continue
        law_record = lcp.get(record.point["index"])
        if law_record is None:
            continue
        split = departure_split(record.departure, law_record.departure)
        label = record_label(record)
        solve.setdefault(label, -math.inf)
        if math.isfinite(split["law_part"]):
            law_part = max(law_part, split["law_part"])
        if math.isfinite(split["solve_part"]):
            solve[label] = max(solve[label], split["solve_part"])
    if not solve:
        return {}
    return {"law_part": None if law_part == -math.inf else law_part,
            "solve": {label: None if value == -math.inf else value
                      for label, value in solve.items()}}


def split_order(results: Results) -> tuple[list[str], list[str]]:
    """The scenarios and labels of :func:`harness.report.views.split_rows`, in the order of
    their first row, without computing the rows."""
    lcp = {(r.scenario, r.point["index"]) for r in results.records
           if r.source == ANALYTIC and r.law == "newton-lcp" and r.ok}
    scenarios: dict[str, None] = {}
    labels: dict[str, None] = {}
    for record in results.records:
        if (record.source == ANALYTIC or record.u_after is None or record.skipped
                or (record.scenario, record.point["index"]) not in lcp
                or not single_contact(record)):  # as split_rows
            continue
        scenarios[record.scenario] = None
        labels[record_label(record)] = None
    return list(scenarios), list(labels)


@dataclass
class Prepared:
    """The report's per-scenario pieces: ``digests`` of the records, the engine ``labels``,
    each scenario's :func:`scenario_view`, the ``cache`` they came from, and
    ``records_digest``, of every record in order (what a piece made of all of them reads)."""

    digests: dict[str, str]
    labels: list[str]
    views: dict[str, dict]
    cache: FragmentCache = field(repr=False)
    records_digest: str = ""

    def whole(self, kind: str, make: Callable[[], str]) -> str:
        """A piece made of every record (``kind`` names it), from the cache while no record
        changed."""
        return self.cache.get(f"{kind}\0{self.records_digest}", make)


def open_cache(results: Results, out_dir: Path | None = None,
               name: str = CACHE_FILE) -> FragmentCache:
    """The fragment cache of a report of ``results`` in ``out_dir`` (None: nothing kept),
    in its file ``name`` there."""
    return FragmentCache(None if out_dir is None else Path(out_dir) / name,
                         cache_context(engine_labels(results)))


def prepare(results: Results, out_dir: Path | None = None,
            digests: dict[str, str] | None = None,
            cache: FragmentCache | None = None) -> Prepared:
    """The views of every scenario, from ``<out_dir>/`` :data:`CACHE_FILE` (or ``cache``,
    :func:`open_cache`'s) where their records are unchanged (``out_dir`` None: computed,
    nothing kept)."""
    labels = engine_labels(results)
    cache = open_cache(results, out_dir) if cache is None else cache
    digests = scenario_digests(results, cache.get) if digests is None else digests
    names = results.scenario_names()
    views = {name: cache.get(f"view\0{name}\0{digests.get(name, '')}",
                             lambda name=name: scenario_view(results.for_scenario(name), labels))
             for name in names}
    # every scenario's digest, and the order of the records across scenarios (a run of a
    # scenario's records after another's: the first appearances a piece may show)
    order, previous = [], None
    for scenario in record_scenarios(results):
        if scenario != previous:
            order.append(scenario)
            previous = scenario
    inputs = json.dumps([[[name, digests.get(name, "")] for name in names], order])
    return Prepared(digests, labels, views, cache,
                    hashlib.sha256(inputs.encode()).hexdigest())
