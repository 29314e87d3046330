"""One table of bounds for every knob, however it is set (issue 23 item 5): a scenario
file's ``[engine_settings]``, ``--set``, the Python API, the command-line options and a
population file all refuse the same values, with one line naming where the value came
from, the key, the value and the allowed range (exit 2, before any work)."""

from __future__ import annotations

import pytest

from harness import bounds, cli
from harness.engines import ENGINE_NAMES, EngineNotInstalled, load_engine
from harness.engines.settings import EngineSettingsError
from harness.scenarios import SCENARIO_DIR

DISK = SCENARIO_DIR / "disk-direct.toml"
POLYGONS = SCENARIO_DIR.parent / "populations" / "polygon-corner.toml"

#: (setting, a value outside its bounds): the issue's reproducers.
OUT_OF_BOUNDS_SETTINGS = [("time_step", 1e-8), ("max_steps", 10_000_000),
                          ("iterations", 1_000_000_000), ("approach_steps", 1e12)]


def test_every_preset_of_every_engine_is_within_the_bounds():
    for name in ENGINE_NAMES:
        try:
            engine = load_engine(name)
        except EngineNotInstalled:
            continue
        for preset in engine.presets:
            for key, value in engine.settings(preset).items():
                assert bounds.problem(key, value) is None, (name, preset, key, value)


def no_work(monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("work started before the bounds were checked")

    from harness.run import runner

    monkeypatch.setattr(runner, "run", refuse)


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return err


@pytest.mark.parametrize("key,value", OUT_OF_BOUNDS_SETTINGS)
def test_set_refuses_what_a_file_refuses(tmp_path, monkeypatch, capsys, key, value):
    no_work(monkeypatch)
    status = cli.main(["run", str(DISK), "--engines", "pymunk", "--no-cache",
                       "--json", str(tmp_path / "r.json"), "--set", f"pymunk.{key}={value!r}"])
    err = one_line(capsys)
    assert status == 2
    allowed = bounds.BOUNDS[key].allowed()
    assert f"--set pymunk.{key}" in err and f"key {key!r}" in err and allowed in err

    scenario = tmp_path / "scenario.toml"
    scenario.write_text(DISK.read_text(encoding="utf-8")
                        + f"\n[engine_settings.pymunk]\n{key} = {value!r}\n", encoding="utf-8")
    assert cli.main(["validate", str(scenario)]) == 2
    said = capsys.readouterr()
    said = said.out + said.err
    assert f"scenario.toml: engine_settings.pymunk.{key} = " in said and allowed in said

    with pytest.raises(EngineSettingsError, match=f"setting '{key}' = .*out of range"):
        load_engine("pymunk").settings("defaults", {key: value})


def exit_status(argv: list[str]) -> int:
    """``impact-harness ARGV``'s exit status, an option refused by argparse included."""
    try:
        return cli.main(argv)
    except SystemExit as stop:
        return stop.code


@pytest.mark.parametrize("option,value", [("--samples", "1000000000"), ("--samples", "0"),
                                          ("--workers", "0"), ("--workers", "100000"),
                                          ("--seed", "-1"), ("--seed", "99999999999")])
def test_survey_options_out_of_bounds_are_one_line_exit_2(tmp_path, capsys, option, value):
    status = exit_status(["survey", "disk-disk", option, value, "--out", str(tmp_path / "s")])
    err = one_line(capsys)
    assert status == 2
    knob = option.lstrip("-")
    assert f"argument {option}: '{value}' is out of range" in err
    assert bounds.BOUNDS[knob].allowed() in err
    assert not (tmp_path / "s").exists()


@pytest.mark.parametrize("option,value", [("--workers", "100000"), ("--chunk-size", "0"),
                                          ("--task-time-limit", "0"),
                                          ("--task-time-limit", "1e9")])
def test_run_options_out_of_bounds_are_one_line_exit_2(tmp_path, monkeypatch, capsys, option,
                                                       value):
    no_work(monkeypatch)
    status = exit_status(["run", str(DISK), option, value, "--json", str(tmp_path / "r.json")])
    err = one_line(capsys)
    assert status == 2 and option in err


def test_a_population_with_a_million_sides_is_refused(tmp_path, capsys):
    population = tmp_path / "many-sides.toml"
    population.write_text(POLYGONS.read_text(encoding="utf-8").replace(
        "sides = { choice = [3, 5, 6, 8] }", "sides = 1000000"), encoding="utf-8")
    status = cli.main(["survey", str(population), "--samples", "5", "--out",
                       str(tmp_path / "s")])
    err = one_line(capsys)
    assert status == 2
    assert "many-sides.toml: body.polygon.sides = 1000000" in err and "64" in err


def test_a_bound_raised_through_the_environment_is_read_where_it_is_checked(monkeypatch):
    assert bounds.problem("iterations", 20_000) is not None
    monkeypatch.setenv("IMPACT_HARNESS_MAX_SOLVER_ITERATIONS", "1e5")
    assert bounds.problem("iterations", 20_000) is None
    assert bounds.problem("iterations", 2.5) is not None  # still an integer


# Issue 37, item 10: the settings the first table left unbounded, and a population's values
#: (--set ENGINE.KEY=VALUE, the reproducer of issue 37, item 10).
UNBOUNDED_BEFORE = ["box2d.length_scale=1e300", "pybullet.num_sub_steps=1e9",
                    "mujoco.margin=1e300", "mujoco.solref=[0,0]",
                    "mujoco.solimp=[2,2,2,2,2]", "pymunk.damping=5",
                    "pybullet.contact_erp=-1", "mujoco.impratio=0"]


def test_every_numeric_setting_of_every_engine_has_a_bound():
    """A number (or a list of numbers) an engine takes is in the table; only flags and
    choices of names are not (their own checks list what is allowed)."""
    for name in ENGINE_NAMES:
        try:
            engine = load_engine(name)
        except EngineNotInstalled:
            continue
        for preset in engine.presets:
            for key, value in engine.settings(preset).items():
                numeric = (isinstance(value, (int, float)) and not isinstance(value, bool)) \
                    or (isinstance(value, list) and all(
                        isinstance(v, (int, float)) for v in value))
                if numeric:
                    assert key in bounds.BOUNDS, (name, key, value)


@pytest.mark.parametrize("assignment", UNBOUNDED_BEFORE)
def test_a_setting_without_a_bound_before_is_refused(tmp_path, monkeypatch, capsys,
                                                    assignment):
    no_work(monkeypatch)
    engine = assignment.split(".")[0]
    status = exit_status(["run", str(DISK), "--engines", engine, "--no-cache", "--set",
                          assignment, "--json", str(tmp_path / "r.json")])
    err = one_line(capsys)
    assert status == 2 and "out of range; allowed:" in err and assignment.split("=")[0] in err


POPULATION_VALUES = [  # (text replaced, by what): each a value a scenario file refuses
    ("speed = { log_uniform = [0.3, 3.0] }", "speed = 1e6"),
    ("radius = { uniform = [0.05, 0.3] }", "radius = 1e-6"),
    ("mass_ratio = { log_uniform = [0.1, 10.0] }", "mass_ratio = 1e10"),
    ("mass_ratio = { log_uniform = [0.1, 10.0] }", "mass_ratio = { choice = [1e-10, 1] }"),
    ("mass_ratio = { log_uniform = [0.1, 10.0] }",
     "mass_ratio = { log_uniform = [0.1, 10.0] }\nmax_attempts = 1e12"),
    ("mass_ratio = { log_uniform = [0.1, 10.0] }",
     "mass_ratio = { log_uniform = [0.1, 10.0] }\nmax_attempts = 2.5"),
]


@pytest.mark.parametrize("old,new", POPULATION_VALUES)
def test_a_population_takes_only_what_a_scenario_file_takes(tmp_path, capsys, old, new):
    text = (SCENARIO_DIR.parent / "populations" / "disk-disk.toml").read_text(encoding="utf-8")
    assert old in text
    population = tmp_path / "hostile.toml"
    population.write_text(text.replace(old, new, 1), encoding="utf-8")
    assert cli.main(["validate", str(population)]) == 2
    said = capsys.readouterr()
    said = said.out + said.err
    assert "allowed" in said and new.split("\n")[-1].split(" ")[0] in said
