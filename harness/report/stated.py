"""Numbers the README and ``docs/`` state about results, each produced by a named command.

A stated number is marked in the Markdown so that it can be found, regenerated and compared:

* inline, an HTML comment right after the number (no space between them), naming the source
  and the key: ``67<!-- stated table3.reproduced -->``. The number is the run of digits
  (with a sign, ``,`` ``.``, an exponent and a trailing ``%``) that ends where the comment
  begins;
* a generated block (a whole table) between two comments on lines of their own::

      <!-- begin stated flat-landings.table -->
      ...
      <!-- end stated -->

Each source (:data:`SOURCES`) names the command a reader runs to get the same numbers and
computes them as ``{key: text}``. ``impact-harness findings --check`` recomputes every source
the text marks and lists each stated number that differs (exit 1);
``impact-harness findings --write`` rewrites them in place. ``tests/report/test_stated.py``
runs the check, so a number cannot go stale silently: a change to the code that moves it
fails the tests until ``--write`` is run and the change reviewed.

The ``library`` source counts the engine runs of the validation suite; it is read from a
results file (``reports/results.json``, written by ``make validate``), and its test compares
the text with a fresh run of the library (tests/run/test_suite_invariants.py).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

from harness.engines import ENGINE_NAMES, source_label
from harness.experiments import drops_engines, registry
from harness.reference.flat_faces import count_flat
from harness.report import experiments, findings
from harness.report.table3 import computed_cells, printed_du_residual, reproduce_table3
from harness.report.views import fmt_departure
from harness.run.records import ANALYTIC, read_results
from harness.run.references import point_reference
from harness.run.verdicts import reason_counts
from harness.scenarios import load_scenario
from harness.store.files import write_text_atomically
from harness.stress import engines as stress_engines
from harness.survey import cli as survey_cli
from harness.survey.population import resolve_populations
from planar_impact.multicontact.families import scan as multicontact_scan
from planar_impact.simultaneous import coherent_count_distribution

ROOT = Path(__file__).resolve().parents[2]
# The texts that state results (paths relative to the repository root).
TEXTS = ("README.md", "docs/*.md", "scenarios/README.md")

_NUMBER = r"[-+−]?\d[\d,.]*(?:e[-−]?\d+)?%?"
_KEY = r"[A-Za-z0-9][A-Za-z0-9_.+-]*"
INLINE = re.compile(rf"(?P<value>{_NUMBER})<!-- stated (?P<key>{_KEY}) -->")
BLOCK = re.compile(rf"^<!-- begin stated (?P<key>{_KEY}) -->\n(?P<value>.*?)^<!-- end stated -->$",
                   re.M | re.S)
ANY_MARKER = re.compile(r"<!-- (?:begin |end )?stated\b[^>]*-->")


@dataclass(frozen=True)
class Source:
    """Where a group of stated numbers comes from: the command a reader runs, and the
    function that computes them (``{key: text}``, keys without the source's prefix)."""

    command: str
    compute: Callable[[], dict[str, str]]


@dataclass(frozen=True)
class Stated:
    """One marked number (or block) in a text."""

    path: Path
    line: int
    key: str  # "source.key"
    value: str
    block: bool

    @property
    def source(self) -> str:
        return self.key.split(".", 1)[0]

    @property
    def where(self) -> str:
        return f"{shown(self.path)}:{self.line}"


def shown(path: Path) -> Path:
    """``path`` relative to the repository when inside it."""
    return path.relative_to(ROOT) if path.is_relative_to(ROOT) else path


def share(part: int, whole: int, digits: int = 0) -> str:
    """``part/whole`` as a percentage with ``digits`` decimals."""
    return f"{100.0 * part / whole:.{digits}f}%"


def findings_numbers(count: int = 100_000, seed: int = 2009) -> dict[str, str]:
    """``impact-harness findings``: the solver findings of the README."""
    measured = findings.measure(count, seed)
    numbers = {"count": f"{count:,}"}
    bins = measured["pgs_bins"]
    above = [b for b in bins if b["low"] >= 1.0]
    below = [b for b in bins if b["high"] <= 0.9]
    edge = [b for b in bins if b["low"] == 0.9]
    numbers["pgs.above"] = f"{sum(b['problems'] for b in above):,}"
    numbers["pgs.above-failed"] = f"{sum(b['failed'] for b in above):,}"
    numbers["pgs.below"] = f"{sum(b['problems'] for b in below):,}"
    numbers["pgs.below-failed"] = f"{sum(b['failed'] for b in below):,}"
    numbers["pgs.edge"] = f"{sum(b['problems'] for b in edge):,}"
    numbers["pgs.edge-failed"] = f"{sum(b['failed'] for b in edge):,}"
    jump = measured["jump"]
    numbers["jump.problems"] = f"{jump['problems']:,}"
    numbers["jump.share"] = share(jump["large"], jump["problems"], 1)
    numbers["jump.median-e-below"] = f"{jump['median_e_below']:.3g}"
    numbers["jump.median-jump"] = f"{jump['median_jump']:.0%}"
    for law, counts in measured["energy"].items():
        numbers[f"energy.{law}"] = share(counts["gained"], counts["solved"], 2)
        numbers[f"energy.{law}.rounded"] = share(counts["gained"], counts["solved"], 0)
        numbers[f"energy.{law}.gained"] = f"{counts['gained']:,}"
    return numbers


def signed(value: float, decimals: int) -> str:
    """``value`` with ``decimals`` decimals and a typographic minus, as the docs print it."""
    return f"{value:.{decimals}f}".replace("-", "−")


def table3_numbers() -> dict[str, str]:
    """``impact-harness paper``: how many of Table 3's printed cells reproduce; each cell's
    computed value as the report prints it (``LAW.ROW.CELL``, and ``…​.3`` to 3 decimals);
    the exact Stronge law's Δu and ΔE on the Stronge rows (``exact-stronge.ROW.CELL``); the
    distance of the printed Stronge Δu from the reachable ones and the nearest ``e_i``."""
    rows = reproduce_table3()
    cells = [c for row in rows for c in row["cells"]]
    reproduced = sum(c.reproduced for c in cells)
    numbers = {"printed": str(len(cells)), "reproduced": str(reproduced),
               "missed": str(len(cells) - reproduced)}
    for c in cells:
        numbers[f"{c.law}.{c.row}.{c.name}"] = signed(c.computed, max(c.decimals, 1) + 1)
        numbers[f"{c.law}.{c.row}.{c.name}.3"] = signed(c.computed, 3)
    for row in rows:
        if row["law"] != "stronge":
            continue
        exact = computed_cells(row["solutions"]["stronge"])
        for name in ("du1", "du3", "du4", "du6", "dE"):
            numbers[f"exact-stronge.{row['index']}.{name}"] = signed(exact[name], 4)
        distance, nearest_e = printed_du_residual(row["row"])
        numbers[f"stronge.{row['index']}.du-distance"] = signed(distance, 3)
        numbers[f"stronge.{row['index']}.du-distance.1"] = signed(distance, 1)
        numbers[f"stronge.{row['index']}.du-nearest-e"] = signed(nearest_e, 3)
    return numbers


TWO_CONTACT_PROBLEMS, TWO_CONTACT_SEED = 200, 0
_COUNT_LAWS = (("poisson", "Poisson"), ("stronge-paper", "Stronge (paper)"), ("newton", "Newton"))
#: The readings of the paper's proposal, as the texts name them (harness and planar_impact
#: call them by the coupling: ``literal`` is the paper's, ``effective`` our extension).
_READINGS = (("literal", "literal (the paper's)"), ("effective", "effective (extension)"))


def two_contact_numbers() -> dict[str, str]:
    """``python -m planar_impact.simultaneous 200 0``: per family (``generic``, ``body``),
    the coherent solutions of the paper's proposal under both readings, and Newton–Coulomb's
    (``FAMILY.READING.LAW.BUCKET``, ``FAMILY.newton-coulomb.BUCKET``, and ``…-share``)."""
    problems = TWO_CONTACT_PROBLEMS
    numbers = {"problems": str(problems)}
    rows = ["| family | reading | law | 0 solutions | 1 | 2+ | at boundary | gains |",
            "|---|---|---|---:|---:|---:|---:|---:|"]
    for family in ("generic", "body"):
        for coupling, reading in _READINGS:
            counts = coherent_count_distribution(problems, TWO_CONTACT_SEED, family, coupling)
            for law, name in _COUNT_LAWS:
                c = counts[law]
                rows.append(f"| {family} | {reading} | {name} | {c['0']} | {c['1']} | "
                            f"{c['2+']} | {c['boundary']} | {c['gains']} |")
                for bucket in ("0", "1", "2+", "boundary", "gains"):
                    numbers[f"{family}.{coupling}.{law}.{bucket}"] = str(c[bucket])
                    numbers[f"{family}.{coupling}.{law}.{bucket}-share"] = share(c[bucket],
                                                                                problems)
        c = counts["newton-coulomb"]  # the same under either reading
        rows.append(f"| {family} | — | Newton–Coulomb | {c['0']} | {c['1']} | {c['2+']} | "
                    f"— | {c['gains']} |")
        for bucket in ("0", "1", "2+", "gains"):
            numbers[f"{family}.newton-coulomb.{bucket}"] = str(c[bucket])
    numbers["table"] = "\n".join(rows)
    return numbers


FLAT_LANDINGS, FLAT_SEED = 200, 0


def flat_landing_numbers() -> dict[str, str]:
    """``python -m harness.reference.flat_faces 200 0``: coherent solutions on random flat
    landings, those at the boundary of a decision apart, Newton–Coulomb's and the two-phase
    Poisson law's solutions with distinct velocities and Newton–Coulomb's non-unique impulse
    splits; per law the draws with a solution that breaks admissibility or gains energy."""
    counts, _ = count_flat(FLAT_LANDINGS, FLAT_SEED)
    numbers = {"landings": str(FLAT_LANDINGS)}
    rows = ["| law | reading | 0 | 1 | 2+ | at boundary | split not unique | inadmissible "
            "| gains |",
            "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    buckets = ("0", "1", "2+", "boundary", "inadmissible", "gains")
    for law, name in _COUNT_LAWS:
        for coupling, reading in _READINGS:
            c = counts[f"{law}/{coupling}"]
            rows.append(f"| {name} | {reading} | {c['0']} | {c['1']} | {c['2+']} | "
                        f"{c['boundary']} | | {c['inadmissible']} | {c['gains']} |")
            for bucket in buckets:
                numbers[f"{coupling}.{law}.{bucket}"] = str(c[bucket])
                numbers[f"{coupling}.{law}.{bucket}-share"] = share(c[bucket], FLAT_LANDINGS)
    for key, name in (("newton-coulomb", "Newton–Coulomb"),
                      ("two-phase/poisson", "two-phase Poisson")):
        c = counts[key]
        split = f" {c['split']} " if key == "newton-coulomb" else " "
        rows.append(f"| {name} | — | {c['0']} | {c['1']} | {c['2+']} | |{split}| "
                    f"{c['inadmissible']} | {c['gains']} |")
        for bucket in ("0", "1", "2+", "split", "inadmissible", "gains"):
            stem = key.replace("/", "-")
            numbers[f"{stem}.{bucket}"] = str(c[bucket])
            numbers[f"{stem}.{bucket}-share"] = share(c[bucket], FLAT_LANDINGS)
        numbers[f"{stem}.max-gain"] = f"{100 * c['max-gain']:.0f}%"
    numbers["table"] = "\n".join(rows)
    return numbers


ADMISSIBLE_DRAWS, ADMISSIBLE_SEED = 500, 0
#: The references of :func:`planar_impact.multicontact.families.scan`, as the table names them.
_ADMISSIBLE_ROWS = (
    ("newton-coulomb", "Newton–Coulomb"), ("two-phase/poisson", "two-phase Poisson"),
    ("coherent/poisson/literal", "Poisson, literal (the paper's)"),
    ("coherent/stronge-paper/literal", "Stronge (paper), literal"),
    ("coherent/newton/literal", "Newton, literal"),
    ("coherent/poisson/effective", "Poisson, effective (extension)"),
    ("coherent/stronge-paper/effective", "Stronge (paper), effective"),
    ("coherent/newton/effective", "Newton, effective"),
    ("sequential/newton-lcp", "sequential, newton-lcp (both orders)"),
    ("sequential/poisson", "sequential, Poisson (both orders)"))


def admissible_numbers() -> dict[str, str]:
    """``python -m planar_impact.multicontact admissible 500 0``: per m-contact reference on
    broad flat landings, its solutions, the inadmissible ones, those that gain energy and
    the draws with one that gains (``NAME.BUCKET``, ``/`` in names as ``-``)."""
    table = multicontact_scan(ADMISSIBLE_DRAWS, ADMISSIBLE_SEED)
    numbers = {"draws": f"{ADMISSIBLE_DRAWS:,}"}
    rows = ["| reference | solutions | inadmissible | gain energy | draws with a gain | "
            "draws with several |", "|---|---:|---:|---:|---:|---:|"]
    for key, name in _ADMISSIBLE_ROWS:
        c = table.get(key, dict.fromkeys(("solutions", "inadmissible", "gains",
                                          "draws-gaining", "draws-several"), 0))
        rows.append(f"| {name} | {c['solutions']} | {c['inadmissible']} | {c['gains']} | "
                    f"{c['draws-gaining']} | {c['draws-several']} |")
        stem = key.replace("/", "-")
        for bucket, value in c.items():
            numbers[f"{stem}.{bucket}"] = str(value)
        numbers[f"{stem}.draws-gaining-share"] = share(c["draws-gaining"], ADMISSIBLE_DRAWS, 1)
    numbers["table"] = "\n".join(rows)
    return numbers


#: The library's flat scenes whose solution counts the texts state.
FLAT_SCENES = ("flat-box", "flat-box-receding-end")


def flat_scene_numbers() -> dict[str, str]:
    """The coherent solutions of the library's flat scenes (``NAME.LAW.READING``, and
    ``NAME.LAW.READING.at-boundary``), as the runner's references count them."""
    numbers = {}
    for name in FLAT_SCENES:
        reference = point_reference(load_scenario(ROOT / "scenarios" / f"{name}.toml"), None)
        for key, count in reference["solutions"].items():
            parts = key.split("/")
            if parts[0] == "coherent":
                numbers[".".join([name, *parts[1:]])] = str(count)
    return numbers


MUJOCO_GAIN_SAMPLES, MUJOCO_GAIN_SEED = 200, 0
MUJOCO_GAIN_POPULATIONS = ("populations/rod-ground.toml", "populations/box-corner.toml")


def mujoco_gain_numbers() -> dict[str, str]:
    """``impact-harness survey populations/rod-ground.toml populations/box-corner.toml
    --samples 200 --engines mujoco --preset defaults,accurate``: how often MuJoCo's runs end
    with more kinetic energy than they began with, per preset and family, and by how much."""
    import numpy as np


    survey = survey_cli.run_survey(
        resolve_populations([str(ROOT / p) for p in MUJOCO_GAIN_POPULATIONS]),
        MUJOCO_GAIN_SAMPLES, MUJOCO_GAIN_SEED, ["mujoco"], ["defaults", "accurate"],
        workers=1, echo=lambda _: None)
    runs = {key: np.asarray(values) for key, values in survey["runs"].items()}
    numbers = {"samples": str(MUJOCO_GAIN_SAMPLES)}
    for preset in ("defaults", "accurate"):
        chosen = runs["preset"] == preset
        gains = runs["gains_energy"][chosen].astype(bool)
        numbers[f"{preset}.runs"] = str(int(chosen.sum()))
        numbers[f"{preset}.gains"] = str(int(gains.sum()))
        numbers[f"{preset}.share"] = share(int(gains.sum()), int(chosen.sum()), 1)
        for family in sorted(set(runs["family"][chosen].tolist())):
            member = runs["family"][chosen] == family
            numbers[f"{preset}.{family}.share"] = share(int(gains[member].sum()),
                                                       int(member.sum()), 1)
        if gains.any():
            change = runs["energy_change_relative"][chosen][gains]
            numbers[f"{preset}.max-gain"] = f"+{change.max():.0%}"
            numbers[f"{preset}.median-gain"] = f"+{np.median(change):.0%}"
            numbers[f"{preset}.least-e"] = f"{runs['e'][chosen][gains].min():.2f}"
    return numbers


RESULTS = ROOT / "reports" / "results.json"


def library_numbers_of(records: Iterable, scenarios: int) -> dict[str, str]:
    """The validation suite's counts from its records: scenarios, records, engine runs,
    single impacts and the runs per verdict reason (as ``summary.md`` counts them)."""
    records = list(records)
    engine_runs = [r for r in records if r.source != ANALYTIC and not r.skipped]
    single = sum(r.ok for r in engine_runs)
    numbers = {"scenarios": str(scenarios), "records": f"{len(records):,}",
               "engine-runs": str(len(engine_runs)), "single-impacts": str(single),
               "flagged": str(len(engine_runs) - single)}
    for reason, count in reason_counts([r.reasons for r in engine_runs]).items():
        numbers[f"reason.{reason.replace(' (law)', '-law')}"] = str(count)
    numbers.update(flat_face_numbers(engine_runs))
    numbers.update(group_numbers(engine_runs))
    numbers.update(departure_numbers(engine_runs))
    return numbers


def departure_numbers(engine_runs) -> dict[str, str]:
    """Every single impact's departure from each law on the scenarios of one point, as the
    report prints it: ``departure.SCENARIO.ENGINE.PRESET.LAW`` (``28.9%``)."""
    numbers = {}
    for run in engine_runs:
        if run.ok and not run.point.get("label") and run.departure:
            for law, value in run.departure.items():
                key = f"departure.{run.scenario}.{run.source}.{run.preset}.{law}"
                numbers[key] = fmt_departure(value)
    return numbers


FLAT_FACES = ("flat-box", "flat-box-slip", "flat-box-spin", "flat-rod")


def flat_face_numbers(engine_runs) -> dict[str, str]:
    """docs/multi-contact.md, 'Engines on a flat face': the engines' departures from their
    primary reference on the library's flat faces and on the tilt sweep of the box
    (``flat.…`` and ``tilt.…`` keys), in percent as the report writes them."""

    def departures(scenarios, engine, preset, keep=lambda run: True, reference=None):
        values = []
        for run in engine_runs:
            if not (run.scenario in scenarios and run.source == engine
                    and run.preset == preset and keep(run)):
                continue
            summary = (run.diagnostics or {}).get("reference") or {}
            values.append(summary["departure_from_primary"] if reference is None
                          else min(value for name, value in run.departure.items()
                                   if name.startswith(reference)))
        return values

    numbers = {}
    pymunk = departures(FLAT_FACES, "pymunk", "defaults")
    numbers["flat.pymunk-defaults.max"] = fmt_departure(max(pymunk))
    pybullet = departures(FLAT_FACES, "pybullet", "accurate")
    numbers["flat.pybullet-accurate.min"] = fmt_departure(min(pybullet))
    numbers["flat.pybullet-accurate.max"] = fmt_departure(max(pybullet))
    numbers["flat.mujoco-accurate.flat-box"] = fmt_departure(
        departures(FLAT_FACES[:1], "mujoco", "accurate")[0])
    turning = departures(FLAT_FACES[1:], "mujoco", "accurate")
    numbers["flat.mujoco-accurate.min"] = fmt_departure(min(turning))
    numbers["flat.mujoco-accurate.max"] = fmt_departure(max(turning))
    receding = ("flat-box-receding-end",)
    numbers["flat.receding-end.pymunk"] = fmt_departure(
        max(departures(receding, "pymunk", "accurate")))
    numbers["flat.receding-end.pymunk-sequential"] = fmt_departure(
        max(departures(receding, "pymunk", "accurate", reference="sequential/")))
    tilt = ("sweep-tilted-box",)

    def up_to(degrees):
        return lambda run: float(run.point["value"]) <= degrees

    followed = departures(tilt, "pymunk", "accurate", up_to(1.0))
    numbers["tilt.pymunk.min"] = fmt_departure(min(followed))
    numbers["tilt.pymunk.max"] = fmt_departure(max(followed))
    return numbers


#: Groups of the library's scenarios whose verdict counts docs/verdicts.md states:
#: ``group.NAME.runs``, ``….single``, ``….flagged`` and ``….reason.REASON``.
GROUPS = {"flat": ("flat-",), "tilts": ("sweep-tilted-",)}


def group_numbers(engine_runs) -> dict[str, str]:
    """Verdict counts of the engine runs of each :data:`GROUPS` (scenario name prefixes)."""
    numbers = {}
    for group, prefixes in GROUPS.items():
        runs = [run for run in engine_runs if run.scenario.startswith(prefixes)]
        single = sum(run.ok for run in runs)
        numbers.update({f"group.{group}.runs": str(len(runs)),
                        f"group.{group}.single": str(single),
                        f"group.{group}.flagged": str(len(runs) - single)})
        for reason, count in reason_counts([run.reasons for run in runs]).items():
            numbers[f"group.{group}.reason.{reason.replace(' (law)', '-law')}"] = str(count)
    return numbers


def ellipse_contact_numbers() -> dict[str, str]:
    """Each engine's ellipse against the true one: the table, and per engine and preset
    role the largest moment-arm and height errors of its single impacts (mm, 3 digits)."""
    rows, results = drops_engines.contact_error_table(ENGINE_NAMES)
    numbers = {"table": "\n".join(rows)}
    for result in results:
        for part in ("arm", "height"):
            worst = result[part]["max_ok"]
            if worst is not None and worst >= drops_engines.ROUNDING_LEVEL:
                key = f"{result['engine']}.{result['preset']}.{part}"
                numbers[key] = f"{worst * 1e3:.3g}"
    return numbers


def stress_numbers() -> dict[str, str]:
    """``impact-harness stress --quick``, its engine runs (read from the result cache when
    run before): the table of outcomes per engine and preset (docs/stress.md), and each count
    as ``ENGINE.PRESET.OUTCOME`` (the preset's role: ``mujoco.accurate.no-contact``), with
    ``cases`` (runs per engine and preset)."""
    report = stress_engines.engine_stress(quick=True)
    cases = len(stress_engines.engine_cases(quick=True))
    numbers = {"cases": str(cases), "engine-runs": str(len(report["runs"]))}
    rows = ["| engine.preset | runs | ok | not ok, by outcome (the first that applies) |",
            "|---|---:|---:|---|"]
    for name in report["versions"]:
        for role in report["presets"]:
            counts = report["counts"][source_label(name, role)]
            for outcome, count in counts.items():
                numbers[f"{name}.{role}.{outcome}"] = str(count)
            bad = ", ".join(f"{outcome} {count}" for outcome, count in counts.items()
                            if count and outcome != "ok")
            rows.append(f"| {source_label(name, role)} | {sum(counts.values())} | "
                        f"{counts['ok']} | {bad or '–'} |")
    rows += [f"| {name} | – | – | not installed: {reason} |"
             for name, reason in report["skipped"].items()]
    numbers["table"] = "\n".join(rows)
    return numbers


class Unavailable(Exception):
    """A source whose inputs are not on this machine (the Fazeli drops, never committed):
    its numbers are not checked, and ``findings`` says so."""


def experiments_numbers() -> dict[str, str]:
    """``impact-harness experiments`` with its defaults, on the copy of the Fazeli drops
    that ``IMPACT_HARNESS_FAZELI_DIR`` names (:func:`experiments.stated_numbers`; read from
    the result cache when computed before)."""
    try:
        return experiments.stated_numbers()
    except registry.DataMissing as missing:
        raise Unavailable(str(missing)) from None


def library_numbers(results: Path = RESULTS) -> dict[str, str]:
    """``make validate``: the counts of its results file (``reports/results.json``)."""
    records = read_results(results).records
    return library_numbers_of(records, len({r.scenario for r in records}))


SOURCES: dict[str, Source] = {
    "findings": Source("impact-harness findings", findings_numbers),
    "table3": Source("impact-harness paper", table3_numbers),
    "two-contacts": Source(f"python -m planar_impact.simultaneous {TWO_CONTACT_PROBLEMS} "
                           f"{TWO_CONTACT_SEED}", two_contact_numbers),
    "flat-landings": Source(f"python -m harness.reference.flat_faces {FLAT_LANDINGS} "
                            f"{FLAT_SEED}", flat_landing_numbers),
    "admissible": Source(f"python -m planar_impact.multicontact admissible {ADMISSIBLE_DRAWS} "
                         f"{ADMISSIBLE_SEED}", admissible_numbers),
    "flat-scenes": Source("impact-harness run scenarios/flat-box.toml "
                          "scenarios/flat-box-receding-end.toml --json R (the references "
                          "of each point in R's scenario info)", flat_scene_numbers),
    "mujoco-gain": Source("impact-harness survey " + " ".join(MUJOCO_GAIN_POPULATIONS)
                          + f" --samples {MUJOCO_GAIN_SAMPLES} --engines mujoco "
                          "--preset defaults,accurate", mujoco_gain_numbers),
    "library": Source("make validate (reports/results.json)", library_numbers),
    "experiments": Source("impact-harness experiments (its defaults, with "
                          "IMPACT_HARNESS_FAZELI_DIR set to a copy of the Fazeli drops)",
                          experiments_numbers),
    "stress": Source("impact-harness stress --quick (its engine runs)", stress_numbers),
    "ellipse-contact": Source("impact-harness experiments --engines all (its table \"Each "
                              "engine's ellipse against the true one\")",
                              ellipse_contact_numbers),
}


def texts(root: Path = ROOT) -> list[Path]:
    """The files that state results."""
    return sorted(path for pattern in TEXTS for path in root.glob(pattern))


def stated_in(path: Path) -> list[Stated]:
    """Every marked number and block of ``path``, in order. A marker that is not part of a
    well-formed inline number or block raises ``ValueError`` naming the file and line."""
    text = path.read_text(encoding="utf-8")
    found = []
    spans = []
    for pattern, block in ((INLINE, False), (BLOCK, True)):
        for match in pattern.finditer(text):
            line = text.count("\n", 0, match.start()) + 1
            value = match["value"].strip("\n") if block else match["value"]
            found.append(Stated(path, line, match["key"], value, block))
            spans.append(match.span())
    for marker in ANY_MARKER.finditer(text):
        if not any(start <= marker.start() < end for start, end in spans):
            line = text.count("\n", 0, marker.start()) + 1
            raise ValueError(f"{shown(path)}:{line}: a 'stated' marker without a number right "
                             f"before it (or a block without its end): {marker.group()}")
    return sorted(found, key=lambda s: s.line)


def compute(sources: Iterable[str], skipped: dict[str, str] | None = None) -> dict[str, str]:
    """``{"source.key": text}`` for the named sources. A source :class:`Unavailable` here
    raises, or with ``skipped`` is left out and put there with the reason."""
    numbers = {}
    for name in sources:
        try:
            computed = SOURCES[name].compute()
        except Unavailable as why:
            if skipped is None:
                raise
            skipped[name] = str(why)
            continue
        numbers.update({f"{name}.{key}": value for key, value in computed.items()})
    return numbers


def differences(stated: Iterable[Stated], numbers: Mapping[str, str]) -> list[str]:
    """One line per stated number that differs from ``numbers`` or names no key of its
    source (only sources present in ``numbers`` are compared)."""
    computed_sources = {key.split(".", 1)[0] for key in numbers}
    lines = []
    for s in stated:
        if s.source not in SOURCES:
            lines.append(f"{s.where}: unknown source {s.source!r} "
                         f"(known: {', '.join(SOURCES)})")
        elif s.source not in computed_sources:
            continue
        elif s.key not in numbers:
            lines.append(f"{s.where}: {s.key} is not a number "
                         f"`{SOURCES[s.source].command}` gives")
        elif numbers[s.key] != s.value:
            shown = "the block" if s.block else repr(s.value)
            lines.append(f"{s.where}: {s.key} states {shown}, "
                         f"`{SOURCES[s.source].command}` gives "
                         + ("another" if s.block else repr(numbers[s.key])))
    return lines


def rewrite(path: Path, numbers: Mapping[str, str]) -> bool:
    """Write ``numbers`` over the marked numbers and blocks of ``path`` (keys not in
    ``numbers`` left as they are); True when the file changed."""
    text = path.read_text(encoding="utf-8")

    def inline(match: re.Match) -> str:
        value = numbers.get(match["key"], match["value"])
        return f"{value}<!-- stated {match['key']} -->"

    def block(match: re.Match) -> str:
        if match["key"] not in numbers:
            return match.group()
        return (f"<!-- begin stated {match['key']} -->\n\n{numbers[match['key']]}\n\n"
                "<!-- end stated -->")

    new = BLOCK.sub(block, INLINE.sub(inline, text))
    if new != text:
        write_text_atomically(path, new)  # whole or not at all, never through a link
    return new != text


def check(write: bool = False, only: Iterable[str] | None = None,
          root: Path = ROOT, skipped: dict[str, str] | None = None) -> list[str]:
    """Recompute every source the texts mark (or those in ``only``), and return the stated
    numbers that differ; with ``write``, rewrite them first (and return what is still
    wrong: an unknown source or key). A source :class:`Unavailable` here is put in
    ``skipped`` with the reason (raised when ``skipped`` is None)."""
    paths = texts(root)
    stated = [s for path in paths for s in stated_in(path)]
    used = {s.source for s in stated if s.source in SOURCES}
    numbers = compute(sorted(used if only is None else used & set(only)), skipped)
    if write:
        for path in paths:
            rewrite(path, numbers)
        stated = [s for path in paths for s in stated_in(path)]
    return differences(stated, numbers)


__all__ = ["SOURCES", "Source", "Stated", "Unavailable", "check", "compute", "differences",
           "library_numbers_of", "rewrite", "stated_in", "texts"]
