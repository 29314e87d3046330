"""``impact-harness experiments``: carries on without the data, refuses a bad copy."""

from __future__ import annotations

from harness import cli
from harness.experiments import registry


def test_without_the_data_it_says_where_to_get_them_and_carries_on(monkeypatch, capsys):
    monkeypatch.delenv(registry.FAZELI_2017.env_var, raising=False)
    assert cli.main(["experiments"]) == 0
    out = capsys.readouterr().out
    assert "Fazeli et al. 2017: skipped" in out and "planar-impact-dataset" in out
    assert "## Kharaz, Gorham & Salman 2001" in out
    assert "recalled from the paper's figures" in out  # the points' status is printed


def test_a_copy_that_is_not_the_published_files_is_bad_input(synthetic_copy, capsys):
    directory, _ = synthetic_copy
    assert cli.main(["experiments", "--data", str(directory)]) == 2
    error = capsys.readouterr().err.strip().splitlines()
    assert len(error) == 1 and "is not the published file's" in error[0]


def test_a_data_path_that_is_no_directory_is_bad_input(tmp_path, capsys):
    assert cli.main(["experiments", "--data", str(tmp_path / "absent")]) == 2
    assert "not a directory" in capsys.readouterr().err


def test_bad_options_are_refused_before_any_work(capsys):
    assert cli.main(["experiments", "--replicates", "3"]) == 2
    assert "--replicates 3" in capsys.readouterr().err
