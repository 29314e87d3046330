"""The report's figure cache: each figure is redrawn only when its inputs change.

A figure's PNG carries the digest of its inputs (a scenario's records by
:func:`scenario_digests`) and of the report's code in its metadata (:data:`TAG_KEY`);
:func:`render_once` skips a figure whose file already holds that digest. The figures
themselves are drawn by :mod:`harness.report.figures`.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import os
import stat
from collections.abc import Callable
from pathlib import Path

from harness.engines import engine_names, renamed_roles
from harness.plotting import (  # shared with the survey's figures
    SVG_TWIN,
    TAG_KEY,
)
from harness.report.reading import LazyResults, inputs_digests, scenario_digest, with_inputs
from harness.run.records import Results, record_line


@dataclasses.dataclass(frozen=True)
class FigureTask:
    """One figure of the report: drawn by ``draw(path, tag)`` from inputs whose digest is
    ``tag``; deterministic, so that any worker draws the same file.

    ``slot`` says where the file goes in the report's ``figures`` mapping: ``(key,)`` or
    ``(key, scenario)``; ``svg`` whether its SVG twin is written; ``reads_records``
    whether ``draw`` reads the records (a figure of Table 3 or the key reads none).
    """

    kind: str
    file: str
    payload: object
    draw: Callable[[Path, str], Path | None]
    slot: tuple
    svg: bool = True
    reads_records: bool = True

@dataclasses.dataclass(frozen=True)
class FigureKind:
    """A kind of the report's figures, registered once in :data:`FIGURE_KINDS`: its name
    (the digest's kind and the key of the page's ``figures`` mapping), its file (``{}``: the
    scenario's slug or the engine, for a figure per scenario or engine), its rough drawing
    cost and whether it is a headline figure (drawn once per report)."""

    name: str
    file: str
    #: CPU seconds, PNG and SVG, measured at 1,000 scenarios (the headline figures with the
    #: heat map's row per family): the pool draws the dearest first, so that no worker is
    #: left with the dearest at the end
    cost: float
    #: drawn once per report, not per scenario: its SVG twin is kept with ``--svg headline``
    headline: bool

    def svg(self, choice: str) -> bool:
        """Whether its SVG twin is written under ``--svg`` ``choice`` (``all``,
        ``headline``)."""
        return choice == "all" or (self.headline and choice == "headline")

    def task(self, payload, draw: Callable[[Path, str], Path | None], svg: bool,
             key: str | None = None, file_key: str | None = None,
             reads_records: bool = True) -> FigureTask:
        """The :class:`FigureTask` of one figure of this kind: ``key`` (a scenario's name,
        an engine) its place in the page's mapping, ``file_key`` (default ``key``) the
        part of its file's name that tells it apart."""
        file = self.file.format(key if file_key is None else file_key)
        slot = (self.name,) if key is None else (self.name, key)
        return FigureTask(self.name, file, payload, draw, slot, svg, reads_records)


#: Every kind of figure the report draws (:class:`FigureKind`).
FIGURE_KINDS: dict[str, FigureKind] = {kind.name: kind for kind in (
    FigureKind("heatmap", "heatmap.png", 2.5, headline=True),
    FigureKind("split", "split.png", 1.8, headline=True),
    FigureKind("table3", "paper-table3.png", 1.7, headline=True),
    FigureKind("survey_map", "survey-map-{}.png", 1.2, headline=True),
    FigureKind("survey_cdf", "survey-cdf-{}.png", 0.6, headline=True),
    FigureKind("sweep", "sweep-{}.png", 2.2, headline=False),
    FigureKind("impulse", "impulse-{}.png", 0.5, headline=False),
    FigureKind("history", "history-{}.png", 1.0, headline=False),
)}


def scenario_digests(results: Results, known=None) -> dict[str, str]:
    """``{scenario: sha256 of its records}``, what every figure of a scenario (and the
    headline figures, of all) depends on besides the code: of what they decided and of what
    they were made from, never of their floats' last bits, which depend on the CPU
    (:func:`~harness.report.reading.scenario_digest`, ``inputs_digests``).

    Hashed from each record's line in the results file (:func:`harness.run.records.
    record_line`), as read (``Results.record_lines``, or the bytes of the file for
    :class:`~harness.report.reading.LazyResults`) or else written anew: only what they
    decided is taken from them (:data:`~harness.report.reading.DECIDED_TEXT`; no time, no
    float): a warm report hashes text instead of encoding 28,000 records again, which was
    half of its time at 1,000 scenarios. A change to what a record decided, to a scenario's
    definition, the code, the installed versions or the engines' settings changes the
    digest; times, the cache's hits and a float's last bits do not. ``known``: where
    :meth:`LazyResults.scenario_digests <harness.report.reading.LazyResults.scenario_digests>`
    finds the digests of lines it hashed before (a report's fragment cache's ``get``).
    """
    if isinstance(results, LazyResults):
        return results.scenario_digests(known)
    lines = results.record_lines()
    if lines is None:  # built in memory: the lines the results file would hold
        lines = [record_line(record.as_dict()) for record in results.records]
    texts: dict[str, list[str]] = {}
    for record, line in zip(results.records, lines):
        texts.setdefault(record.scenario, []).append(line)
    return with_inputs({name: scenario_digest(parts) for name, parts in texts.items()},
                       inputs_digests(results.provenance, results.scenarios))


@functools.cache
def code_digest() -> bytes:
    """What the code drawing the figures contributes to every digest: every module of the
    report package (a figure reads views, history and the rest as well as figures.py: an
    edit to any of them redraws), the engines' preset names users see (titles and legends
    show them; harness/engines) and matplotlib's version, read without importing it (a
    warm report draws nothing)."""
    sources = [*sorted(Path(__file__).parent.glob("*.py")),
               Path(__file__).parents[1] / "plotting.py"]
    labels = json.dumps({engine: renamed_roles(engine) for engine in engine_names()},
                        sort_keys=True).encode()
    return b"".join(path.read_bytes() for path in sources) + labels + _matplotlib_version()


def _matplotlib_version() -> bytes:
    """Matplotlib's version file (``matplotlib/_version.py``, which setuptools-scm writes),
    found without importing matplotlib or ``importlib.metadata`` (a tenth of a warm
    report's imports); else its version from the package's metadata, ``b"none"`` when it
    is not installed (nothing can be drawn then either)."""
    from importlib.util import find_spec

    spec = find_spec("matplotlib")
    if spec is None:
        return b"none"
    for location in spec.submodule_search_locations or ():
        try:
            return (Path(location) / "_version.py").read_bytes()
        except OSError:
            continue
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("matplotlib").encode()
    except PackageNotFoundError:
        return b"none"


def inputs_digest(kind: str, payload) -> str:
    """Digest of a figure's inputs and of the code drawing it (the report package, matplotlib)."""
    text = json.dumps([kind, payload], sort_keys=True, default=str)
    return hashlib.sha256(code_digest() + text.encode()).hexdigest()


PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def png_tag(path: Path) -> str | None:
    """The inputs digest stored in a PNG by :func:`save_png` (None if absent/unreadable).

    Read from the file's ``tEXt`` chunks, which matplotlib writes before the image data
    (``IDAT``): the chunks before it are read, never the pixels, and Pillow is not imported
    (a warm report opens every figure and draws none).
    """
    key = TAG_KEY.encode("latin-1") + b"\0"
    try:  # a regular file only, never through a link: a FIFO planted there would block
        descriptor = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0)
                             | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
        with open(descriptor, "rb") as handle:
            if not stat.S_ISREG(os.fstat(descriptor).st_mode):
                return None
            if handle.read(8) != PNG_SIGNATURE:
                return None
            while True:
                head = handle.read(8)
                if len(head) < 8:
                    return None
                length, kind = int.from_bytes(head[:4], "big"), head[4:]
                if kind in (b"IDAT", b"IEND"):
                    return None
                data = handle.read(length)
                if len(data) < length:
                    return None
                handle.seek(4, 1)  # the chunk's CRC
                if kind == b"tEXt" and data.startswith(key):
                    return data[len(key):].decode("latin-1")
    except OSError:  # a missing or broken file is simply redrawn
        return None


def render_once(kind: str, path: Path, payload, draw, svg: bool = True) -> Path | None:
    """Draw a figure unless ``path`` (and its SVG, when ``svg``) already hold one drawn from
    the same inputs."""
    tag = inputs_digest(kind, payload)
    if is_current(path, tag, svg):
        return path
    token = SVG_TWIN.set(svg)
    try:
        return draw(path, tag)
    finally:
        SVG_TWIN.reset(token)


def is_current(path: Path, tag: str, svg: bool = True) -> bool:
    """Whether ``path`` holds the figure drawn from the inputs whose digest is ``tag`` (and
    its SVG twin exists, when ``svg``)."""
    return (path.exists() and (not svg or path.with_suffix(".svg").exists())
            and png_tag(path) == tag)


def table3_inputs() -> str:
    """What the Table 3 figure depends on besides the report's code: table3.py and its data (read,
    not imported: a warm report solves nothing)."""
    source = Path(__file__).with_name("table3.py")
    data = source.parent / "data" / "djerassi-table3.csv"
    return hashlib.sha256(source.read_bytes() + data.read_bytes()).hexdigest()


def table3_payload() -> list[str]:
    """The inputs of the Table 3 figure: :func:`table3_inputs` and the solver's code."""
    return [table3_inputs(), solver_digest()]


@functools.cache
def solver_digest() -> str:
    """The sha256 of the modules of ``planar_impact`` and its subpackages (read, not
    imported), which solves what the Table 3 reproduction shows."""
    from importlib.util import find_spec

    spec = find_spec("planar_impact")
    digest = hashlib.sha256()
    for folder in (spec.submodule_search_locations or []) if spec else []:
        for path in sorted(Path(folder).rglob("*.py")):
            name = path.relative_to(folder).as_posix()
            digest.update(name.encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()
