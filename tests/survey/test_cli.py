"""``impact-harness survey`` end to end on a few samples: the files, their columns, one-call
reads, and the laws' departures against the solver's own types."""

from __future__ import annotations

import re

import numpy as np
import pyarrow.parquet as pq
import pytest

from harness.cli import main
from harness.survey.population import resolve_populations

SAMPLES = 3


@pytest.fixture(scope="module")
def survey_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("survey")
    code = main(["survey", "--samples", str(SAMPLES), "--seed", "5", "--engines", "pymunk",
                 "--preset", "accurate", "--out", str(out), "--no-figures"])
    assert code == 0
    return out


def test_tables_are_written_and_read_in_one_call(survey_dir):
    families = {p.name for p in resolve_populations()}
    samples = pq.read_table(survey_dir / "samples.parquet").to_pydict()
    runs = pq.read_table(survey_dir / "runs.parquet").to_pydict()
    stats = pq.read_table(survey_dir / "statistics.parquet").to_pydict()
    assert len(samples["family"]) == SAMPLES * len(families)
    assert set(samples["family"]) == families
    assert len(runs["family"]) == SAMPLES * len(families)  # one engine, one preset
    assert set(runs["engine"]) == {"pymunk"} and set(runs["preset"]) == {"accurate"}
    # An "all types" row per family, and its n is every run of the family.
    every = [i for i, kind in enumerate(stats["poisson_type"]) if kind == 0]
    assert sorted(stats["family"][i] for i in every) == sorted(families)
    assert all(stats["n"][i] == SAMPLES for i in every)


def test_poisson_departs_from_itself_by_zero_and_newton_lcp_by_the_law_part(survey_dir):
    samples = pq.read_table(survey_dir / "samples.parquet").to_pydict()
    runs = pq.read_table(survey_dir / "runs.parquet").to_pydict()
    assert np.all(np.asarray(samples["poisson.from_poisson"]) == 0.0)
    # The runs' law part is the samples' newton-lcp departure (same rows, same order).
    assert np.array_equal(np.asarray(runs["law_part"]),
                          np.asarray(samples["newton-lcp.from_poisson"]))
    assert set(samples["poisson.collision_type"]) <= {1, 2, 3, 4, 5}


def test_summary_lists_every_family_and_the_timings(survey_dir):
    text = (survey_dir / "summary.md").read_text()
    for population in resolve_populations():
        assert f"| pymunk | accurate | {population.name} | all types |" in text
    assert "## Rejected draws" in text and "| engine pymunk accurate |" in text


def test_the_summarys_p90_note_names_this_surveys_run_counts(survey_dir):
    from harness.survey.outputs import p90_runs

    text = (survey_dir / "summary.md").read_text()
    stats = pq.read_table(survey_dir / "statistics.parquet").to_pydict()
    most = max(n for n, kind in zip(stats["n"], stats["poisson_type"]) if kind == 0)
    intro = text.split("## Every")[0]
    assert most == SAMPLES and f"{most} runs" in intro and p90_runs(most) in intro
    assert "with 20 runs" not in text


def test_bad_engine_name_is_bad_input_exit_2_in_one_line(capsys):
    assert main(["survey", "--engines", "pymunck", "--samples", "1"]) == 2
    err = capsys.readouterr().err
    assert "unknown ['pymunck']" in err and err.count("\n") == 1


def test_unknown_population_exits_2(capsys, tmp_path):
    assert main(["survey", "no-such-family", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "POPULATION 'no-such-family': no population file" in err and "<scenario>" not in err


def test_figures_are_written(tmp_path):
    code = main(["survey", "spinning-disk", "--samples", "4", "--engines", "pymunk",
                 "--out", str(tmp_path)])
    assert code == 0
    names = {path.name for path in (tmp_path / "figures").iterdir()}
    assert {"map-pymunk.png", "map-pymunk.svg", "cdf-pymunk.png", "cdf-pymunk.svg"} <= names


def test_default_survey_leaves_mujoco_matched_bounce_out_and_says_so(tmp_path):
    pytest.importorskip("mujoco")
    # no --preset: MuJoCo at defaults only, and the summary names what was not run
    assert main(["survey", "spinning-disk", "--samples", "1", "--engines", "mujoco",
                 "--out", str(tmp_path / "default"), "--no-figures"]) == 0
    runs = pq.read_table(tmp_path / "default" / "runs.parquet").to_pydict()
    assert set(runs["preset"]) == {"defaults"}
    summary = (tmp_path / "default" / "summary.md").read_text()
    assert "Not run: mujoco.matched-bounce" in summary
    # the option the summary gives runs it: its own name, not the presets that already ran
    advised = re.search(r"Not run: mujoco\.matched-bounce \([^)]*`--preset ([^`]+)`",
                        summary).group(1)
    assert "matched-bounce" in advised.split(",")
    assert main(["survey", "spinning-disk", "--samples", "1", "--engines", "mujoco",
                 "--preset", advised, "--out", str(tmp_path / "both"),
                 "--no-figures"]) == 0
    runs = pq.read_table(tmp_path / "both" / "runs.parquet").to_pydict()
    assert set(runs["preset"]) == {"defaults", "accurate"}
    assert "Not run" not in (tmp_path / "both" / "summary.md").read_text()


def test_tables_describe_themselves_and_keep_the_users_names(survey_dir):
    import json

    from harness.survey.outputs import METADATA_KEY

    for name in ("samples", "runs", "statistics"):
        schema = pq.read_schema(survey_dir / f"{name}.parquet")
        about = json.loads(schema.metadata[METADATA_KEY.encode()])
        assert about["table"] == name and about["settings"]["seed"] == 5
        assert about["settings"]["samples"] == SAMPLES and "numpy" in about["versions"]
        assert about["engine_settings"]["pymunk"]["accurate"]["iterations"] == 100
    runs = pq.read_schema(survey_dir / "runs.parquet")
    assert runs.field("departure_poisson").metadata == {b"unit": b"fraction"}
    assert runs.field("reasons").type.value_type == "string"
    reasons = pq.read_table(survey_dir / "runs.parquet").column("reasons").to_pylist()
    assert all(isinstance(names, list) and "," not in "".join(names) for names in reasons)
    # drawn parameters under the bodies' own names, as the population files write them
    samples = pq.read_schema(survey_dir / "samples.parquet")
    assert "rod.length" in samples.names and "slab.width" in samples.names
    assert "polygon.sides" in samples.names and "box.height" in samples.names
    bodies = {body.name for population in resolve_populations() for body in population.bodies}
    drawn = {column.split(".")[0] for column in samples.names if column.endswith(".mass")}
    assert drawn == bodies
    assert samples.field("rod.length").metadata == {b"unit": b"m"}


def test_set_changes_a_setting_of_every_preset_and_is_recorded(tmp_path):
    import json

    from harness.survey.outputs import METADATA_KEY

    out = tmp_path / "survey"
    code = main(["survey", "spinning-disk", "--samples", "2", "--engines", "pymunk",
                 "--preset", "accurate", "--set", "pymunk.iterations=3", "--out", str(out),
                 "--no-figures", "--workers", "1"])
    assert code == 0
    about = json.loads(pq.read_schema(out / "runs.parquet").metadata[METADATA_KEY.encode()])
    assert about["settings"]["overrides"] == {"pymunk": {"iterations": 3}}
    assert about["engine_settings"]["pymunk"]["accurate"]["iterations"] == 3
    assert "by --set: iterations=3" in (out / "summary.md").read_text(encoding="utf-8")
    assert main(["survey", "--samples", "2", "--engines", "pymunk", "--set",
                 "pymunk.iterations=-1", "--out", str(out)]) == 2
    assert main(["survey", "--samples", "2", "--engines", "pymunk", "--set",
                 "mujoco.iterations=3", "--out", str(out)]) == 2  # engine not selected


def test_without_out_another_survey_is_not_replaced(tmp_path, monkeypatch, capsys):
    import json

    monkeypatch.chdir(tmp_path)
    existing = tmp_path / "reports" / "survey"
    existing.mkdir(parents=True)
    settings = {"samples": 20, "seed": 0, "engines": ["pymunk"], "presets": ["accurate"],
                "families": ["spinning-disk"], "skipped": {}}
    (existing / "settings.json").write_text(json.dumps(settings))
    argv = ["survey", "spinning-disk", "--samples", "2", "--engines", "pymunk", "--preset",
            "accurate", "--no-figures", "--workers", "1"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "reports/survey holds a survey of samples 20 (asked: 2)" in err and "--force" in err
    assert sorted(p.name for p in existing.iterdir()) == ["settings.json"]  # untouched
    assert main(argv + ["--force"]) == 0
    # the same survey again replaces it without --force
    assert main(argv) == 0


def _timings_rows(summary: str) -> dict[str, list[str]]:
    """The Timings table of a summary: ``{stage: [seconds, per impact, per engine run]}``."""
    table = summary.split("## Timings", 1)[1]
    rows = [line.strip("|").split(" | ") for line in table.splitlines()
            if line.startswith("| ") and not line.startswith("| stage")]
    return {cells[0].strip(): [cell.strip() for cell in cells[1:]] for cells in rows}


def test_timings_divide_every_row_by_the_impacts_and_say_so():
    from harness.survey.cli import run_survey
    from harness.survey.outputs import summary_markdown

    populations = resolve_populations(["spinning-disk"])
    samples = 2
    survey = run_survey(populations, samples, 0, ["pymunk"], ["defaults", "accurate"],
                        workers=1, echo=lambda _: None)
    settings = {"samples": samples, "seed": 0, "engines": ["pymunk"],
                "presets": ["defaults", "accurate"]}
    summary = summary_markdown(survey["statistics"], survey["rejections"], survey["timings"],
                               settings)
    rows = _timings_rows(summary)
    impacts = samples * len(populations)
    assert set(rows) == set(survey["timings"])
    for stage, (seconds, runs) in survey["timings"].items():
        # one divisor for the whole column: the impacts, on the rows over both pairs too
        assert rows[stage][1] == f"{seconds / impacts * 1e6:.1f}", stage
        assert rows[stage][2] == ("" if not runs else f"{seconds / runs * 1e6:.1f}"), stage
    both_pairs = survey["timings"]["parts (wall: sampling, laws, engines, verdicts)"][1]
    assert both_pairs == impacts * 2
    assert survey["timings"]["engine pymunk accurate"][1] == impacts
    assert f"÷ the {impacts:,} impacts" in summary and f"{impacts:,} × 2 pairs" in summary


def test_the_suite_survey_command_computes_the_suites_survey(tmp_path):
    """The command ``survey --quick``'s help gives for ``make validate``'s survey computes
    the same tables as ``impact-harness suite``'s own survey (every engine installed here)."""
    import argparse
    import shlex

    from harness import suite
    from harness.survey.cli import suite_survey_command

    suite.quick_survey(argparse.Namespace(engines=None, preset=None), tmp_path / "suite")
    command = shlex.split(suite_survey_command(str(tmp_path / "command")))
    assert command[:2] == ["impact-harness", "survey"]
    assert main(command[1:]) == 0
    for table in ("samples", "runs", "statistics"):
        ours = pq.read_table(tmp_path / "command" / f"{table}.parquet")
        theirs = pq.read_table(tmp_path / "suite" / f"{table}.parquet")
        assert ours.column_names == theirs.column_names, table
        assert ours.num_rows == theirs.num_rows, table
        for name in ours.column_names:
            pairs = zip(ours[name].to_pylist(), theirs[name].to_pylist())
            assert all(a == b or (a != a and b != b) for a, b in pairs), f"{table}.{name}"
    assert not (tmp_path / "command" / "figures").exists()


def test_quick_help_says_what_it_runs_and_how_to_get_the_suites_survey(capsys):
    from harness import suite
    from harness.survey.cli import QUICK_SAMPLES, suite_survey_command

    with pytest.raises(SystemExit):
        main(["survey", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    quick = help_text.split("--quick", 2)[2]
    assert f"{QUICK_SAMPLES} samples per population" in quick
    assert f"({suite.SURVEY_SAMPLES} samples, no pair left out, no figures)" in quick
    assert suite_survey_command() in quick
