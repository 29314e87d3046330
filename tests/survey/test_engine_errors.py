"""An engine that raises on some scenes of a survey: those runs are recorded ``error`` with
the exception's type and first line, left out of the statistics and listed in the summary;
every other run is the one a survey without the fault gives, bit for bit; the survey exits 4
with its tables written, and a survey resumed after losing chunks gives the same tables.

The engine is the test-only toy (tests/engines/toy_engine.py, registered by the ``toy_engine``
fixture) made to raise on chosen samples; one test runs Drake's real failure, when Drake is
installed."""

from __future__ import annotations

import json

import numpy as np
import pyarrow.parquet as pq
import pytest

from harness.cli import main
from harness.survey import cli as survey_cli
from harness.survey import statistics, stream
from harness.survey.engines import ERROR, run_engine
from harness.survey.population import resolve_populations
from harness.survey.sampling import sample_range

FAMILY = "spinning-disk"
SAMPLES = 20  # chunks of 8: (0, 8), (8, 16), (16, 20)
SEED = 3
#: The samples the faulty toy raises on: two in the first chunk (its batch is rerun scene by
#: scene), one in the last.
FAULTY = (2, 5, 17)
MESSAGE = "toy solver failed to converge (a test's fault)"
OPTIONS = [FAMILY, "--samples", str(SAMPLES), "--seed", str(SEED), "--engines", "toy",
           "--preset", "defaults,accurate", "--no-figures", "--quiet", "--workers", "1"]


def _read(path) -> dict:
    table = pq.read_table(path).to_pydict()
    if "reasons" in table:
        table["reasons"] = [",".join(item) for item in table["reasons"]]
    return {name: np.asarray(values) for name, values in table.items()}


def _equal(expected, found, name) -> None:
    expected, found = np.asarray(expected), np.asarray(found)
    if expected.dtype.kind == "f":
        assert np.array_equal(expected, found, equal_nan=True), name
    else:
        assert expected.astype(str).tolist() == found.astype(str).tolist(), name


@pytest.fixture
def faulty_toy(toy_engine, monkeypatch):
    """The toy raising, in its per-scene preparation inside ``run_many``, on the scenes of
    samples :data:`FAULTY` (told by their drawn friction and restitution); a message of two
    lines, as Drake's are."""
    from tests.engines.toy_engine import ToyEngine

    population, = resolve_populations([FAMILY])
    drawn = sample_range(population, 0, SAMPLES, SEED).samples
    chosen = {(drawn[index].scene.friction, drawn[index].scene.restitution)
              for index in FAULTY}
    assert len(chosen) == len(FAULTY)
    original = ToyEngine._prepare

    def prepare(self, world, scene, settings, start, weights):
        if (scene.friction, scene.restitution) in chosen:
            raise RuntimeError(f"{MESSAGE}\nsecond line of advice, never shown")
        return original(self, world, scene, settings, start, weights)

    monkeypatch.setattr(ToyEngine, "_prepare", prepare)
    return toy_engine


@pytest.fixture
def clean(toy_engine, tmp_path):
    """The same survey, the toy not raising."""
    out = tmp_path / "clean"
    assert main(["survey", *OPTIONS, "--out", str(out)]) == 0
    return out


def test_errored_runs_are_recorded_and_the_others_are_unchanged(clean, faulty_toy, tmp_path,
                                                                 capsys):
    out = tmp_path / "faulty"
    capsys.readouterr()
    assert main(["survey", *OPTIONS, "--out", str(out)]) == 4
    err = capsys.readouterr().err
    for preset in ("defaults", "accurate"):
        for sample in FAULTY:
            assert (f"ENGINE ERROR: toy {preset} {FAMILY} sample {sample}: RuntimeError: "
                    f"{MESSAGE}\n") in err
    assert "second line" not in err
    runs, expected = _read(out / "runs.parquet"), _read(clean / "runs.parquet")
    assert list(runs) == list(expected)
    errored = (runs["status"] == ERROR)
    assert sorted(runs["sample"][errored].tolist()) == sorted(FAULTY * 2)
    assert (runs["engine_status"][errored] == ERROR).all()
    assert set(runs["error"][errored].tolist()) == {f"RuntimeError: {MESSAGE}"}
    assert (runs["error"][~errored] == "").all()
    assert np.isnan(runs["departure_poisson"][errored]).all()
    # every other run is the clean survey's, bit for bit (its batch rerun scene by scene)
    for name in runs:
        if name != "error":
            _equal(expected[name][~errored], runs[name][~errored], name)
    # the statistics are those of the clean runs without the errored ones, plus their count
    stats = _read(out / "statistics.parquet")
    kept = statistics.statistics({name: values[~errored] for name, values in expected.items()
                                  if name in stream.STATISTICS_COLUMNS})
    assert list(kept) == list(stats)
    for name, values in kept.items():
        if name != "n_error":
            _equal(values, stats[name], name)
    every = stats["poisson_type"] == 0
    assert (stats["n"][every] == SAMPLES - len(FAULTY)).all()
    assert (stats["n_error"][every] == len(FAULTY)).all()
    assert stats["n_error"].sum() == 2 * 2 * len(FAULTY)  # per type and over all, 2 presets
    summary = (out / "summary.md").read_text(encoding="utf-8")
    assert f"**Engine errors: {2 * len(FAULTY)} runs raised**" in summary
    assert "## Engine errors (the engine raised)" in summary
    assert f"| toy defaults | {FAMILY} | {len(FAULTY)} |" in summary
    for sample in FAULTY:
        assert f"| toy accurate | {FAMILY} | {sample} | RuntimeError: {MESSAGE} |" in summary
    settings = json.loads((out / "settings.json").read_text(encoding="utf-8"))
    assert settings["engine_errors"]["runs"] == 2 * len(FAULTY)
    assert [error[2] for error in settings["engine_errors"]["shown"]] == [*FAULTY, *FAULTY]
    # the report's survey section lists them too, and its headline counts them
    from harness.report.survey import survey_section
    from harness.report.views import escape_html

    section = survey_section(out, {})
    assert "<h3>Engine errors</h3>" in section
    assert escape_html(f"RuntimeError: {MESSAGE}") in section
    assert f"; {2 * len(FAULTY)} engine errors" in section


def test_a_resumed_survey_gives_the_same_tables_and_errors(faulty_toy, tmp_path, capsys):
    out = tmp_path / "resumed"
    assert main(["survey", *OPTIONS, "--out", str(out)]) == 4
    first = {table: _read(out / table) for table in ("runs.parquet", "statistics.parquet")}
    summary = (out / "summary.md").read_text(encoding="utf-8")
    chunks = sorted((out / "dataset" / "chunks").glob("part-*.json"))
    assert len(chunks) == 3
    for record in chunks[1:]:  # killed after the first chunk: the others never finished
        record.unlink()
    (out / "statistics.parquet").unlink()
    capsys.readouterr()
    assert main(["survey", *OPTIONS, "--out", str(out)]) == 4
    assert "resuming: 1 of 3 chunks" in capsys.readouterr().out
    for table, columns in first.items():
        found = _read(out / table)
        assert list(found) == list(columns)
        for name, values in columns.items():
            _equal(values, found[name], f"{table} {name}")
    again = (out / "summary.md").read_text(encoding="utf-8")
    section = summary.split("## Engine errors")[1].split("## Rejected")[0]
    assert section == again.split("## Engine errors")[1].split("## Rejected")[0]


def test_the_survey_held_in_memory_lists_the_same_errors(faulty_toy, tmp_path):
    populations = resolve_populations([FAMILY])
    survey = survey_cli.run_survey(populations, SAMPLES, SEED, ["toy"],
                                   ["defaults", "accurate"], workers=1, echo=lambda _: None)
    out = tmp_path / "streamed"
    assert main(["survey", *OPTIONS, "--out", str(out)]) == 4
    assert survey_cli.errors_in_memory(survey) == stream.totals(out / "dataset",
                                                                populations)["errors"]
    assert (survey["statistics"]["n_error"][survey["statistics"]["poisson_type"] == 0]
            == len(FAULTY)).all()


def test_a_memory_error_stops_the_survey(toy_engine, monkeypatch):
    # Not a scene's fault: no record can say what to do about it.
    from tests.engines.toy_engine import ToyEngine

    def prepare(self, world, scene, settings, start, weights):
        raise MemoryError("test")

    monkeypatch.setattr(ToyEngine, "_prepare", prepare)
    population, = resolve_populations([FAMILY])
    scenes = [sample.scene for sample in sample_range(population, 0, 2, SEED).samples]
    with pytest.raises(MemoryError):
        run_engine(toy_engine, "defaults", scenes)


def test_drakes_failure_to_converge_is_an_engine_error(load_or_skip):
    # box-on-box-face sample 231 of seed 0: MultibodyPlant's discrete solver does not
    # converge under `accurate` (found by a 500-sample survey); ~0.1 s.
    load_or_skip("drake")
    population, = resolve_populations(["box-on-box-face"])
    scenes = [sample.scene for sample in sample_range(population, 230, 232, 0).samples]
    result = run_engine("drake", "accurate", scenes)
    assert result.status[1] == ERROR and result.engine_status[1] == ERROR
    assert result.errors[1].startswith(
        "RuntimeError: MultibodyPlant's discrete update solver failed to converge")
    assert "\n" not in result.errors[1]
    # its first sentence, not the paragraph of advice that follows on the same line
    assert result.errors[1].endswith("with discrete update period = 1e-06.")
    assert result.status[0] != ERROR and result.errors[0] == ""
    alone = run_engine("drake", "accurate", scenes[:1])
    assert np.array_equal(alone.velocities[0], result.velocities[0])


@pytest.mark.parametrize(("message", "expected"), [
    ("short. Two sentences on one short line stay", "short. Two sentences on one short "
                                                    "line stay"),
    ("a" * 200 + ". then advice. more advice", "a" * 200 + "."),
    ("b" * 200 + " without a sentence's end", "b" * 200 + " without a sentence's end"),
    ("first line\nsecond line", "first line"),
    ("", None),
])
def test_an_error_reads_as_its_type_and_first_line_or_sentence(message, expected):
    from harness.survey.engines import ERROR_TEXT_CHARACTERS, error_text

    assert len("a" * 200) > ERROR_TEXT_CHARACTERS
    text = error_text(ValueError(message))
    assert text == ("ValueError" if expected is None else f"ValueError: {expected}")


def test_the_suite_exits_4_when_its_survey_had_an_engine_error(toy_beside_the_others,
                                                               monkeypatch, tmp_path, capsys):
    from harness import suite
    from tests.engines.toy_engine import ToyEngine

    population, = resolve_populations([FAMILY])
    drawn = sample_range(population, 4, 5, 0).samples[0].scene  # the suite's seed is 0
    original = ToyEngine._prepare

    def prepare(self, world, scene, settings, start, weights):
        if (scene.friction, scene.restitution) == (drawn.friction, drawn.restitution):
            raise RuntimeError(MESSAGE)
        return original(self, world, scene, settings, start, weights)

    monkeypatch.setattr(ToyEngine, "_prepare", prepare)
    out = tmp_path / "reports"
    arguments = ["suite", "--tags", "dumbbell", "--engines", "toy", "--out", str(out),
                 "--cache-dir", str(tmp_path / "cache")]
    code = main(arguments)
    err = capsys.readouterr().err
    assert code == 4, err[-3000:]
    assert f"ENGINE ERROR: survey: 2 engine runs raised (listed in {out / 'survey'}" in err
    summary = (out / "survey" / "summary.md").read_text(encoding="utf-8")
    assert f"| toy accurate | {FAMILY} | 4 | RuntimeError: {MESSAGE} |" in summary
    assert suite.SURVEY_SAMPLES > 4
    # a warm rerun keeps the survey, and says so again
    code = main(arguments)
    again = capsys.readouterr().err
    assert code == 4, again[-2000:]
    assert "ENGINE ERROR: survey: 2 engine runs raised" in again


def test_a_long_line_opening_with_a_full_stop_keeps_its_text():
    # The first ". " is the line's opening: cut there, the reason would read "ValueError: ."
    # and say nothing of the error.
    from harness.survey.engines import error_text

    message = ". " + "z" * 200 + ". advice"
    assert error_text(ValueError(message)) == f"ValueError: {message}"
