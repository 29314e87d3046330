"""``impact-harness validate`` on population files as well as scenario files."""

from __future__ import annotations

from pathlib import Path

from harness.cli import main

ROOT = Path(__file__).resolve().parents[1]


def test_population_files_and_directories_are_checked_as_populations(capsys):
    code = main(["validate", str(ROOT / "populations"), str(ROOT / "populations" /
                                                            "box-corner.toml"),
                 str(ROOT / "scenarios" / "disk-oblique.toml"), "--no-solve"])
    out = capsys.readouterr().out
    assert code == 0
    count = len(list((ROOT / "populations").glob("*.toml")))
    assert f"{count} of {count} population files OK" in out  # each file once
    assert "1 of 1 scenario files OK" in out


def test_a_bad_population_file_is_one_line_per_problem(tmp_path, capsys):
    path = tmp_path / "mine.toml"
    path.write_text('name = "mine"\nrestitution = 0.5\nfriction = 2.0\n[ground]\n'
                    '[approach]\nspeed = { uniform = [1.0, 0.5] }\ndirection_deg = 0\n'
                    '[[body]]\nname = "hex"\nshape = "polygon"\nsides = 6\nradius = 0.1\n'
                    'mass = 1.0\nangle_deg = 10.0\nangular_velocity = 0.0\n')
    assert main(["validate", str(path)]) == 2
    out = capsys.readouterr().out
    errors = [line for line in out.splitlines() if line.startswith("ERROR")]
    assert errors and all(str(path) in line for line in errors)
    assert any("approach.speed" in line for line in errors)
    assert "0 of 1 population files OK, 1 with errors" in out
    assert "scenario files" not in out  # no scenario named: the library is not checked
