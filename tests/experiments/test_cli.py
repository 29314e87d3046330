"""``impact-harness experiments``: carries on without the data, refuses a bad copy."""

from __future__ import annotations

import pytest

from harness import cli
from harness.experiments import registry


def test_without_the_data_it_says_where_to_get_them_and_carries_on(monkeypatch, capsys):
    monkeypatch.delenv(registry.FAZELI_2017.env_var, raising=False)
    assert cli.main(["experiments"]) == 0
    out = capsys.readouterr().out
    assert "Fazeli et al. 2017: skipped" in out and "planar-impact-dataset" in out
    assert "## Kharaz, Gorham & Salman 2001" in out
    assert "write_usr0.f" in out  # where the measured points come from is printed


def test_a_copy_that_is_not_the_published_files_is_bad_input(synthetic_copy, capsys):
    directory, _ = synthetic_copy
    assert cli.main(["experiments", "--data", str(directory)]) == 2
    error = capsys.readouterr().err.strip().splitlines()
    assert len(error) == 1 and "is not the published file's" in error[0]


def test_a_data_path_that_is_no_directory_is_bad_input(tmp_path, capsys):
    assert cli.main(["experiments", "--data", str(tmp_path / "absent")]) == 2
    assert "not a directory" in capsys.readouterr().err


def test_bad_options_are_refused_before_any_work(capsys):
    assert exit_status(cli.main, ["experiments", "--replicates", "3"]) == 2
    assert "--replicates: '3' is out of range" in capsys.readouterr().err


def test_the_json_holds_aggregates_only(synthetic_copy, tmp_path, monkeypatch, capsys):
    """The Fazeli data carry no licence: nothing per drop may leave the command. The
    synthetic copy stands in for the real files (their hashes differ, so the check is
    skipped here only)."""
    import json

    from harness.experiments import cli as experiments_cli
    from harness.experiments import fazeli

    directory, truth = synthetic_copy
    real_load = fazeli.load
    monkeypatch.setattr(fazeli, "load", lambda path: real_load(path, check_hashes=False))
    loaded = []  # each engine is loaded once for both of its tables
    real_engine = experiments_cli.load_engine  # the name the command calls
    monkeypatch.setattr(experiments_cli, "load_engine",
                        lambda name: loaded.append(name) or real_engine(name))
    out = tmp_path / "experiments.json"
    assert cli.main(["experiments", "--data", str(directory), "--replicates", "10",
                     "--workers", "1", "--objective", "impulse", "--engines", "pymunk",
                     "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "### Every law fitted: objective impulse" in printed
    assert "### The engines on the drops" in printed and "| pymunk | accurate | " in printed
    assert "### The Kharaz curves through the engines" in printed and loaded == ["pymunk"]
    document = json.loads(out.read_text())
    assert document["objective"] == "impulse"
    section = document["fazeli2017"]
    assert set(section["laws"]) == {"newton", "poisson", "stronge", "stronge-paper",
                                    "newton-lcp"}

    def longest_list(value) -> int:
        if isinstance(value, dict):
            return max((longest_list(v) for v in value.values()), default=0)
        if isinstance(value, list):
            return max([len(value)] + [longest_list(v) for v in value])
        return 0

    assert longest_list(section) < truth["drops"] / 10


@pytest.mark.parametrize("option, value", [("--replicates", "1000000000000"),
                                           ("--replicates", "3"), ("--seed", "-1"),
                                           ("--workers", "0")])
def test_every_count_is_bounded_before_any_work(option, value, monkeypatch, capsys):
    """``--replicates 10^12`` was accepted and would have run for ever; the bound is in
    harness/bounds.py's table, one line names the option, the value and what is allowed."""
    from harness.experiments import cli as experiments_cli

    monkeypatch.setattr(experiments_cli, "run_engines", _no_work)
    assert exit_status(cli.main, ["experiments", option, value]) == 2
    # argparse's usage line, then one line naming the option, the value and what is allowed
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert f"{option}: '{value}' is out of range; allowed: an integer" in line


def _no_work(*args, **kwargs):
    raise AssertionError("work started before the options were checked")


def test_json_through_a_link_is_refused_and_its_target_kept(tmp_path, monkeypatch, capsys):
    from harness.experiments import cli as experiments_cli

    monkeypatch.setattr(experiments_cli, "run_engines", _no_work)
    target = tmp_path / "precious.txt"
    target.write_text("keep me")
    link = tmp_path / "out.json"
    link.symlink_to(target)
    assert cli.main(["experiments", "--json", str(link)]) == 2
    assert "symbolic link" in capsys.readouterr().err
    assert target.read_text() == "keep me" and link.is_symlink()


@pytest.mark.parametrize("where", ["missing", "read-only"])
def test_json_into_a_directory_it_cannot_write_is_refused_first(where, tmp_path, monkeypatch,
                                                                 capsys):
    import os

    from harness.experiments import cli as experiments_cli

    monkeypatch.setattr(experiments_cli, "run_engines", _no_work)
    directory = tmp_path / "out"
    if where == "read-only":
        directory.mkdir()
        directory.chmod(0o500)
        if os.access(directory, os.W_OK):  # root writes anyway
            pytest.skip("running as a user who writes into read-only directories")
    assert cli.main(["experiments", "--json", str(directory / "x.json")]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert f"--json {directory / 'x.json'}: its directory" in line


def test_json_is_written_atomically_over_a_regular_file(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv(registry.FAZELI_2017.env_var, raising=False)
    out = tmp_path / "out.json"
    out.write_text("old")
    assert cli.main(["experiments", "--engines", "none", "--json", str(out)]) == 0
    assert out.read_text().startswith("{") and not list(tmp_path.glob("*.tmp"))


def test_a_rerun_reads_the_cache_and_prints_the_same(synthetic_copy, monkeypatch, capsys,
                                                     tmp_path, own_cache):
    """The second run with nothing changed computes nothing (the work is replaced by a
    failure) and prints and writes what the first did; another setting computes again;
    progress goes to stderr, never into the printed results."""
    from harness.experiments import analysis, fazeli

    directory, _ = synthetic_copy
    real_load = fazeli.load
    monkeypatch.setattr(fazeli, "load", lambda path: real_load(path, check_hashes=False))
    first_json, second_json = tmp_path / "1.json", tmp_path / "2.json"
    command = ["experiments", "--data", str(directory), "--replicates", "10", "--workers",
               "1", "--engines", "none"]
    assert cli.main([*command, "--json", str(first_json)]) == 0
    first = capsys.readouterr()
    assert "impact-harness experiments: fitting every law" in first.err
    assert "impact-harness experiments" not in first.out

    def no_fit(*args, **kwargs):
        raise AssertionError("computed again")

    monkeypatch.setattr(analysis, "fit_laws", no_fit)
    assert cli.main([*command, "--json", str(second_json)]) == 0
    second = capsys.readouterr()
    assert second.out == first.out and "read from the cache" in second.err
    assert second_json.read_text() == first_json.read_text()
    for changed in (["--seed", "1"], ["--no-cache"]):
        assert cli.main([*command, *changed]) != 0  # the cli reports the failure
        assert "computed again" in capsys.readouterr().err
    # an entry edited after it was written is a miss (its SHA-256 differs): computed again
    (entry,) = own_cache.rglob("*.json")
    entry.write_text(entry.read_text().replace("poisson", "poissin"))
    assert cli.main(command) != 0 and "computed again" in capsys.readouterr().err


def test_the_command_and_the_report_lead_with_one_headline_fit():
    """The command's defaults are the report's headline: Poisson fitted by the same
    objective to the same frame of post-impact speeds (aggregates.SHOWN_*,
    frames.DEFAULT_FRAME), so the engines run at the same (μ, e) in both."""
    from harness.experiments import aggregates, frames
    from harness.experiments import cli as experiments_cli

    options = experiments_cli.default_options()
    assert options.objective == aggregates.SHOWN_OBJECTIVE
    assert options.post_speeds == frames.DEFAULT_FRAME == "published"
    assert aggregates.SHOWN_LAW == frames.LAW == "poisson"


def test_a_cached_run_writes_this_copys_place_in_the_json(synthetic_copy, tmp_path,
                                                          monkeypatch, capsys):
    """The cache is keyed by the files' SHA-256, not their place: a copy moved elsewhere
    reads the same entry, and the --json provenance names where the copy is now."""
    import json
    import shutil

    from harness.experiments import fazeli

    directory, _ = synthetic_copy
    moved = tmp_path / "moved"
    shutil.copytree(directory, moved)
    real_load = fazeli.load
    monkeypatch.setattr(fazeli, "load", lambda path: real_load(path, check_hashes=False))
    command = ["experiments", "--replicates", "10", "--workers", "1", "--engines", "none"]
    assert cli.main([*command, "--data", str(directory)]) == 0
    out = tmp_path / "moved.json"
    assert cli.main([*command, "--data", str(moved), "--json", str(out)]) == 0
    assert "read from the cache" in capsys.readouterr().err
    assert json.loads(out.read_text())["fazeli2017"]["provenance"]["directory"] == str(moved)


def exit_status(main, argv):
    """The status a command line ends with: what ``main`` returns, or the status argparse
    exits with when an option's type (harness.bounds.option) refuses its value."""
    try:
        return main(argv)
    except SystemExit as stop:
        return stop.code
