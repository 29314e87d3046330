"""The report's further pages: the benchmarks (``bench.html``) and the stress test
(``stress.html``), rendered from what ``impact-harness bench`` and ``impact-harness stress``
wrote (``bench.json`` in ``bench/``, ``stress.md`` in ``stress/``) when those files exist.

Their figures are copied into ``<out>/bench/`` and ``<out>/stress/`` so that the report
directory stays self-contained whatever directory the inputs came from.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path

from harness.report.markup import html_table, markdown_to_html, page_head
from harness.report.views import escape_html
from harness.store.files import make_inner_directory, write_bytes_atomically, write_text_atomically
from harness.store.identity import code_version_of

BENCH_PAGE, STRESS_PAGE = "bench.html", "stress.html"
PAGE_TITLES = {BENCH_PAGE: "Benchmarks: speed and accuracy",
               STRESS_PAGE: "Stress test: the solver and the engines at extremes"}


def find_input(kind: str, file: str, sources: Sequence[Path]) -> Path | None:
    """The first ``<source>/<kind>/<file>`` that exists."""
    for source in sources:
        path = Path(source) / kind / file
        if path.is_file():
            return path
    return None


#: The directories of ``out`` the bench and stress pages copy their figures into.
PAGE_DIRECTORIES = ("bench", "stress")


def copy_figures(source_dir: Path, target_dir: Path) -> list[str]:
    """Copy the PNG (and SVG) figures of ``source_dir`` into ``target_dir`` (made in its
    parent, never through a link); PNG names."""
    make_inner_directory(target_dir.parent, target_dir.name)
    names = []
    for figure in sorted(source_dir.glob("*.png")) + sorted(source_dir.glob("*.svg")):
        target = target_dir / figure.name
        if figure.resolve() != target.resolve():
            write_bytes_atomically(target, figure.read_bytes())  # over a regular file only
        if figure.suffix == ".png":
            names.append(figure.name)
    return names


def fmt_value(value) -> str:
    """A JSON value as a short cell."""
    if isinstance(value, bool) or value is None:
        return "–" if value is None else ("yes" if value else "no")
    if isinstance(value, float):
        if not math.isfinite(value):
            return "nan"
        return f"{value:.4g}"
    if isinstance(value, (dict, list)):
        return escape_html(json.dumps(value))
    return escape_html(value)


def is_scalar(value) -> bool:
    return not isinstance(value, (dict, list))


def json_html(data, title: str, level: int = 2) -> list[str]:
    """A JSON tree as headings and tables: scalars in a key/value table, a list of records
    as one table, a dict whose values are all flat records as one table keyed by name."""
    heading = f"h{min(level, 6)}"
    parts = [f"<{heading}>{escape_html(title)}</{heading}>"] if title else []
    if isinstance(data, list):
        if data and all(isinstance(item, dict) for item in data):
            columns = list(dict.fromkeys(key for item in data for key, value in item.items()
                                         if is_scalar(value)))
            parts.append(html_table(columns, [[fmt_value(item.get(c)) for c in columns]
                                              for item in data], left=0))
        else:
            parts.append(f"<p>{fmt_value(data)}</p>")
        return parts
    if not isinstance(data, dict):
        return parts + [f"<p>{fmt_value(data)}</p>"]
    scalars = {k: v for k, v in data.items() if is_scalar(v)}
    if scalars:
        parts.append(html_table(["item", "value"], [[escape_html(k), fmt_value(v)]
                                                    for k, v in scalars.items()], left=2))
    nested = {k: v for k, v in data.items() if not is_scalar(v)}
    flat_records = nested and all(isinstance(v, dict) and all(map(is_scalar, v.values()))
                                  for v in nested.values())
    if flat_records and len(nested) > 1:
        columns = list(dict.fromkeys(key for value in nested.values() for key in value))
        parts.append(html_table(["name", *columns],
                                [[escape_html(name), *(fmt_value(value.get(c)) for c in columns)]
                                 for name, value in nested.items()]))
        return parts
    for key, value in nested.items():
        parts += json_html(value, str(key), level + 1)
    return parts


#: What to read in each figure of the bench and stress pages, by file name (``{engine}``: the
#: part of the name after the prefix). A figure without an entry is captioned by its name.
CAPTIONS = {
    "pareto-": ("{engine}: the wall time per impact against the departure, one point per "
                "setting and family. Blue: the departure from the engine's own law, grey and "
                "gold: from Poisson and Stronge; the step line is the Pareto front of the blue "
                "points, numbered, with each number's setting listed under its panel. Read the "
                "leftmost point below a dotted line (1%, 0.1%): the cheapest setting that "
                "reaches that accuracy."),
    "solver-throughput": ("Problems solved per second by <code>solve_batch</code> against the "
                          "batch size, per law; the dotted line is the pure-Python exact "
                          "impulse process, one problem at a time."),
    "engine-grid": ("Each engine and preset (rows; an engine not installed is a row of its "
                    "own) on each stress case (columns, with units; the disk above, the rod "
                    "below): the outcome of its run, the first that applies, coloured as the "
                    "key says."),
    "solver-energy": ("Per stress family, the largest relative change of kinetic energy "
                      "against the family's parameter, for Poisson, Stronge and Newton, on a "
                      "symmetric log scale: above zero is a gain."),
    "solver-boundary-jumps": ("Per boundary of Table 1, the solution's jump when the "
                              "problem crosses it by a tiny step, per law: a jump that does "
                              "not shrink with the step is a discontinuity of the law."),
}


def caption(name: str) -> str:
    """The caption of a page figure (:data:`CAPTIONS`), else its file name."""
    stem = Path(name).stem
    for prefix, text in CAPTIONS.items():
        if stem.startswith(prefix):
            return text.format(engine=escape_html(stem.removeprefix(prefix)))
    return escape_html(name)


def figures_html(directory: str, names: Sequence[str]) -> str:
    return "\n".join(f'<figure><img src="{directory}/{escape_html(name)}" '
                     f'alt="{escape_html(name)}"><figcaption>{caption(name)}</figcaption>'
                     "</figure>" for name in names)


def write_page(out_dir: Path, file: str, body: Sequence[str]) -> Path:
    title = PAGE_TITLES[file]
    parts = [page_head(title), ("<p class='back'><a href='index.html'>← back to the report</a>"
             "</p>"), f"<h1>{escape_html(title)}</h1>", *body,
             "<p class='back'><a href='index.html'>← back to the report</a></p></body></html>"]
    path = out_dir / file
    write_text_atomically(path, "\n".join(parts))  # over a regular file only
    return path


def provenance_html(made: dict, report: dict, command: str, page: str | None = None) -> str:
    """Where a page's numbers come from (commit, date, machine) and, when that differs from
    the report's own results (or, for ``page``, its command's code from today's), a warning
    that they may be stale and how to refresh them."""
    commit = ((made.get("git") or {}).get("commit") or "")[:10]
    dirty = " with uncommitted changes" if (made.get("git") or {}).get("dirty") else ""
    when = made.get("created_utc") or made.get("time") or "an unknown date"
    machine = made.get("machine")
    machine = machine.get("cpu_model") or machine.get("machine") if isinstance(machine, dict) \
        else machine
    text = (f"Measured {escape_html(when)}"
            + (f" at commit <code>{escape_html(commit)}</code>{dirty}" if commit
               else " (commit not recorded)")
            + (f" on {escape_html(machine)}" if machine else "") + ".")
    # compared by the code's digest, not the commit: a commit of docs only, or a rerun of
    # the suite, leaves the page as it was; an edit of the code makes the numbers stale
    made_code, report_code = made.get("code_version"), report.get("code_version")
    if report_code and made_code != report_code:  # (not the report's commit: it moves)
        text += (" <b>Older than the report</b>: "
                 + ("measured with other code than" if made_code else
                    "its code version is not recorded, so it may predate")
                 + f" the report's results; <code>{escape_html(command)}</code> measures "
                 "them again.")
    elif page is not None and not command_code_holds(made, page):
        text += (f" <b>Older than the report</b>: measured by another version of "
                 f"<code>harness/{PAGE_CODE[page]}/</code> than today's; "
                 f"<code>{escape_html(command)}</code> measures them again.")
    return f"<p class='provenance'>{text}</p>"


def write_bench_page(bench_json: Path, out_dir: Path, report: dict | None = None) -> Path:
    """``bench.html`` from ``bench.json`` and the figures beside it; ``report``: the
    report's results' provenance (the page says when it is older)."""
    data = json.loads(bench_json.read_text(encoding="utf-8"))
    names = copy_figures(bench_json.parent, out_dir / PAGE_DIRECTORIES[0])
    body = [provenance_html(data.get("provenance") or {}, report or {},
                            PAGE_COMMANDS[BENCH_PAGE], BENCH_PAGE),
            ("<p>Written by <code>impact-harness bench</code>; machine-readable: "
             "<a href='bench/bench.json'>bench.json</a>.</p>"), figures_html("bench", names)]
    copy = out_dir / "bench" / "bench.json"
    if bench_json.resolve() != copy.resolve():
        write_bytes_atomically(copy, bench_json.read_bytes())
    scalars = {key: value for key, value in data.items() if is_scalar(value)}
    if scalars:  # top-level flags (quick …) in one table, not a heading each
        body += json_html(scalars, "this run", 2)
    for key, value in data.items():
        if not is_scalar(value):
            body += json_html(value, key.replace("_", " "), 2)
    return write_page(out_dir, BENCH_PAGE, body)


def write_stress_page(stress_md: Path, out_dir: Path, report: dict | None = None) -> Path:
    """``stress.html`` from ``stress.md`` (and the provenance of ``stress.json`` beside it)
    and the figures beside it."""
    names = copy_figures(stress_md.parent, out_dir / PAGE_DIRECTORIES[1])
    made = made_by(stress_md.parent / "stress.json")
    text = stress_md.read_text(encoding="utf-8")
    lines = text.splitlines()
    if lines and lines[0].startswith("# "):  # the page has its own title
        text = "\n".join(lines[1:])
    body = [provenance_html(made, report or {}, PAGE_COMMANDS[STRESS_PAGE], STRESS_PAGE),
            markdown_to_html(text, heading_shift=1), "<h2>Figures</h2>",
            figures_html("stress", names)]
    return write_page(out_dir, STRESS_PAGE, body)


#: The command that measures each page again (``make validate`` does not: minutes each).
PAGE_COMMANDS = {BENCH_PAGE: "make bench", STRESS_PAGE: "make stress"}


#: The command package behind each page, whose code makes its numbers beside the cached
#: code that ``code_version`` hashes (the solver, the engines' adapters, the scenes).
PAGE_CODE = {BENCH_PAGE: "bench", STRESS_PAGE: "stress"}
_HARNESS_DIR = Path(__file__).resolve().parent.parent  # harness/, from harness/report/


def command_code_version(package: str) -> str:
    """The SHA-256 of ``harness/<package>/`` today, as :func:`code_version_of` hashes code;
    ``bench`` and ``stress`` record theirs in their provenance (``command_code_version``)."""
    return code_version_of((_HARNESS_DIR / package,))


def command_code_holds(made: dict, page: str) -> bool:
    """Whether the command code a page was measured by is today's: a file that does not
    record it (written before it was recorded) is judged by ``code_version`` alone."""
    recorded = made.get("command_code_version")
    return recorded is None or recorded == command_code_version(PAGE_CODE[page])


def is_current(made: dict, report: dict, page: str | None = None) -> bool:
    """Whether a page measured with provenance ``made`` holds for the report's results
    (provenance ``report``): made by the same code (its digest, not the commit, which a
    change of docs moves) and, for ``page``, by today's code of its command
    (:func:`command_code_holds`)."""
    return (bool(made.get("code_version"))
            and made.get("code_version") == report.get("code_version")
            and (page is None or command_code_holds(made, page)))


def made_by(json_file: Path) -> dict:
    """The provenance a page's JSON input (``bench.json``, ``stress.json``) records; {}
    when it is missing or unreadable."""
    try:
        made = json.loads(json_file.read_text(encoding="utf-8")).get("provenance")
    except (OSError, ValueError, AttributeError):
        return {}
    return made if isinstance(made, dict) else {}


def write_pages(out_dir: Path, sources: Sequence[Path], report: dict | None = None
                ) -> tuple[dict[str, str], dict[str, str]]:
    """Write the pages whose inputs exist; returns ``({file: title}, {title: why})``: the
    pages the report links, those made by the report's code, and those it names without a
    link, older than its results (each written anyway, saying so at its top). ``report``:
    the provenance of the report's results, which each page compares its own with."""
    report = report or {}
    linked, stale = {}, {}
    inputs = {BENCH_PAGE: (find_input("bench", "bench.json", [out_dir, *sources]), "bench.json"),
              STRESS_PAGE: (find_input("stress", "stress.md", [out_dir, *sources]),
                            "stress.json")}
    for page, (found, provenance_file) in inputs.items():
        if found is None:
            continue
        (write_bench_page if page == BENCH_PAGE else write_stress_page)(found, out_dir, report)
        made = made_by(found.parent / provenance_file)
        if is_current(made, report, page):
            linked[page] = PAGE_TITLES[page]
        else:
            when = made.get("created_utc") or made.get("time") or "at an unknown date"
            other = ("other code than these results"
                     if made.get("code_version") != report.get("code_version") or
                     not made.get("code_version")
                     else f"another version of harness/{PAGE_CODE[page]}/ than today's")
            stale[PAGE_TITLES[page]] = (f"measured {escape_html(when)} with {other}; <code>"
                                        f"{PAGE_COMMANDS[page]}</code> then <code>"
                                        "impact-harness report</code> measure and link it")
    return linked, stale
