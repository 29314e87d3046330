"""``impact-harness validate`` and ``impact-harness new`` through the real dispatcher."""

from __future__ import annotations

import pytest

from harness.cli import main
from harness.scenarios import SCENARIO_DIR, load_scenario

GOOD = SCENARIO_DIR / "disk-oblique.toml"


def run(capsys, *argv):
    code = main(list(map(str, argv)))
    out, err = capsys.readouterr()
    return code, out, err


def test_validate_good_files(capsys):
    code, out, _ = run(capsys, "validate", GOOD, SCENARIO_DIR / "two-sled-row2.toml")
    assert code == 0
    assert out.count("OK    ") == 2 and "2 of 2 scenario files OK" in out


def test_validate_the_whole_library(capsys):
    code, out, _ = run(capsys, "validate", "--quiet")
    assert code == 0 and out == ""


def test_validate_a_bad_file(capsys, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(GOOD.read_text().replace("mass = 1.0", "mass = -3.0"))
    code, out, _ = run(capsys, "validate", GOOD, bad)
    assert code == 2  # bad input
    assert "ERROR" in out and "bad.toml" in out and "body.disk.mass = -3.0" in out
    assert "allowed: > 0" in out
    assert "1 of 2 scenario files OK, 1 with errors" in out


def test_validate_reports_a_wrong_expectation(capsys, tmp_path):
    wrong = tmp_path / "wrong.toml"
    wrong.write_text(GOOD.read_text().replace("poisson = 2", "poisson = 5"))
    code, out, _ = run(capsys, "validate", wrong)
    assert code == 2
    assert "wrong.toml: expect.collision_type.poisson = 5, but the solver gives 2" in out
    code, out, _ = run(capsys, "validate", "--no-solve", wrong)
    assert code == 0


def test_validate_duplicate_names(capsys, tmp_path):
    copy = tmp_path / "copy.toml"
    copy.write_text(GOOD.read_text())
    code, out, _ = run(capsys, "validate", GOOD, copy)
    assert code == 2 and "copy.toml: name = 'disk-oblique': the name is already used" in out


def test_validate_an_empty_directory(capsys, tmp_path):
    code, _, err = run(capsys, "validate", tmp_path)
    assert code == 2 and "no scenario files" in err


@pytest.mark.parametrize("shape, kind", [
    (shape, kind) for shape in ("disk", "rod", "box", "polygon", "ellipse")
    for kind in ("--ground", "--two-body", None)
    if not (shape == "ellipse" and kind == "--two-body")])  # refused: the test below
def test_new_writes_a_file_that_validates(capsys, tmp_path, shape, kind):
    name = f"my-{shape}"
    argv = ["new", name, "--shape", shape, "--out", tmp_path] + ([kind] if kind else [])
    code, out, _ = run(capsys, *argv)
    path = tmp_path / f"{name}.toml"
    assert code == 0 and str(path) in out
    scenario = load_scenario(path)
    assert scenario.name == name
    assert scenario.ground == (kind != "--two-body")
    assert scenario.bodies[0].shape.kind == shape
    assert "#" in path.read_text()  # commented
    code, out, _ = run(capsys, "validate", path)
    assert code == 0, out


def test_new_template_sweep_validates_when_uncommented(capsys, tmp_path):
    run(capsys, "new", "swept", "--shape", "rod", "--out", tmp_path)
    path = tmp_path / "swept.toml"
    text = path.read_text()
    for line in ("[sweep]", "parameter", "values"):
        text = text.replace(f"# {line}", line, 1)
    path.write_text(text)
    scenario = load_scenario(path)
    assert scenario.sweep.parameter == "body.rod.angle_deg" and len(scenario.points()) == 3


def test_new_refuses_to_overwrite_and_bad_names(capsys, tmp_path):
    assert run(capsys, "new", "x", "--out", tmp_path)[0] == 0
    code, _, err = run(capsys, "new", "x", "--out", tmp_path)
    assert code == 1 and "exists" in err
    assert run(capsys, "new", "x", "--out", tmp_path, "--force")[0] == 0
    code, _, err = run(capsys, "new", "bad name", "--out", tmp_path)
    assert code == 2 and "'bad name'" in err and "allowed" in err


def test_new_refuses_a_two_body_ellipse(capsys, tmp_path):
    code, _, err = run(capsys, "new", "pair", "--shape", "ellipse", "--two-body", "--out",
                       tmp_path)
    assert code == 2 and "an ellipse touches only the ground" in err
    assert len(err.strip().splitlines()) == 1 and not list(tmp_path.iterdir())
